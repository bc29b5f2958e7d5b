#pragma once
// Helpers for the io tests: assert that a call throws semap::Error naming a file.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "semap/core/error.hpp"

namespace semap::test {

/// Runs fn; passes when it throws semap::Error whose message contains `must_name`.
template <class F>
::testing::AssertionResult throws_naming(F&& fn, const std::string& must_name) {
  try {
    fn();
  } catch (const semap::Error& e) {
    if (std::string(e.what()).find(must_name) != std::string::npos) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "error '" << e.what() << "' does not name '" << must_name << "'";
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "threw a non-semap exception: " << e.what();
  }
  return ::testing::AssertionFailure() << "did not throw (expected an error naming '" << must_name << "')";
}

inline std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
inline void write_bytes(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

}  // namespace semap::test
