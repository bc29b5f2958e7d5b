#pragma once
// numpy arrays <-> cv::Mat and poses for the Python module (issue 15).
//
// In: share() wraps an array's memory in a cv::Mat without a copy. The Mat holds a reference to
// the array (OpenCV's own cv2 module does the same with a numpy MatAllocator), so the Mapper may
// keep it past add_frame() (keyframes, queues, the refresh archive) on any thread; the last
// release takes the GIL to drop the reference. Consequence: every Mapper call runs with the GIL
// released (a worker freeing a frame needs it).
// Out: view() exposes a Mat or a vector owned by a Python object as an array whose base is that
// object (no copy).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "semap/core/pose.hpp"

namespace semap::python {

namespace py = pybind11;

/// "float64 array of shape (480, 640)" / "list" for messages.
std::string describe(const py::handle& object);

/// Throws ValueError "NAME: expected EXPECTED, got DESCRIPTION".
[[noreturn]] void bad_argument(const std::string& name, const std::string& expected, const py::handle& got);

/// The array's memory as a rows x cols Mat of `type` sharing it (the Mat keeps the array alive).
/// `data` points at element (0, 0); rows are `row_step` bytes apart, pixels are contiguous.
cv::Mat share(const py::array& array, int rows, int cols, int type, void* data, size_t row_step);

/// A 2-D (or H x W x C) view of `mat` whose lifetime is tied to `owner`.
py::array view(const cv::Mat& mat, py::handle owner);

/// 4x4 float64 copy of a pose.
py::array_t<double> pose_to_numpy(const Pose& pose);
/// [(timestamp, (4, 4) T_world_camera), ...].
py::list trajectory_to_python(const Trajectory& trajectory);
/// A 4x4 rigid transform (any real dtype, nested lists too) or ValueError naming `name`.
Pose pose_from_python(const py::handle& object, const std::string& name);

}  // namespace semap::python
