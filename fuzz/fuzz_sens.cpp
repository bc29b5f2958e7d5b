// ScanNet .sens recordings (issue 44): open_dataset on a .sens file - header, the camera check
// every reader goes through, the frame table - and every frame decoded (raw or zlib depth,
// raw or JPEG/PNG colour).
#include <array>
#include <string>

#include "semap/core/error.hpp"
#include "semap/io/dataset.hpp"
#include "fuzz/fuzz_util.hpp"

namespace {

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

/// A two-frame 8x8 .sens v4 file: raw colour and raw 16-bit depth (so the fuzzer reaches the
/// frame table and the decoders without a codec in the way).
std::string sens_seed() {
  std::string out;
  put(out, uint32_t{4});
  put(out, uint64_t{4});
  out += "seed";
  const std::array<float, 16> k{8, 0, 4, 0, 0, 8, 4, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const std::array<float, 16> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  for (const auto* m : {&k, &identity, &k, &identity})
    for (float v : *m) put(out, v);
  put(out, int32_t{0});  // raw colour
  put(out, int32_t{0});  // raw depth
  for (uint32_t side : {8u, 8u, 8u, 8u}) put(out, side);
  put(out, 1000.0f);
  put(out, uint64_t{2});
  for (uint64_t n = 0; n < 2; ++n) {
    for (float v : identity) put(out, v);
    put(out, uint64_t{1000 * (n + 1)});
    put(out, uint64_t{1000 * (n + 1)});
    put(out, uint64_t{8 * 8 * 3});
    put(out, uint64_t{8 * 8 * 2});
    out.append(8 * 8 * 3, char(100));
    for (int p = 0; p < 64; ++p) put(out, uint16_t{1500});
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  semap::fuzz::write_seed("seed.sens", sens_seed());
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = semap::fuzz::input_file("input.sens", data, size);
  try {
    const auto reader = semap::open_dataset(path);
    for (size_t i = 0; i < reader->size() && i < 8; ++i) reader->load(i);
  } catch (const semap::Error&) {
  }
  return 0;
}
