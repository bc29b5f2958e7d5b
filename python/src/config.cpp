#include "config.hpp"

#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "numpy_mat.hpp"
#include "semap/io/config_loader.hpp"

namespace semap::python {
namespace {

constexpr const char* kSource = "config dict";
/// Nesting levels a config dict may have. The YAML config nests 3 deep; a deeper value (or a dict
/// or list that contains itself) is refused before the recursion can exhaust the C stack.
constexpr int kMaxConfigDepth = 32;

/// A value whose __index__ / __float__ raised: the Python error becomes this ValueError.
[[noreturn]] void unconvertible(const py::handle& value, const std::string& key, const char* as) {
  PyErr_Clear();
  throw py::value_error(std::string(kSource) + ": config key '" + key + "' has a value of type " + describe(value) +
                        " that does not convert to " + as);
}

/// Writes one Python value as YAML: dicts as maps, lists/tuples as sequences, scalars quoted
/// or plain so that the loader reads back the same type (bool before int: True is an int).
void emit(YAML::Emitter& out, const py::handle& value, const std::string& key, int depth = 0) {
  const bool container = py::isinstance<py::dict>(value) || py::isinstance<py::list>(value) ||
                         py::isinstance<py::tuple>(value);
  if (container && depth >= kMaxConfigDepth)
    throw py::value_error(std::string(kSource) + ": nested more than " + std::to_string(kMaxConfigDepth) +
                          " levels deep" + (key.empty() ? "" : " under '" + key + "'") +
                          " (a dict or list that contains itself?)");
  if (py::isinstance<py::dict>(value)) {
    out << YAML::BeginMap;
    for (const auto& [k, v] : py::reinterpret_borrow<py::dict>(value)) {
      if (!py::isinstance<py::str>(k))
        throw py::value_error(std::string(kSource) + ": keys must be strings, got " + describe(k) +
                              (key.empty() ? "" : " under '" + key + "'"));
      const std::string name = k.cast<std::string>();
      out << YAML::Key << name << YAML::Value;
      emit(out, v, key.empty() ? name : key + "." + name, depth + 1);
    }
    out << YAML::EndMap;
  } else if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    out << YAML::BeginSeq;
    for (const auto& item : value) emit(out, item, key, depth + 1);
    out << YAML::EndSeq;
  } else if (py::isinstance<py::bool_>(value) || py::isinstance(value, py::module_::import("numpy").attr("bool_"))) {
    out << (value.cast<bool>() ? "true" : "false");
  } else if (py::isinstance<py::str>(value)) {
    out << YAML::DoubleQuoted << value.cast<std::string>();
  } else if (PyIndex_Check(value.ptr())) {  // int, numpy integers
    const auto index = py::reinterpret_steal<py::object>(PyNumber_Index(value.ptr()));
    if (!index) unconvertible(value, key, "an integer");  // a failing __index__: not "<NULL>"
    out << py::str(index).cast<std::string>();
  } else if (PyFloat_Check(value.ptr()) || py::hasattr(value, "__float__")) {  // float, numpy floats
    const double number = PyFloat_AsDouble(value.ptr());
    if (number == -1.0 && PyErr_Occurred()) unconvertible(value, key, "a float");
    out << YAML::Precision(17) << number;
  } else if (value.is_none()) {
    out << YAML::Null;
  } else {
    throw py::value_error(std::string(kSource) + ": config key '" + key + "' has a value of type " + describe(value) +
                          " (expected a dict, list, bool, int, float or str)");
  }
}

}  // namespace

SemapConfig config_from_python(const py::handle& config) {
  SemapConfig c;  // the CLI's defaults: mesh.colors are the surfaces' RGB colours
  const ParamTree tree = [&](ParamVisitor& v) { c.visit(v); };
  if (config.is_none()) return c;
  if (py::isinstance<py::dict>(config)) {
    YAML::Emitter out;
    emit(out, config, "");
    load_config_string(out.c_str(), kSource, tree);
    c.validate();
    return c;
  }
  const py::object fspath = py::module_::import("os").attr("fspath");
  if (py::isinstance<py::str>(config) || py::hasattr(config, "__fspath__")) {
    const std::string path = fspath(config).cast<std::string>();
    if (path.empty()) throw py::value_error("config: empty path (None gives the defaults)");
    load_config_file(path, tree);
    c.validate();
    return c;
  }
  bad_argument("config", "None, a dict with the YAML's keys or the path of a YAML file", config);
}

}  // namespace semap::python
