#include "semap/core/params.hpp"

#include <algorithm>

#include "semap/core/error.hpp"  // compact_number

namespace semap {
namespace {

std::string number(double v) { return compact_number(v); }
std::string number(int v) { return std::to_string(v); }

template <class T>
std::string describe_range(const ParamRange<T>& r) {
  const std::string lo = (r.min_exclusive ? "(" : "[") + number(r.min);
  if (r.bounded_below() && r.bounded_above()) return lo + ", " + number(r.max) + "]";
  if (r.bounded_below()) return (r.min_exclusive ? "> " : ">= ") + number(r.min);
  if (r.bounded_above()) return "<= " + number(r.max);
  return "";
}

/// Walks a parameter tree and throws at the first value outside its declared range.
class RangeCheckVisitor : public ParamVisitor {
 public:
  explicit RangeCheckVisitor(std::string prefix) : prefix_(std::move(prefix)) {}

  void param(std::string_view, bool&, std::string_view, std::string_view) override {}
  void param(std::string_view key, int& v, std::string_view, std::string_view, ParamRange<int> range) override {
    if (!range.contains(v)) fail(key, "must be " + in(describe(range)) + ", got " + std::to_string(v));
  }
  void param(std::string_view key, double& v, std::string_view, std::string_view,
             ParamRange<double> range) override {
    if (!range.contains(v)) fail(key, "must be " + in(describe(range)) + ", got " + compact_number(v));
  }
  void param(std::string_view, std::string&, std::string_view, std::string_view) override {}
  void choice(std::string_view key, std::string& v, std::span<const std::string_view> choices,
              std::string_view) override {
    if (std::find(choices.begin(), choices.end(), v) != choices.end()) return;
    std::string all;
    for (const auto c : choices) all += (all.empty() ? "" : " | ") + std::string(c);
    fail(key, "must be one of " + all + ", got '" + v + "'");
  }
  void section(std::string_view key, std::string_view, const std::function<void(ParamVisitor&)>& body) override {
    RangeCheckVisitor sub(join(key));
    body(sub);
  }

 private:
  static std::string in(const std::string& range) {
    return range.front() == '[' || range.front() == '(' ? "in " + range : range;
  }
  std::string join(std::string_view key) const {
    return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
  }
  [[noreturn]] void fail(std::string_view key, const std::string& why) const {
    throw Error("config key '" + join(key) + "'", why);
  }
  std::string prefix_;
};

}  // namespace

std::string describe(const ParamRange<double>& range) { return describe_range(range); }
std::string describe(const ParamRange<int>& range) { return describe_range(range); }

void ParamVisitor::param(std::string_view key, std::vector<std::string>& value, std::string_view unit,
                         std::string_view doc) {
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

void check_param_ranges(const ParamTree& tree, std::string_view section) {
  RangeCheckVisitor visitor{std::string(section)};
  tree(visitor);
}

void require_param(bool ok, std::string_view key, std::string_view reason) {
  if (!ok) throw Error("config key '" + std::string(key) + "'", std::string(reason));
}

}  // namespace semap
