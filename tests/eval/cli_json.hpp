#pragma once
// Runs build/semap with arguments and parses its --json output (shared by the eval CLI tests).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "test_support.hpp"

namespace semap::test {

inline std::string exe() { return "'" + semap_executable().string() + "'"; }

inline nlohmann::json run_json(const std::string& args) {
  const auto r = run_command(exe() + " " + args);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  try {
    return nlohmann::json::parse(r.output);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not one JSON object: " << e.what() << "\n" << r.output;
    return {};
  }
}

}  // namespace semap::test
