#pragma once
// What the final map refresh needs from the online pass, kept compactly in memory: the
// refresh rebuilds the TSDF with the optimised poses (issue 7) and should neither run the
// segmenter again nor decode colour images and repair depth (METHODS A1) a second time.
#include <cstdint>
#include <map>
#include <mutex>
#include <opencv2/core.hpp>
#include <vector>

namespace semap {

/// Labels of segmented frames, PNG-compressed (bounded memory, no full images kept).
class LabelArchive {
 public:
  void store(size_t frame_index, const cv::Mat& labels);
  /// The labels stored for the frame, or an empty Mat.
  cv::Mat find(size_t frame_index) const;
  size_t bytes() const;

 private:
  mutable std::mutex mutex_;
  std::map<size_t, std::vector<uchar>> archive_;
};

/// The pixels depth repair filled in each frame, in the dataset's 16-bit depth units (a
/// repaired value is a median of decoded values, so it converts back exactly), up to a byte
/// budget. With them a frame's repaired depth is its depth image plus the fills: the colour
/// image is not decoded and the repair not run again. A frame past the budget, or with a fill
/// that would not convert back exactly, is not archived (the caller re-reads and repairs it).
class RepairArchive {
 public:
  RepairArchive(double depth_scale, size_t budget_bytes);
  /// Archives the difference between the decoded and the repaired depth (CV_32FC1, same size).
  void store(size_t frame_index, const cv::Mat& decoded, const cv::Mat& repaired);
  bool has(size_t frame_index) const;
  /// Writes the frame's fills into its freshly decoded depth (CV_32FC1, continuous).
  void apply(size_t frame_index, cv::Mat& depth) const;
  size_t bytes() const;

 private:
  struct Fills {
    std::vector<uint32_t> pixels;
    std::vector<uint16_t> values;  ///< depth units: metres * depth_scale
  };
  double depth_scale_;
  float inv_scale_;  ///< as read_depth_image converts: value * (float)(1 / depth_scale)
  size_t budget_;
  mutable std::mutex mutex_;
  size_t bytes_ = 0;
  std::map<size_t, Fills> archive_;
};

/// Whole frames (the depth fused, after repair, and the colour image) compressed losslessly in
/// memory up to a byte budget: what the refresh uses when the caller gave the Mapper no way to
/// reload its frames (a live camera, a Python loop). A frame past the budget is not archived.
class FrameArchive {
 public:
  explicit FrameArchive(size_t budget_bytes) : budget_(budget_bytes) {}
  /// False when the frame did not fit into the budget (nothing stored).
  bool store(size_t key, const cv::Mat& depth, const cv::Mat& colour);
  bool has(size_t key) const;
  /// The depth (CV_32FC1) and colour (CV_8UC3, or empty) stored under key; throws when absent.
  std::pair<cv::Mat, cv::Mat> load(size_t key) const;
  size_t bytes() const;

 private:
  struct Packed {
    int rows = 0, cols = 0, type = 0;
    size_t raw_bytes = 0;
    std::vector<uint8_t> deflated;
  };
  static Packed pack(const cv::Mat& image);
  static cv::Mat unpack(const Packed& packed);

  size_t budget_;
  mutable std::mutex mutex_;
  size_t bytes_ = 0;
  std::map<size_t, std::pair<Packed, Packed>> archive_;
};

}  // namespace semap
