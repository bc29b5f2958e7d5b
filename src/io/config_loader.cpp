#include "semap/io/config_loader.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include "semap/core/error.hpp"
#include "core/paths.hpp"

namespace semap {
namespace {

std::string join_choices(std::span<const std::string_view> choices) {
  std::string all;
  for (const auto c : choices) all += (all.empty() ? "" : " | ") + std::string(c);
  return all;
}

std::string join_key(const std::string& prefix, std::string_view key) {
  return prefix.empty() ? std::string(key) : prefix + "." + std::string(key);
}

/// Walks the parameter tree and a YAML map side by side.
class YamlLoadVisitor : public ParamVisitor {
 public:
  YamlLoadVisitor(YAML::Node node, std::string source, std::string prefix)
      : node_(std::move(node)), source_(std::move(source)), prefix_(std::move(prefix)) {}

  void param(std::string_view key, bool& v, std::string_view, std::string_view) override { read(key, v, "a boolean"); }
  void param(std::string_view key, int& v, std::string_view, std::string_view, ParamRange<int> range) override {
    if (read(key, v, "an integer") && !range.contains(v))
      fail(key, "must be " + in_words(describe(range)) + ", got " + std::to_string(v));
  }
  void param(std::string_view key, double& v, std::string_view, std::string_view,
             ParamRange<double> range) override {
    if (!read(key, v, "a number")) return;
    if (!std::isfinite(v)) fail(key, "must be a finite number");
    if (!range.contains(v)) fail(key, "must be " + in_words(describe(range)) + ", got " + compact_number(v));
  }
  void param(std::string_view key, std::string& v, std::string_view, std::string_view) override {
    read(key, v, "a string");
  }
  void choice(std::string_view key, std::string& v, std::span<const std::string_view> choices,
              std::string_view) override {
    if (!read(key, v, "a string")) return;
    if (std::find(choices.begin(), choices.end(), v) == choices.end())
      fail(key, "must be one of " + join_choices(choices) + ", got '" + v + "'");
  }
  void section(std::string_view key, std::string_view, const std::function<void(ParamVisitor&)>& body) override {
    known_.insert(std::string(key));
    YAML::Node child;
    if (node_ && node_.IsMap()) child = node_[std::string(key)];
    if (child && !child.IsNull() && !child.IsMap()) fail(key, "must be a map of parameters");
    YamlLoadVisitor sub(child && child.IsMap() ? child : YAML::Node(), source_, join_key(prefix_, key));
    body(sub);
    sub.check_unknown();
  }

  void check_unknown() const {
    if (!node_ || !node_.IsMap()) return;
    for (const auto& kv : node_) {
      // A key may be a sequence or a map in YAML ("? [a, b]: 1"); no parameter is named so.
      if (!kv.first.IsScalar())
        throw Error(source_, "config key under '" + (prefix_.empty() ? std::string("(top level)") : prefix_) +
                                 "' is not a plain name");
      const std::string k = kv.first.as<std::string>();
      if (!known_.count(k))
        throw Error(source_, "unknown config key '" + join_key(prefix_, k) + "' (see `semap config --dump`)");
    }
  }

 private:
  /// True when the YAML sets the key (v then holds its value).
  template <class T>
  bool read(std::string_view key, T& v, const char* what) {
    known_.insert(std::string(key));
    if (!node_ || !node_.IsMap()) return false;
    const YAML::Node n = node_[std::string(key)];
    if (!n) return false;
    if (!n.IsScalar()) fail(key, std::string("must be ") + what);
    try {
      v = n.as<T>();
    } catch (const YAML::Exception&) {
      fail(key, std::string("must be ") + what + ", got '" + message_text(n.Scalar(), 80) + "'");
    }
    return true;
  }
  static std::string in_words(const std::string& range) {
    return range.front() == '[' || range.front() == '(' ? "in " + range : range;
  }
  [[noreturn]] void fail(std::string_view key, const std::string& why) const {
    throw Error(source_, "config key '" + join_key(prefix_, key) + "' " + why);
  }

  YAML::Node node_;
  std::string source_, prefix_;
  std::set<std::string> known_;
};

class YamlDumpVisitor : public ParamVisitor {
 public:
  explicit YamlDumpVisitor(int indent) : indent_(indent) {}
  void param(std::string_view key, bool& v, std::string_view u, std::string_view d) override {
    line(key, v ? "true" : "false", u, d);
  }
  void param(std::string_view key, int& v, std::string_view u, std::string_view d, ParamRange<int> range) override {
    line(key, std::to_string(v), u, d, describe(range));
  }
  void param(std::string_view key, double& v, std::string_view u, std::string_view d,
             ParamRange<double> range) override {
    std::ostringstream s;
    s.precision(10);
    s << v;
    std::string t = s.str();
    if (t.find_first_of(".eEn") == std::string::npos) t += ".0";
    line(key, t, u, d, describe(range));
  }
  void param(std::string_view key, std::string& v, std::string_view u, std::string_view d) override {
    line(key, quoted(v), u, d);
  }
  void choice(std::string_view key, std::string& v, std::span<const std::string_view> choices,
              std::string_view d) override {
    line(key, quoted(v), "", d, join_choices(choices));
  }
  void section(std::string_view key, std::string_view doc, const std::function<void(ParamVisitor&)>& body) override {
    if (!doc.empty()) out_ << pad() << "# " << doc << "\n";
    out_ << pad() << key << ":\n";
    YamlDumpVisitor sub(indent_ + 2);
    body(sub);
    out_ << sub.out_.str();
  }
  std::string str() const { return out_.str(); }

 private:
  std::string pad() const { return std::string(indent_, ' '); }
  static std::string quoted(const std::string& v) {
    YAML::Emitter e;
    e << YAML::DoubleQuoted << v;
    return e.c_str();
  }
  /// key: value  # doc [unit; range]
  void line(std::string_view key, const std::string& value, std::string_view unit, std::string_view doc,
            const std::string& range = {}) {
    out_ << pad() << key << ": " << value;
    if (!doc.empty() || !unit.empty() || !range.empty()) {
      out_ << "  # " << doc;
      if (!unit.empty() || !range.empty()) {
        out_ << " [" << unit << (!unit.empty() && !range.empty() ? "; " : "") << range << "]";
      }
    }
    out_ << "\n";
  }
  int indent_;
  std::ostringstream out_;
};

}  // namespace

namespace {

std::string line_of(const std::string& source, const YAML::Mark& mark) {
  return mark.line >= 0 ? source + ":" + std::to_string(mark.line + 1) : source;
}

// yaml-cpp keeps every pair of a map with a repeated key and returns the first: the second,
// usually the one the user meant, would be ignored silently.
void check_unique_keys(const YAML::Node& node, const std::string& source, int depth) {
  if (depth > 64) throw Error(line_of(source, node.Mark()), "YAML nested more than 64 levels deep");
  if (node.IsSequence()) {
    for (const auto& item : node) check_unique_keys(item, source, depth + 1);
  } else if (node.IsMap()) {
    std::map<std::string, int> first_line;
    for (const auto& kv : node) {
      if (kv.first.IsScalar()) {
        const auto [it, inserted] = first_line.emplace(kv.first.Scalar(), kv.first.Mark().line + 1);
        if (!inserted)
          throw Error(line_of(source, kv.first.Mark()), "duplicate key '" + message_text(kv.first.Scalar(), 80) +
                                                            "' (first at line " + std::to_string(it->second) + ")");
      }
      check_unique_keys(kv.second, source, depth + 1);
    }
  }
}

}  // namespace

/// Where each document the parser reports starts (nothing else is kept).
class DocumentStarts : public YAML::EventHandler {
 public:
  std::vector<YAML::Mark> marks;
  void OnDocumentStart(const YAML::Mark& mark) override { marks.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t, const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

YAML::Node parse_yaml_strict(const std::string& text, const std::string& source) {
  const std::string body(std::string_view(text).substr(text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0));
  // The documents are counted by asking the parser for two at most: yaml-cpp 0.7's LoadAll never
  // ends on some inputs (a lone ',' is an empty document at offset 0, again and again:
  // fuzz_dataset_yaml), so a "second" document that starts where the first did is malformed.
  YAML::Node document;
  DocumentStarts starts;
  try {
    std::istringstream stream(body);
    YAML::Parser parser(stream);
    for (int i = 0; i < 2 && parser.HandleNextDocument(starts); ++i) {
    }
    if (!starts.marks.empty()) document = YAML::Load(body);
  } catch (const YAML::Exception& e) {
    throw Error(source, "malformed YAML: " + std::string(e.what()));
  }
  if (starts.marks.size() > 1) {
    if (starts.marks[1].pos <= starts.marks[0].pos)
      throw Error(line_of(source, starts.marks[1]), "malformed YAML: the parser does not get past this point");
    throw Error(line_of(source, starts.marks[1]), "a second YAML document ('---'); the file must hold exactly one");
  }
  if (starts.marks.empty()) return YAML::Node();
  check_unique_keys(document, source, 0);
  return document;
}

void load_config_string(const std::string& yaml, const std::string& source, const ParamTree& tree) {
  const YAML::Node root = parse_yaml_strict(yaml, source);
  if (root && !root.IsNull() && !root.IsMap()) throw Error(source, "config must be a YAML map");
  YamlLoadVisitor visitor(root, source, "");
  tree(visitor);
  visitor.check_unknown();
}

void load_config_file(const std::filesystem::path& yaml_path, const ParamTree& tree) {
  load_config_string(read_regular_file(yaml_path, kMaxTextFileBytes, "config file"), yaml_path.string(), tree);
}

std::string dump_config(const ParamTree& tree) {
  YamlDumpVisitor visitor(0);
  tree(visitor);
  return visitor.str();
}

}  // namespace semap
