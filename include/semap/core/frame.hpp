#pragma once
// The one frame type that flows from dataset readers into the stages.
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "semap/core/pose.hpp"

namespace semap {

struct Frame {
  size_t index = 0;          ///< position in the sequence (0-based, after skipped frames)
  double timestamp = 0.0;    ///< seconds
  cv::Mat rgb;               ///< CV_8UC3, BGR (OpenCV order), colour-camera resolution
  cv::Mat depth;             ///< CV_32FC1, metres, 0 = invalid; depth-camera resolution
  cv::Mat labels;            ///< optional CV_8UC1 project class ids (core/labels.hpp), 0 = unlabelled
  cv::Mat instances;         ///< optional CV_16UC1 instance ids, 0 = none
  std::optional<Pose> gt_T_world_camera;  ///< ground truth, for evaluation only
  std::string rgb_path;      ///< source files, for messages
  std::string depth_path;

  bool has_labels() const { return !labels.empty(); }
  bool has_instances() const { return !instances.empty(); }
};

}  // namespace semap
