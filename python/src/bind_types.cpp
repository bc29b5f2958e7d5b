// semap.Camera, semap.FrameResult, semap.Mesh, semap.Object.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>

#include "bindings.hpp"
#include "bound_types.hpp"
#include "numpy_mat.hpp"
#include "semap/core/camera.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/objects/object_summary.hpp"

namespace semap::python {
namespace {

static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "vertices are viewed as (N, 3) float32");
static_assert(sizeof(Rgb8) == 3, "colours are viewed as (N, 3) uint8");
static_assert(sizeof(std::array<uint32_t, 3>) == 3 * sizeof(uint32_t), "triangles are viewed as (M, 3) uint32");

/// (n, cols) (or (n,) when cols == 0) array of T over `data`, kept alive by `owner`.
template <class T>
py::array vector_view(const void* data, size_t n, size_t cols, py::handle owner) {
  const auto rows = static_cast<py::ssize_t>(n);
  if (cols == 0) return py::array_t<T>({rows}, {static_cast<py::ssize_t>(sizeof(T))}, static_cast<const T*>(data), owner);
  const auto c = static_cast<py::ssize_t>(cols);
  return py::array_t<T>({rows, c}, {static_cast<py::ssize_t>(sizeof(T)) * c, static_cast<py::ssize_t>(sizeof(T))},
                        static_cast<const T*>(data), owner);
}

/// The cloud's attribute as a view, or None when the cloud has none.
template <class T, class Vector>
py::object optional_view(const Vector& values, size_t cols, py::handle owner) {
  if (values.empty()) return py::none();
  return vector_view<T>(values.data(), values.size(), cols, owner);
}

py::array_t<double> vector3(const Eigen::Vector3f& v) {
  py::array_t<double> out(3);
  for (int i = 0; i < 3; ++i) out.mutable_at(i) = v[i];
  return out;
}

CameraModel make_camera(double fx, double fy, double cx, double cy, int width, int height, double depth_scale,
                        std::array<double, 5> distortion) {
  CameraModel camera;
  camera.depth = {fx, fy, cx, cy, width, height};
  camera.depth_scale = depth_scale;
  camera.distortion = distortion;
  validate_camera(camera, "semap.Camera");
  return camera;
}

void bind_camera(py::module_& m) {
  py::class_<CameraModel>(m, "Camera",
                          "Pinhole RGB-D camera: depth intrinsics (colour registered to depth) and the raw depth "
                          "units per metre.")
      .def(py::init(&make_camera), py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::arg("width"),
           py::arg("height"), py::arg("depth_scale") = 5000.0,
           py::arg("distortion") = std::array<double, 5>{0, 0, 0, 0, 0},
           "distortion: k1 k2 p1 p2 k3 (OpenCV order) of the lens; Mapper.add_frame undistorts the frames")
      .def_static("tum", &tum_camera_preset, py::arg("freiburg"), "TUM RGB-D preset (freiburg 1, 2 or 3)")
      .def_property_readonly("fx", [](const CameraModel& c) { return c.depth.fx; })
      .def_property_readonly("fy", [](const CameraModel& c) { return c.depth.fy; })
      .def_property_readonly("cx", [](const CameraModel& c) { return c.depth.cx; })
      .def_property_readonly("cy", [](const CameraModel& c) { return c.depth.cy; })
      .def_property_readonly("width", [](const CameraModel& c) { return c.depth.width; })
      .def_property_readonly("height", [](const CameraModel& c) { return c.depth.height; })
      .def_readonly("depth_scale", &CameraModel::depth_scale)
      .def_property_readonly("distortion", [](const CameraModel& c) { return py::make_tuple(
          c.distortion[0], c.distortion[1], c.distortion[2], c.distortion[3], c.distortion[4]); })
      .def_property_readonly("has_color_camera", [](const CameraModel& c) { return c.colour.has_value(); })
      .def_property_readonly("color_size", [](const CameraModel& c) {
        return py::make_tuple(c.colour_intrinsics().width, c.colour_intrinsics().height);
      }, "(width, height) of the colour images add_frame() takes")
      .def_property_readonly("K", [](const CameraModel& c) {
        py::array_t<double> k({3, 3});
        for (int r = 0; r < 3; ++r)
          for (int col = 0; col < 3; ++col) k.mutable_at(r, col) = c.depth.K()(r, col);
        return k;
      });
}

void bind_frame_result(py::module_& m) {
  py::class_<PyFrameResult>(m, "FrameResult", "What Mapper.add_frame() did with a frame.")
      .def_property_readonly("pose", [](const PyFrameResult& r) { return pose_to_numpy(r.result.T_world_camera); },
                             "(4, 4) float64 T_world_camera (camera-to-world), the online estimate")
      .def_property_readonly("status", [](const PyFrameResult& r) { return std::string(to_string(r.result.status)); },
                             "'tracking', 'keyframe', 'lost' or 'relocalised'")
      .def_property_readonly("frame_index", [](const PyFrameResult& r) { return r.result.frame_index; })
      .def_property_readonly("timestamp", [](const PyFrameResult& r) { return r.result.timestamp; })
      .def_property_readonly("fused", [](const PyFrameResult& r) { return r.result.fused; })
      .def_property_readonly("segmented", [](const PyFrameResult& r) { return r.result.segmented; })
      .def_property_readonly("tracking_ms", [](const PyFrameResult& r) { return r.result.tracking_ms; })
      .def_property_readonly("total_ms", [](const PyFrameResult& r) { return r.result.total_ms; },
                             "time the C++ Mapper::add_frame took")
      .def_readonly("binding_ms", &PyFrameResult::binding_ms,
                    "time add_frame spent outside the C++ call (checks, RGB->BGR, depth units, GIL)");
}

void bind_mesh(py::module_& m) {
  py::class_<PyMesh>(m, "Mesh", "The labelled mesh (METHODS B7). Arrays are views into this object.")
      .def_property_readonly("vertices", [](py::object self) {
        const auto& v = self.cast<const PyMesh&>().mesh.vertices.points;
        return vector_view<float>(v.data(), v.size(), 3, self);
      }, "(N, 3) float32, world frame, metres")
      .def_property_readonly("triangles", [](py::object self) {
        const auto& t = self.cast<const PyMesh&>().mesh.triangles;
        return vector_view<uint32_t>(t.data(), t.size(), 3, self);
      }, "(M, 3) uint32 vertex indices")
      .def_property_readonly("colors", [](py::object self) {
        return optional_view<uint8_t>(self.cast<const PyMesh&>().mesh.vertices.colours, 3, self);
      }, "(N, 3) uint8 RGB surface colour, or None")
      .def_property_readonly("normals", [](py::object self) {
        return optional_view<float>(self.cast<const PyMesh&>().mesh.vertices.normals, 3, self);
      }, "(N, 3) float32 unit normals, or None")
      .def_property_readonly("labels", [](py::object self) {
        return optional_view<uint8_t>(self.cast<const PyMesh&>().mesh.vertices.labels, 0, self);
      }, "(N,) uint8 class ids (semap.class_names()), or None")
      .def_property_readonly("instances", [](py::object self) {
        return optional_view<uint32_t>(self.cast<const PyMesh&>().mesh.vertices.instances, 0, self);
      }, "(N,) uint32 object ids (0 = none), or None")
      .def_property_readonly("num_vertices", [](const PyMesh& m) { return m.mesh.vertices.size(); })
      .def_property_readonly("num_triangles", [](const PyMesh& m) { return m.mesh.triangles.size(); })
      .def("save_ply", [](const PyMesh& m, const std::filesystem::path& path) {
        py::gil_scoped_release nogil;
        write_ply(path, m.mesh);
      }, py::arg("path"), "binary PLY with x y z red green blue label instance");
}

void bind_object(py::module_& m) {
  py::class_<ObjectSummary>(m, "Object", "One object of the object map (world frame, metres).")
      .def_readonly("id", &ObjectSummary::id)
      .def_readonly("class_id", &ObjectSummary::class_id)
      .def_property_readonly("class_name", [](const ObjectSummary& o) { return std::string(class_name(o.class_id)); })
      .def_property_readonly("centroid", [](const ObjectSummary& o) { return vector3(o.centroid); })
      .def_property_readonly("extent", [](const ObjectSummary& o) { return vector3(o.box.extent); },
                             "(3,) full side lengths of the oriented box (PCA)")
      .def_property_readonly("box_center", [](const ObjectSummary& o) { return vector3(o.box.center); })
      .def_property_readonly("box_rotation", [](const ObjectSummary& o) {
        py::array_t<double> r({3, 3});
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) r.mutable_at(i, j) = o.box.rotation(i, j);
        return r;
      }, "(3, 3) world_from_box rotation")
      .def_property_readonly("aabb_min", [](const ObjectSummary& o) { return vector3(o.aabb_min); })
      .def_property_readonly("aabb_max", [](const ObjectSummary& o) { return vector3(o.aabb_max); })
      .def_property_readonly("point_count", [](const ObjectSummary& o) { return o.points.size(); })
      .def_property_readonly("points", [](py::object self) {
        const auto& p = self.cast<const ObjectSummary&>().points;
        return vector_view<float>(p.data(), p.size(), 3, self);
      }, "(K, 3) float32, one per occupied object voxel")
      .def_property_readonly("colors", [](py::object self) {
        return optional_view<uint8_t>(self.cast<const ObjectSummary&>().colours, 3, self);
      })
      .def_readonly("class_distribution", &ObjectSummary::class_distribution, "class name -> mean score")
      .def_readonly("merge_count", &ObjectSummary::merge_count)
      .def_readonly("associations", &ObjectSummary::associations)
      .def_readonly("first_frame", &ObjectSummary::first_frame)
      .def_readonly("last_frame", &ObjectSummary::last_frame)
      .def_readonly("state", &ObjectSummary::state)
      .def_property_readonly("view_jpeg", [](const ObjectSummary& o) { return py::bytes(o.best_view_jpeg); },
                             "bytes: JPEG crop (longest side <= 96 px) of the keyframe that saw the object best, "
                             "as report.html's card shows it; kept in map.semap; b'' when no keyframe showed it")
      .def("to_json", [](const ObjectSummary& o) { return to_json(o).dump(); }, "the objects.json entry as text");
}

}  // namespace

void bind_types(py::module_& m) {
  bind_camera(m);
  bind_frame_result(m);
  bind_mesh(m);
  bind_object(m);
}

}  // namespace semap::python
