#pragma once
// The arguments of Mapper.add_frame() checked and turned into a semap::Frame + FrameHints.
// Two steps: take_frame_arrays() (GIL held) checks dtypes and shapes and shares the arrays'
// memory (numpy_mat share(): no copy where the layout allows); to_frame() (GIL released)
// does what needs a pass over the pixels: RGB -> BGR, raw depth units -> metres, invalid
// float depth -> 0, label range checks, the caller's segmentation.
#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>
#include <optional>

#include "semap/core/camera.hpp"
#include "semap/mapper.hpp"

namespace semap::python {

struct FrameArrays {
  cv::Mat colour;               ///< CV_8UC3 sharing the caller's array
  bool colour_is_rgb = false;   ///< the memory is in RGB order (converted in to_frame)
  cv::Mat depth;                ///< CV_16UC1 raw units or CV_32FC1 metres, shared
  cv::Mat labels, instances;    ///< CV_8UC1 / CV_16UC1, shared (or empty)
  std::optional<Pose> pose;
  double timestamp = 0.0;
};

/// Throws ValueError naming the argument and what was expected.
FrameArrays take_frame_arrays(const CameraModel& camera, const pybind11::handle& rgb, const pybind11::handle& depth,
                              double timestamp, const pybind11::handle& labels, const pybind11::handle& instances,
                              const pybind11::handle& pose, bool bgr);

/// Needs no GIL. `arrays` keeps the shared Mats (release them with the GIL held).
Frame to_frame(const FrameArrays& arrays, const CameraModel& camera, size_t index, FrameHints& hints);

}  // namespace semap::python
