// semap.Mapper: semap::Mapper with numpy in and out. Every call into the Mapper runs with the
// GIL released (numpy_mat.hpp says why); add_frame/finish/save are serialised by a mutex (the
// Mapper's driver calls), the read accessors are not (the Mapper makes them thread-safe).
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <mutex>

#include "bindings.hpp"
#include "bound_types.hpp"
#include "config.hpp"
#include "frame_input.hpp"
#include "numpy_mat.hpp"
#include "semap/io/config_loader.hpp"
#include "semap/navigation/distance_query.hpp"
#include "semap/pipeline/navigation_outputs.hpp"
#include "semap/pipeline/outputs.hpp"

namespace semap::python {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

void apply_segmenter_spec(SemapConfig& c, const py::handle& segmenter) {
  if (segmenter.is_none()) return;
  if (!py::isinstance<py::str>(segmenter))
    bad_argument("segmenter", "None or a spec: yolo:MODEL.onnx | semantic:MODEL.onnx | precomputed:DIR | none",
                 segmenter);
  c.segmentation.segmenter = segmenter.cast<std::string>();
}

class PyMapper {
 public:
  PyMapper(const CameraModel& camera, const py::handle& config, const py::handle& segmenter) {
    SemapConfig c = config_from_python(config);
    apply_segmenter_spec(c, segmenter);
    py::gil_scoped_release nogil;  // a network segmenter loads its model
    mapper_ = std::make_unique<Mapper>(c, camera);
  }
  explicit PyMapper(std::unique_ptr<Mapper> mapper) : mapper_(std::move(mapper)) {}

  /// Mapper::load: continue a saved map.semap (issue 19).
  static std::unique_ptr<PyMapper> load(const std::filesystem::path& path, const py::handle& config,
                                        const py::handle& segmenter) {
    std::optional<SemapConfig> c;
    if (!config.is_none() || !segmenter.is_none()) {
      c = config_from_python(config);
      apply_segmenter_spec(*c, segmenter);
    }
    py::gil_scoped_release nogil;
    return std::make_unique<PyMapper>(Mapper::load(path, c));
  }
  ~PyMapper() {
    py::gil_scoped_release nogil;  // workers drain their queues and release frames (GIL)
    mapper_.reset();
  }

  PyFrameResult add_frame(const py::handle& rgb, const py::handle& depth, double timestamp, const py::handle& labels,
                          const py::handle& instances, const py::handle& pose, bool bgr) {
    const auto t0 = Clock::now();
    const FrameArrays arrays = take_frame_arrays(mapper_->camera(), rgb, depth, timestamp, labels, instances, pose, bgr);
    PyFrameResult out;
    {
      py::gil_scoped_release nogil;
      std::lock_guard lock(driver_mutex_);
      FrameHints hints;
      const Frame frame = to_frame(arrays, mapper_->camera(), next_index_, hints);
      out.result = mapper_->add_frame(frame, std::move(hints));
      ++next_index_;
      ++map_generation_;
    }
    out.binding_ms = ms_since(t0) - out.result.total_ms;
    return out;
  }

  void finish() {
    py::gil_scoped_release nogil;
    std::lock_guard lock(driver_mutex_);
    mapper_->finish();
    ++map_generation_;
  }

  void save(const std::filesystem::path& dir) {
    py::gil_scoped_release nogil;
    std::lock_guard lock(driver_mutex_);
    write_map_outputs(*mapper_, dir);
  }

  // Issue 39: the scene graph (scene_graph.json as a dict) and 3D distance queries.
  py::object scene_graph() const {
    nlohmann::json graph;
    {
      py::gil_scoped_release nogil;
      graph = to_json(build_navigation_maps(*mapper_).scene_graph);
    }
    return json_to_python(graph);
  }
  /// The distance field of the map now (navigation/distance_query.hpp), built on the first query
  /// after the map changed (add_frame, finish) from the TSDF and the camera positions.
  std::shared_ptr<const DistanceQuery> distance_query() const {
    std::lock_guard lock(query_mutex_);
    const size_t generation = map_generation_;
    if (!query_ || query_generation_ != generation) {
      std::vector<Eigen::Vector3d> cameras;
      for (const StampedPose& p : mapper_->trajectory()) cameras.push_back(p.T_world_camera.translation());
      mapper_->read_tsdf([&](const TsdfMap& map) {
        query_ = std::make_shared<const DistanceQuery>(map, mapper_->config().navigation, cameras);
      });
      query_generation_ = generation;
    }
    return query_;
  }
  double distance_m(const std::array<double, 3>& p) const {
    py::gil_scoped_release nogil;
    return distance_query()->distance_m({p[0], p[1], p[2]});
  }
  bool is_free(const std::array<double, 3>& p, double radius_m) const {
    py::gil_scoped_release nogil;
    return distance_query()->is_free({p[0], p[1], p[2]}, radius_m);
  }

  py::list trajectory() const {
    Trajectory t;
    {
      py::gil_scoped_release nogil;
      t = mapper_->trajectory();
    }
    return trajectory_to_python(t);
  }

  PyMesh mesh() const {
    py::gil_scoped_release nogil;
    return PyMesh{mapper_->mesh()};
  }

  std::vector<ObjectSummary> objects() const {
    py::gil_scoped_release nogil;
    return mapper_->objects();
  }

  py::dict stats() const {
    MapperStats s;
    {
      py::gil_scoped_release nogil;
      s = mapper_->stats();
    }
    py::dict d;
    d["frames"] = s.frames, d["frames_fused"] = s.frames_fused, d["keyframes"] = s.keyframes;
    d["lost_frames"] = s.lost_frames, d["relocalisations"] = s.relocalisations, d["loop_edges"] = s.loop_edges;
    d["local_edges"] = s.local_edges;
    d["optimisations"] = s.optimisations, d["segmented_frames"] = s.segmented_frames;
    d["semantic_segmented_frames"] = s.semantic_segmented_frames;
    d["segmentations_dropped"] = s.segmentations_dropped, d["segmentations_failed"] = s.segmentations_failed;
    d["segmentation_error"] = s.segmentation_error, d["object_frames"] = s.object_frames, d["objects"] = s.objects;
    d["finished"] = s.finished, d["map_refreshed"] = s.map_refreshed, d["map_refresh_note"] = s.map_refresh_note;
    d["max_pose_correction_m"] = s.max_pose_correction_m, d["external_poses"] = s.external_poses;
    d["segmenter"] = s.segmenter;
    d["resumed_keyframes"] = s.resumed_keyframes, d["held_frames"] = s.held_frames;
    // Issue 42: registrations verified and how often each check failed (report.json tracking.checks).
    py::dict checks;
    checks["verified"] = s.verified_registrations, checks["dense_residual_failed"] = s.dense_residual_failed;
    checks["spread_failed"] = s.spread_failed, checks["ambiguous"] = s.ambiguous_matches;
    checks["under_constrained"] = s.under_constrained;
    d["tracking_checks"] = checks;
    return d;
  }

  py::dict timings() const {
    std::map<std::string, TimingSummary> t;
    {
      py::gil_scoped_release nogil;
      t = mapper_->timings();
    }
    py::dict d;
    for (const auto& [stage, s] : t) {
      py::dict e;
      e["count"] = s.count, e["mean_ms"] = s.mean_ms, e["median_ms"] = s.median_ms, e["p95_ms"] = s.p95_ms;
      e["total_ms"] = s.total_ms;
      d[py::str(stage)] = e;
    }
    return d;
  }

  const CameraModel& camera() const { return mapper_->camera(); }
  std::string config_yaml() const {
    SemapConfig c = mapper_->config();
    return dump_config([&](ParamVisitor& v) { c.visit(v); });
  }

 private:
  std::unique_ptr<Mapper> mapper_;
  std::mutex driver_mutex_;
  size_t next_index_ = 0;
  std::atomic<size_t> map_generation_{0};  ///< bumped by every call that changes the map
  mutable std::mutex query_mutex_;
  mutable std::shared_ptr<const DistanceQuery> query_;
  mutable size_t query_generation_ = 0;
};

}  // namespace

void bind_mapper(py::module_& m) {
  py::class_<PyMapper>(m, "Mapper", "semap::Mapper: frames in; poses, a labelled mesh and objects out.")
      .def(py::init<const CameraModel&, const py::handle&, const py::handle&>(), py::arg("camera"),
           py::arg("config") = py::none(), py::arg("segmenter") = py::none())
      .def("add_frame", &PyMapper::add_frame, py::arg("rgb"), py::arg("depth"), py::arg("timestamp"),
           py::arg("labels") = py::none(), py::arg("instances") = py::none(), py::arg("pose") = py::none(),
           py::kw_only(), py::arg("bgr") = false,
           "Tracks (or takes `pose`, a (4, 4) T_world_camera), segments and fuses one frame. rgb: uint8 "
           "(H, W, 3) in RGB order (BGR with bgr=True); depth: uint16 raw units or float32 metres (H, W); "
           "labels: uint8 class ids and instances: uint16 ids (H, W, depth size), the caller's own "
           "segmentation. The arrays are referenced, not copied: do not write into them afterwards.")
      .def("finish", &PyMapper::finish, "final pose graph, map refresh, final object pass (idempotent)")
      .def_static("load", &PyMapper::load, py::arg("path"), py::arg("config") = py::none(),
                  py::arg("segmenter") = py::none(),
                  "Continues a saved map (a map.semap, e.g. out_dir/map.semap of save()): new frames are first "
                  "relocalised into it (held, status 'lost', until one verifies), then extend it in its world "
                  "frame. config / segmenter as for Mapper(); the map's tsdf and objects settings stay the file's.")
      .def("save", &PyMapper::save, py::arg("out_dir"),
           "trajectory.txt, mesh.ply, objects.json + objects/*.ply, map.semap (what `semap run` writes)")
      .def("trajectory", &PyMapper::trajectory, "list of (timestamp, (4, 4) T_world_camera)")
      .def("mesh", &PyMapper::mesh, "the labelled mesh now")
      .def("objects", &PyMapper::objects, "the object map now")
      .def("stats", &PyMapper::stats)
      .def("timings", &PyMapper::timings, "per stage: count, mean_ms, median_ms, p95_ms, total_ms")
      .def_property_readonly("camera", &PyMapper::camera)
      .def("config_yaml", &PyMapper::config_yaml, "the configuration in use, as YAML")
      .def("scene_graph", &PyMapper::scene_graph, "the scene graph now, as scene_graph.json's dict (issue 39)")
      .def("distance_m", &PyMapper::distance_m, py::arg("point"),
           "signed Euclidean distance (m, world frame) from point to the nearest observed surface (3D distance field, "
           "built once per map state): positive in observed free space, nan where unobserved, at most "
           "navigation.esdf_max_distance_m")
      .def("is_free", &PyMapper::is_free, py::arg("point"), py::arg("radius"),
           "whether point is observed and distance_m(point) >= radius (no observed surface in the ball; unobserved: "
           "not free)");
}

}  // namespace semap::python
