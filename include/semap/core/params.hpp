#pragma once
// Parameter reflection: every stage's config struct lists its fields once, with unit, doc and
// valid range, through `void visit(ParamVisitor& v)`. The one config loader (io/config) walks
// YAML against it (unknown keys and bad values are errors naming the key), `semap config
// --dump` prints the defaults from the same list, and validation of the ranges is derived
// from it (check_param_ranges), so a range is never written twice. Example:
//
//   enum class Integrator { grouped, projective };
//   inline constexpr EnumNames<Integrator, 2> kIntegratorNames{{{Integrator::grouped, "grouped"},
//                                                               {Integrator::projective, "projective"}}};
//   struct TsdfConfig {
//     double voxel_size = 0.02;
//     Integrator integrator = Integrator::projective;
//     void visit(ParamVisitor& v) {
//       v.param("voxel_size", voxel_size, "m", "voxel edge", {0.001, 1.0});
//       v.param("integrator", integrator, kIntegratorNames, "integration method");
//     }
//     void validate() const { check_param_ranges(*this, "tsdf"); /* + cross-field rules */ }
//   };
#include <array>
#include <functional>
#include <optional>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace semap {

/// Valid values of a numeric parameter: [min, max], or (min, max] when min_exclusive.
template <class T>
struct ParamRange {
  T min = std::numeric_limits<T>::lowest();
  T max = std::numeric_limits<T>::max();
  bool min_exclusive = false;

  bool contains(T v) const {
    if constexpr (std::is_floating_point_v<T>)
      if (v != v) return false;  // NaN is never valid
    return (min_exclusive ? v > min : v >= min) && v <= max;
  }
  bool bounded_below() const { return min != std::numeric_limits<T>::lowest(); }
  bool bounded_above() const { return max != std::numeric_limits<T>::max(); }
};
/// (0, max]: a positive quantity.
inline ParamRange<double> positive(double max = std::numeric_limits<double>::max()) { return {0.0, max, true}; }
/// [0, max].
inline ParamRange<double> non_negative(double max = std::numeric_limits<double>::max()) { return {0.0, max}; }
/// [0, 1]: a fraction or a probability.
inline ParamRange<double> fraction() { return {0.0, 1.0}; }

/// "[1, 16]", "(0, 1]", ">= 0", "> 0", "<= 5" or "" (unbounded); numbers printed compactly.
std::string describe(const ParamRange<double>& range);
std::string describe(const ParamRange<int>& range);

/// The names of an enum's values, as they appear in YAML and on the command line.
template <class E>
struct EnumName {
  E value;
  std::string_view name;
};
template <class E, size_t N>
using EnumNames = std::array<EnumName<E>, N>;

/// The name of `value` ("" when it has none).
template <class E, size_t N>
constexpr std::string_view enum_name(const EnumNames<E, N>& names, E value) {
  for (const auto& n : names)
    if (n.value == value) return n.name;
  return {};
}
/// The value named `name`, or nullopt.
template <class E, size_t N>
constexpr std::optional<E> enum_value(const EnumNames<E, N>& names, std::string_view name) {
  for (const auto& n : names)
    if (n.name == name) return n.value;
  return std::nullopt;
}
/// "a | b | c".
template <class E, size_t N>
std::string enum_choices(const EnumNames<E, N>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : " | ") + std::string(n.name);
  return out;
}

class ParamVisitor {
 public:
  virtual ~ParamVisitor() = default;
  virtual void param(std::string_view key, bool& value, std::string_view unit, std::string_view doc) = 0;
  virtual void param(std::string_view key, int& value, std::string_view unit, std::string_view doc,
                     ParamRange<int> range = {}) = 0;
  virtual void param(std::string_view key, double& value, std::string_view unit, std::string_view doc,
                     ParamRange<double> range = {}) = 0;
  virtual void param(std::string_view key, std::string& value, std::string_view unit, std::string_view doc) = 0;
  /// A string that must be one of `choices` (enum parameters go through here by name).
  virtual void choice(std::string_view key, std::string& value, std::span<const std::string_view> choices,
                      std::string_view doc) = 0;
  /// A nested section ("tsdf", "tracking.icp", ...).
  virtual void section(std::string_view key, std::string_view doc, const std::function<void(ParamVisitor&)>& body) = 0;

  // Convenience overloads for other arithmetic types (stored as double / int in YAML).
  void param(std::string_view key, float& value, std::string_view unit, std::string_view doc,
             ParamRange<double> range = {}) {
    double d = value;
    param(key, d, unit, doc, range);
    value = static_cast<float>(d);
  }
  void param(std::string_view key, std::vector<std::string>& value, std::string_view unit, std::string_view doc);
  /// An enum parameter, written and read by its name.
  template <class E, size_t N>
    requires std::is_enum_v<E>
  void param(std::string_view key, E& value, const EnumNames<E, N>& names, std::string_view doc) {
    std::array<std::string_view, N> choices;
    for (size_t i = 0; i < N; ++i) choices[i] = names[i].name;
    std::string name(enum_name(names, value));
    choice(key, name, choices, doc);
    for (const auto& n : names)
      if (n.name == name) value = n.value;
  }
};

/// A parameter tree: a function that visits every parameter of a config.
using ParamTree = std::function<void(ParamVisitor&)>;

/// Throws semap::Error("config key 'SECTION.KEY'", "must be in [a, b], got v") for the first
/// parameter outside its declared range or choices. `section` prefixes the keys in messages.
void check_param_ranges(const ParamTree& tree, std::string_view section = {});
/// The same over a config struct with a visit() method (visited on a copy).
template <class Config>
void check_param_ranges(const Config& config, std::string_view section) {
  Config copy = config;
  check_param_ranges(ParamTree([&](ParamVisitor& v) { copy.visit(v); }), section);
}

/// Throws semap::Error("config key KEY", reason) when `ok` is false. Use in validate() for
/// rules between parameters (single-parameter ranges belong in visit()).
void require_param(bool ok, std::string_view key, std::string_view reason);

}  // namespace semap
