#include "pipeline/refresh_archive.hpp"

#include <libdeflate.h>

#include <cmath>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "semap/core/error.hpp"

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

FrameArchive::Packed FrameArchive::pack(const cv::Mat& image) {
  Packed p;
  if (image.empty()) return p;
  const cv::Mat continuous = image.isContinuous() ? image : image.clone();
  p.rows = image.rows;
  p.cols = image.cols;
  p.type = image.type();
  p.raw_bytes = continuous.total() * continuous.elemSize();
  // Level 1: the archive is written on the fusion thread of every frame; speed over ratio.
  std::unique_ptr<libdeflate_compressor, decltype(&libdeflate_free_compressor)> c(libdeflate_alloc_compressor(1),
                                                                                 libdeflate_free_compressor);
  if (!c) throw Error("FrameArchive", "out of memory");
  p.deflated.resize(libdeflate_deflate_compress_bound(c.get(), p.raw_bytes));
  const size_t n = libdeflate_deflate_compress(c.get(), continuous.data, p.raw_bytes, p.deflated.data(), p.deflated.size());
  p.deflated.resize(n);
  p.deflated.shrink_to_fit();
  return p;
}

cv::Mat FrameArchive::unpack(const Packed& p) {
  if (p.raw_bytes == 0) return {};
  cv::Mat image(p.rows, p.cols, p.type);
  std::unique_ptr<libdeflate_decompressor, decltype(&libdeflate_free_decompressor)> d(libdeflate_alloc_decompressor(),
                                                                                     libdeflate_free_decompressor);
  if (!d || libdeflate_deflate_decompress(d.get(), p.deflated.data(), p.deflated.size(), image.data, p.raw_bytes,
                                          nullptr) != LIBDEFLATE_SUCCESS)
    throw Error("FrameArchive", "cannot restore an archived frame");
  return image;
}

bool FrameArchive::store(size_t key, const cv::Mat& depth, const cv::Mat& colour) {
  if (budget_ == 0) return false;
  {
    std::lock_guard lock(mutex_);
    if (bytes_ >= budget_) return false;
  }
  auto packed = std::make_pair(pack(depth), pack(colour));
  const size_t size = packed.first.deflated.size() + packed.second.deflated.size() + 2 * sizeof(Packed);
  std::lock_guard lock(mutex_);
  if (bytes_ + size > budget_) return false;
  bytes_ += size;
  archive_[key] = std::move(packed);
  return true;
}

bool FrameArchive::has(size_t key) const {
  std::lock_guard lock(mutex_);
  return archive_.count(key) > 0;
}

std::pair<cv::Mat, cv::Mat> FrameArchive::load(size_t key) const {
  const std::pair<Packed, Packed>* packed = nullptr;
  {
    std::lock_guard lock(mutex_);
    const auto it = archive_.find(key);
    if (it == archive_.end()) throw Error("FrameArchive", "frame " + std::to_string(key) + " was not archived");
    packed = &it->second;  // entries are never erased: the pointer stays valid
  }
  return {unpack(packed->first), unpack(packed->second)};
}

size_t FrameArchive::bytes() const {
  std::lock_guard lock(mutex_);
  return bytes_;
}

}  // namespace semap
