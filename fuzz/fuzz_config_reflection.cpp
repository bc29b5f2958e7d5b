// The config reflection (every stage's visit(), core/params.hpp; issue 22): the input assigns
// extreme or arbitrary finite values to the parameters of SemapConfig and SynthConfig through a
// visitor. validate() may refuse them only with semap::Error and a compact message (never a
// number of 20+ digits, such as DBL_MAX written out); whatever it accepts must survive the YAML
// dump -> load -> dump round trip unchanged and validate again. (NaN/Inf never reach a config:
// the loader refuses them, fuzz_config_yaml covers that path.)
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <regex>

#include "semap/core/error.hpp"
#include "fuzz/fuzz_util.hpp"
#include "semap/io/config_loader.hpp"
#include "semap/pipeline/semap_config.hpp"
#include "synth/synth_config.hpp"

namespace {

class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  uint8_t byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  template <class T>
  T raw() {
    T value{};
    uint8_t buffer[sizeof(T)] = {};
    for (auto& b : buffer) b = byte();
    std::memcpy(&value, buffer, sizeof(T));
    return value;
  }

 private:
  const uint8_t* data_;
  size_t size_, pos_ = 0;
};

/// Sets every parameter it visits from the input: kept, an extreme, or raw bytes.
class Assigner : public semap::ParamVisitor {
 public:
  explicit Assigner(Bytes& in) : in_(in) {}
  void param(std::string_view, bool& v, std::string_view, std::string_view) override {
    if (const uint8_t b = in_.byte(); b & 1) v = b & 2;
  }
  void param(std::string_view, int& v, std::string_view, std::string_view, semap::ParamRange<int>) override {
    static const int kExtremes[] = {0, -1, 1, 2, INT_MAX, INT_MIN, 65536, 1 << 30, -65536};
    const uint8_t choice = in_.byte() % 4;
    if (choice == 1) v = kExtremes[in_.byte() % std::size(kExtremes)];
    else if (choice == 2) v = in_.raw<int32_t>();
    else if (choice == 3) v = static_cast<int8_t>(in_.byte());
  }
  void param(std::string_view, double& v, std::string_view, std::string_view,
             semap::ParamRange<double>) override {
    static const double kExtremes[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-9, 1e-300, 5e-324, 1e300, DBL_MAX, -DBL_MAX,
                                       1e6, 1e-6, 65535.0, 2147483648.0, 1e12, -1e12};
    const uint8_t choice = in_.byte() % 4;
    if (choice == 1) v = kExtremes[in_.byte() % std::size(kExtremes)];
    else if (choice == 2) {
      const double raw = in_.raw<double>();
      if (std::isfinite(raw)) v = raw;
    } else if (choice == 3) {
      v *= std::ldexp(1.0, static_cast<int8_t>(in_.byte()) / 4);  // scaled default
    }
  }
  void param(std::string_view, std::string& v, std::string_view, std::string_view) override {
    if (in_.byte() % 2 == 0) return;
    v.clear();
    for (uint8_t n = in_.byte() % 24; n > 0; --n) v.push_back(static_cast<char>(0x20 + in_.byte() % 95));
  }
  // A choice keeps its value or takes any of its names (an invalid name comes from strings).
  void choice(std::string_view, std::string& v, std::span<const std::string_view> choices,
              std::string_view) override {
    if (const uint8_t b = in_.byte(); b & 1) v = std::string(choices[(b >> 1) % choices.size()]);
  }
  void section(std::string_view, std::string_view, const std::function<void(ParamVisitor&)>& body) override {
    body(*this);
  }

 private:
  Bytes& in_;
};

bool compact(const std::string& message) {
  static const std::regex kLongNumber("[0-9]{20}");
  return !std::regex_search(message, kLongNumber);
}

template <class Config>
void round_trip(Config& config) {
  const auto tree = [](Config& c) { return [&c](semap::ParamVisitor& v) { c.visit(v); }; };
  try {
    config.validate();
  } catch (const semap::Error& e) {
    if (!compact(e.what())) std::abort();  // a range message printing a number in full
    return;
  }
  const std::string dump = semap::dump_config(tree(config));
  Config again;
  semap::load_config_string(dump, "dump.yaml", tree(again));  // an Error here escapes: a finding
  again.validate();
  if (semap::dump_config(tree(again)) != dump) std::abort();  // the reflection lost a value
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Bytes in(data, size);
  semap::SemapConfig config;
  Assigner assign(in);
  config.visit(assign);
  round_trip(config);
  semap::SynthConfig synth;
  synth.visit(assign);
  round_trip(synth);
  return 0;
}
