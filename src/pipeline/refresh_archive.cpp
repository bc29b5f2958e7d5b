#include "pipeline/refresh_archive.hpp"

#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"

namespace semap {

void LabelArchive::store(size_t frame_index, const cv::Mat& labels) {
  if (labels.empty()) return;
  std::vector<uchar> png;
  cv::imencode(".png", labels, png);
  std::lock_guard lock(mutex_);
  archive_[frame_index] = std::move(png);
}

cv::Mat LabelArchive::find(size_t frame_index) const {
  std::lock_guard lock(mutex_);
  const auto it = archive_.find(frame_index);
  return it == archive_.end() ? cv::Mat() : cv::imdecode(it->second, cv::IMREAD_UNCHANGED);
}

size_t LabelArchive::bytes() const {
  std::lock_guard lock(mutex_);
  size_t n = 0;
  for (const auto& [index, png] : archive_) n += png.size();
  return n;
}

RepairArchive::RepairArchive(double depth_scale, size_t budget_bytes)
    : depth_scale_(depth_scale), inv_scale_(static_cast<float>(1.0 / depth_scale)), budget_(budget_bytes) {}

void RepairArchive::store(size_t frame_index, const cv::Mat& decoded, const cv::Mat& repaired) {
  if (budget_ == 0 || decoded.size() != repaired.size() || decoded.type() != CV_32FC1 || repaired.type() != CV_32FC1)
    return;
  Fills fills;
  for (int y = 0; y < decoded.rows; ++y) {
    const float* before = decoded.ptr<float>(y);
    const float* after = repaired.ptr<float>(y);
    for (int x = 0; x < decoded.cols; ++x) {
      if (before[x] == after[x]) continue;
      const double units = std::round(static_cast<double>(after[x]) * depth_scale_);
      if (!(units > 0 && units < 65535)) return;
      const auto value = static_cast<uint16_t>(units);
      if (value * inv_scale_ != after[x]) return;  // would not come back bit-identical
      fills.pixels.push_back(static_cast<uint32_t>(y * decoded.cols + x));
      fills.values.push_back(value);
    }
  }
  const size_t size = fills.pixels.size() * (sizeof(uint32_t) + sizeof(uint16_t)) + sizeof(Fills) + 64;
  std::lock_guard lock(mutex_);
  if (bytes_ + size > budget_) return;
  bytes_ += size;
  archive_[frame_index] = std::move(fills);
}

bool RepairArchive::has(size_t frame_index) const {
  std::lock_guard lock(mutex_);
  return archive_.count(frame_index) > 0;
}

void RepairArchive::apply(size_t frame_index, cv::Mat& depth) const {
  std::lock_guard lock(mutex_);
  const auto it = archive_.find(frame_index);
  if (it == archive_.end()) return;
  if (depth.type() != CV_32FC1 || !depth.isContinuous()) throw Error("RepairArchive", "depth must be continuous CV_32FC1");
  float* pixels = depth.ptr<float>();
  const size_t n = depth.total();
  for (size_t k = 0; k < it->second.pixels.size(); ++k)
    if (it->second.pixels[k] < n) pixels[it->second.pixels[k]] = it->second.values[k] * inv_scale_;
}

size_t RepairArchive::bytes() const {
  std::lock_guard lock(mutex_);
  return bytes_;
}

}  // namespace semap
