#pragma once
// Parameter reflection: every stage's config struct lists its fields once, with unit and
// doc, through `void visit(ParamVisitor& v)`. The one config loader (io/config) walks YAML
// against it (unknown keys and bad values are errors naming the key), and `semap config
// --dump` prints the defaults from the same list. Example:
//
//   struct TsdfConfig {
//     double voxel_size = 0.02;
//     void visit(ParamVisitor& v) { v.param("voxel_size", voxel_size, "m", "voxel edge"); }
//   };
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace semap {

class ParamVisitor {
 public:
  virtual ~ParamVisitor() = default;
  virtual void param(std::string_view key, bool& value, std::string_view unit, std::string_view doc) = 0;
  virtual void param(std::string_view key, int& value, std::string_view unit, std::string_view doc) = 0;
  virtual void param(std::string_view key, double& value, std::string_view unit, std::string_view doc) = 0;
  virtual void param(std::string_view key, std::string& value, std::string_view unit, std::string_view doc) = 0;
  /// A nested section ("tsdf", "tracking.icp", ...).
  virtual void section(std::string_view key, std::string_view doc, const std::function<void(ParamVisitor&)>& body) = 0;

  // Convenience overloads for other arithmetic types (stored as double / int in YAML).
  void param(std::string_view key, float& value, std::string_view unit, std::string_view doc) {
    double d = value;
    param(key, d, unit, doc);
    value = static_cast<float>(d);
  }
  void param(std::string_view key, std::vector<std::string>& value, std::string_view unit, std::string_view doc) {
    std::string joined;
    for (size_t i = 0; i < value.size(); ++i) joined += (i ? "," : "") + value[i];
    param(key, joined, unit, doc);
    value.clear();
    size_t start = 0;
    while (start <= joined.size() && !joined.empty()) {
      const size_t comma = joined.find(',', start);
      value.push_back(joined.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
};

/// Throws semap::Error("config key KEY", reason) when `ok` is false. Use in validate().
void require_param(bool ok, std::string_view key, std::string_view reason);

}  // namespace semap
