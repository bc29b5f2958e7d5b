// The _semap extension module; `import semap` loads it through python/semap/__init__.py.
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <yaml-cpp/exceptions.h>

#include <filesystem>
#include <fstream>
#include <new>
#include <optional>

#include "bindings.hpp"
#include "semap/core/error.hpp"
#include "semap/core/labels.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/trajectory_io.hpp"
#include "semap/pipeline/map_merge.hpp"
#include "semap/navigation/scene_graph.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "semap/pipeline/semap_config.hpp"
#include "config.hpp"

namespace py = pybind11;

namespace semap::python {

py::object json_to_python(const nlohmann::json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

namespace {

py::dict evaluate_ate(const std::filesystem::path& gt, const std::filesystem::path& est, double max_dt) {
  nlohmann::json j;
  {
    py::gil_scoped_release nogil;
    j = to_json(compute_ate(read_tum_trajectory(gt), read_tum_trajectory(est), max_dt));
  }
  return json_to_python(j);
}

py::dict evaluate_rpe(const std::filesystem::path& gt, const std::filesystem::path& est, double delta_s, double max_dt) {
  nlohmann::json j;
  {
    py::gil_scoped_release nogil;
    j = to_json(compute_rpe(read_tum_trajectory(gt), read_tum_trajectory(est), delta_s, max_dt));
  }
  return json_to_python(j);
}

/// `semap run` from Python: the same driver, outputs published into `out` as a whole.
py::dict run(const std::filesystem::path& dataset, const std::filesystem::path& out, const py::object& config,
             const std::string& segmenter, const std::optional<std::filesystem::path>& resume, bool evaluate,
             bool progress) {
  RunOptions options;
  options.dataset = dataset;
  options.out_dir = out;
  options.segmenter = segmenter;
  if (resume) options.resume_from = *resume;
  options.evaluate = evaluate;
  options.show_progress = progress;
  const SemapConfig parsed = config_from_python(config);
  nlohmann::json j;
  {
    py::gil_scoped_release nogil;
    run_pipeline(options, parsed);
    // The report.json the run published (it always does when it returns): the run's result plus
    // the map's figures (consistency, gravity, navigation).
    std::ifstream published(out / "report.json");
    if (!published) throw Error(out / "report.json", "the run returned without publishing it");
    j = nlohmann::json::parse(published);
  }
  return json_to_python(j);
}

py::dict merge_maps(const std::filesystem::path& a, const std::filesystem::path& b, const std::filesystem::path& out) {
  nlohmann::json j;
  {
    py::gil_scoped_release nogil;
    j = to_json(semap::merge_maps(a, b, out));
  }
  return json_to_python(j);
}

std::vector<std::string> class_names() {
  std::vector<std::string> names;
  for (int c = 0; c < kNumClasses; ++c) names.emplace_back(class_name(static_cast<ClassId>(c)));
  return names;
}

py::array_t<uint8_t> class_colors() {
  py::array_t<uint8_t> out({kNumClasses, 3});
  for (int c = 0; c < kNumClasses; ++c) {
    const Rgb8 rgb = class_colour(static_cast<ClassId>(c));
    out.mutable_at(c, 0) = rgb.r, out.mutable_at(c, 1) = rgb.g, out.mutable_at(c, 2) = rgb.b;
  }
  return out;
}

}  // namespace
}  // namespace semap::python

PYBIND11_MODULE(_semap, m) {
  using namespace semap::python;
  m.doc() = "semap: RGB-D semantic mapping (C++ core, numpy in and out)";
  m.attr("__version__") = SEMAP_VERSION;
  // Every semap::Error (bad file, bad config key, bad camera, add_frame after finish) is a
  // semap.Error, a ValueError.
  // Issue 44, class 5: no other C++ exception reaches Python as a raw RuntimeError (yaml-cpp or
  // standard-library text): they become semap.Error too. Registered first, so tried last (pybind11
  // tries translators newest first): semap::Error and pybind11's own errors keep their types.
  static PyObject* semap_error_type = nullptr;
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const py::error_already_set&) {
      throw;
    } catch (const py::builtin_exception&) {
      throw;
    } catch (const semap::Error&) {
      throw;
    } catch (const std::bad_alloc&) {
      PyErr_SetString(semap_error_type, "out of memory");
    } catch (const YAML::Exception& e) {
      PyErr_SetString(semap_error_type, ("config: malformed YAML: " + e.msg).c_str());
    } catch (const std::exception& e) {
      PyErr_SetString(semap_error_type, e.what());
    }
  });
  semap_error_type = py::register_exception<semap::Error>(m, "Error", PyExc_ValueError).ptr();
  bind_types(m);
  bind_mapper(m);
  bind_dataset(m);
  m.def("evaluate_ate", &evaluate_ate, py::arg("gt_path"), py::arg("est_path"), py::arg("max_dt") = 0.02,
        "ATE of two TUM trajectory files (TUM benchmark definitions): rmse_m, mean_m, median_m, max_m, matched, "
        "T_gt_est");
  m.def("evaluate_rpe", &evaluate_rpe, py::arg("gt_path"), py::arg("est_path"), py::arg("delta_s") = 1.0,
        py::arg("max_dt") = 0.02, "RPE over delta_s seconds: trans_rmse_m_per_s, rot_rmse_deg_per_s, ...");
  m.def("run", &run, py::arg("dataset"), py::arg("out"), py::arg("config") = py::none(), py::arg("segmenter") = "",
        py::arg("resume") = py::none(), py::arg("evaluate") = true, py::arg("progress") = false,
        "`semap run DATASET --out OUT`: maps a dataset folder/file, publishes the outputs into out as a whole "
        "(trajectory, mesh, objects, map.semap, report) and returns report.json as a dict. config: None, a nested "
        "dict or a YAML path; segmenter: '' (the config's), 'none', 'yolo:MODEL', ...; resume: a saved map to "
        "continue");
  m.def("merge_maps", &merge_maps, py::arg("a"), py::arg("b"), py::arg("out"),
        "`semap merge A B --out OUT`: map B relocalised into map A and fused in A's world frame; returns the "
        "report (summary.merged false and summary.reason when B does not relocalise: nothing written)");
  m.def("load_scene_graph", [](const std::filesystem::path& out) { return json_to_python(to_json(semap::load_scene_graph(out))); },
        py::arg("out"), "OUT/scene_graph.json (or that file) as a dict, validated (issue 39)");
  m.def("class_names", &class_names, "the project's classes; index = class id");
  m.def("class_colors", &class_colors, "(C, 3) uint8 palette; row = class id");
  m.def("default_config", &semap::dump_default_config, "YAML of every parameter with its default");
}
