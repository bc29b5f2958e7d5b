#pragma once
// A JSON number checked against [lo, hi] before it is converted: nlohmann's get<int>() or
// get<uint16_t>() of an out-of-range double is undefined behaviour (fuzz_segmentation_json
// found "id": 6.7e114). Throws nlohmann::json exceptions, which the readers turn into a line
// naming the file.
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

namespace semap {

inline double json_number(const nlohmann::json& j, const std::string& key, double lo, double hi, bool integer) {
  if (!j.is_number()) throw nlohmann::json::type_error::create(302, "\"" + key + "\" must be a number", &j);
  const double v = j.get<double>();
  if (!(v >= lo && v <= hi) || (integer && v != std::floor(v)))
    throw nlohmann::json::out_of_range::create(406, "\"" + key + "\" = " + j.dump() + " is not " +
                                                        (integer ? "an integer" : "a number") + " in [" +
                                                        std::to_string(lo) + ", " + std::to_string(hi) + "]", &j);
  return v;
}

}  // namespace semap
