#include "numpy_mat.hpp"

#include <cmath>

namespace semap::python {
namespace {

/// Mats made by share(): their UMatData holds a reference to the numpy array (userdata).
class NumpyAllocator final : public cv::MatAllocator {
 public:
  // Mats created (not wrapped) with this allocator get ordinary memory.
  cv::UMatData* allocate(int dims, const int* sizes, int type, void* data, size_t* step, cv::AccessFlag flags,
                         cv::UMatUsageFlags usage) const override {
    return cv::Mat::getStdAllocator()->allocate(dims, sizes, type, data, step, flags, usage);
  }
  bool allocate(cv::UMatData* u, cv::AccessFlag flags, cv::UMatUsageFlags usage) const override {
    return cv::Mat::getStdAllocator()->allocate(u, flags, usage);
  }
  void deallocate(cv::UMatData* u) const override {
    if (!u || u->refcount != 0 || u->urefcount != 0) return;
    auto* array = static_cast<PyObject*>(u->userdata);
    delete u;
    // At interpreter exit the GIL cannot be taken from another thread: the reference is left.
    if (!array || !Py_IsInitialized() || _Py_IsFinalizing()) return;
    const PyGILState_STATE state = PyGILState_Ensure();
    Py_DECREF(array);
    PyGILState_Release(state);
  }
};

NumpyAllocator& numpy_allocator() {
  static NumpyAllocator allocator;
  return allocator;
}

py::dtype dtype_of(int depth) {
  switch (depth) {
    case CV_8U: return py::dtype::of<uint8_t>();
    case CV_16U: return py::dtype::of<uint16_t>();
    case CV_32S: return py::dtype::of<int32_t>();
    case CV_32F: return py::dtype::of<float>();
    case CV_64F: return py::dtype::of<double>();
    default: throw std::invalid_argument("semap: no numpy dtype for OpenCV depth " + std::to_string(depth));
  }
}

}  // namespace

std::string describe(const py::handle& object) {
  if (!py::isinstance<py::array>(object)) return std::string(Py_TYPE(object.ptr())->tp_name);
  const auto array = py::reinterpret_borrow<py::array>(object);
  std::string shape;
  for (py::ssize_t i = 0; i < array.ndim(); ++i)
    shape += (i ? ", " : "") + std::to_string(array.shape(i));
  if (array.ndim() == 1) shape += ",";
  return py::str(array.dtype()).cast<std::string>() + " array of shape (" + shape + ")";
}

void bad_argument(const std::string& name, const std::string& expected, const py::handle& got) {
  throw py::value_error(name + ": expected " + expected + ", got " + describe(got));
}

cv::Mat share(const py::array& array, int rows, int cols, int type, void* data, size_t row_step) {
  auto* u = new cv::UMatData(&numpy_allocator());
  u->data = u->origdata = static_cast<uchar*>(data);
  u->size = row_step * static_cast<size_t>(rows);
  u->userdata = array.inc_ref().ptr();
  cv::Mat mat(rows, cols, type, data, row_step);
  mat.u = u;
  mat.addref();
  mat.allocator = &numpy_allocator();
  return mat;
}

py::array view(const cv::Mat& mat, py::handle owner) {
  CV_Assert(mat.dims == 2);
  const auto rows = static_cast<py::ssize_t>(mat.rows), cols = static_cast<py::ssize_t>(mat.cols);
  const auto elem = static_cast<py::ssize_t>(mat.elemSize()), elem1 = static_cast<py::ssize_t>(mat.elemSize1());
  const auto step = static_cast<py::ssize_t>(mat.step[0]);
  if (mat.channels() == 1) return py::array(dtype_of(mat.depth()), {rows, cols}, {step, elem}, mat.data, owner);
  return py::array(dtype_of(mat.depth()), {rows, cols, static_cast<py::ssize_t>(mat.channels())},
                   {step, elem, elem1}, mat.data, owner);
}

py::array_t<double> pose_to_numpy(const Pose& pose) {
  py::array_t<double> out({4, 4});
  auto m = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = pose.matrix()(r, c);
  return out;
}

py::list trajectory_to_python(const Trajectory& trajectory) {
  py::list out;
  for (const StampedPose& p : trajectory) out.append(py::make_tuple(p.timestamp, pose_to_numpy(p.T_world_camera)));
  return out;
}

Pose pose_from_python(const py::handle& object, const std::string& name) {
  const std::string expected = "a rigid 4x4 transform T_world_camera (float array of shape (4, 4))";
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
  if (!array || array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4) bad_argument(name, expected, object);
  Pose pose = Pose::Identity();
  const auto m = array.unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      if (!std::isfinite(m(r, c))) throw py::value_error(name + ": NaN or Inf in the pose");
      pose.matrix()(r, c) = m(r, c);
    }
  const bool bottom_row = m(3, 0) == 0 && m(3, 1) == 0 && m(3, 2) == 0 && m(3, 3) == 1;
  // The Mapper's own tolerance (src/pipeline/mapper.cpp locate()).
  if (!bottom_row || !is_valid_pose(pose, 1e-4))
    throw py::value_error(name + ": not a rigid transform (rotation must be orthonormal with det +1, last row "
                                 "0 0 0 1)");
  return pose;
}

}  // namespace semap::python
