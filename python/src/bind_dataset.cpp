// semap.open_dataset(): the CLI's dataset readers (every layout open_dataset() detects), frames
// decoded on demand, arrays as views into the decoded frame.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <memory>

#include "bindings.hpp"
#include "numpy_mat.hpp"
#include "semap/io/dataset.hpp"

namespace semap::python {
namespace {

/// semap.DatasetFrame: one decoded frame; .rgb is converted to RGB order on first use.
struct PyFrame {
  Frame frame;
  cv::Mat rgb_order;
};

py::object optional_mat(const cv::Mat& mat, py::handle owner) {
  return mat.empty() ? py::none() : py::object(view(mat, owner));
}

struct PyDataset {
  std::shared_ptr<const DatasetReader> reader;

  PyFrame get(py::ssize_t i) const {
    const auto n = static_cast<py::ssize_t>(reader->size());
    if (i < 0) i += n;
    if (i < 0 || i >= n) throw py::index_error("dataset index " + std::to_string(i) + " out of range (" +
                                               std::to_string(n) + " frames)");
    py::gil_scoped_release nogil;  // PNG decoding
    return PyFrame{reader->load(static_cast<size_t>(i)), {}};
  }
};

void bind_frame(py::module_& m) {
  py::class_<PyFrame>(m, "DatasetFrame", "A decoded frame; arrays are views into it.")
      .def_property_readonly("rgb", [](py::object self) -> py::object {
        PyFrame& f = self.cast<PyFrame&>();
        if (f.frame.rgb.empty()) return py::none();
        if (f.rgb_order.empty()) cv::cvtColor(f.frame.rgb, f.rgb_order, cv::COLOR_BGR2RGB);
        return view(f.rgb_order, self);
      }, "(H, W, 3) uint8 in RGB order")
      .def_property_readonly("bgr", [](py::object self) { return optional_mat(self.cast<PyFrame&>().frame.rgb, self); },
                             "(H, W, 3) uint8 in BGR order (OpenCV's), no conversion")
      .def_property_readonly("depth", [](py::object self) { return view(self.cast<PyFrame&>().frame.depth, self); },
                             "(H, W) float32 metres, 0 = invalid")
      .def_property_readonly("labels", [](py::object self) { return optional_mat(self.cast<PyFrame&>().frame.labels, self); },
                             "(H, W) uint8 ground-truth class ids, or None")
      .def_property_readonly("instances", [](py::object self) {
        return optional_mat(self.cast<PyFrame&>().frame.instances, self);
      }, "(H, W) uint16 ground-truth instance ids, or None")
      .def_property_readonly("timestamp", [](const PyFrame& f) { return f.frame.timestamp; })
      .def_property_readonly("index", [](const PyFrame& f) { return f.frame.index; })
      .def_property_readonly("gt_pose", [](const PyFrame& f) -> py::object {
        if (!f.frame.gt_T_world_camera) return py::none();
        return pose_to_numpy(*f.frame.gt_T_world_camera);
      }, "(4, 4) ground-truth T_world_camera, or None")
      .def_property_readonly("rgb_path", [](const PyFrame& f) { return f.frame.rgb_path; })
      .def_property_readonly("depth_path", [](const PyFrame& f) { return f.frame.depth_path; });
}

}  // namespace

void bind_dataset(py::module_& m) {
  bind_frame(m);
  py::class_<PyDataset>(m, "Dataset", "A dataset opened with the CLI's readers.")
      .def("__len__", [](const PyDataset& d) { return d.reader->size(); })
      .def("__getitem__", &PyDataset::get, py::arg("index"))
      .def_property_readonly("camera", [](const PyDataset& d) { return d.reader->camera(); })
      .def_property_readonly("format", [](const PyDataset& d) { return d.reader->format(); })
      .def_property_readonly("root", [](const PyDataset& d) { return d.reader->root(); })
      .def_property_readonly("has_ground_truth", [](const PyDataset& d) { return d.reader->has_ground_truth(); })
      .def_property_readonly("has_labels", [](const PyDataset& d) { return d.reader->has_label_ground_truth(); })
      .def("ground_truth", [](const PyDataset& d) { return trajectory_to_python(d.reader->ground_truth()); },
           "[(timestamp, (4, 4) T_world_camera)] of the frames with a ground-truth pose")
      .def_property_readonly("timestamps", [](const PyDataset& d) {
        std::vector<double> t;
        for (const FrameRecord& r : d.reader->records()) t.push_back(r.timestamp);
        return t;
      });
  m.def("open_dataset", [](const std::filesystem::path& path) {
    std::unique_ptr<DatasetReader> reader;
    {
      py::gil_scoped_release nogil;
      reader = open_dataset(path);
    }
    return PyDataset{std::move(reader)};
  }, py::arg("path"), "TUM, 7-Scenes, YCB-Video, ScanNet, synthetic folders, ROS1 .bag or ScanNet .sens");
}

}  // namespace semap::python
