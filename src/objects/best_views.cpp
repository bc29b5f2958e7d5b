#include "objects/best_views.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unordered_set>

namespace semap {
namespace {

constexpr size_t kMaxScoredPoints = 400;  ///< points per instance projected to score a view
constexpr size_t kMinVisiblePoints = 8;   ///< fewer visible points: no view
constexpr double kCropMargin = 0.15;      ///< crop border around the visible points, share of the box side
constexpr int kJpegQuality = 85;

/// The pixel box of the instance's points visible in this frame and their share of the points.
struct Visibility {
  cv::Rect2d box;
  double visible_share = 0.0;
  size_t visible = 0;
};

/// A point is seen when it projects inside the image in front of the camera and the measured
/// depth there is the point's own (within a few voxels), not a nearer surface hiding it.
Visibility visibility(const ObjectInstance& instance, const cv::Mat& depth_m, const Pose& T_camera_world,
                      const PinholeIntrinsics& camera) {
  Visibility v;
  const size_t n = instance.points.size(), stride = std::max<size_t>(1, n / kMaxScoredPoints);
  double u_lo = 1e9, v_lo = 1e9, u_hi = -1e9, v_hi = -1e9;
  size_t scored = 0;
  for (size_t i = 0; i < n; i += stride, ++scored) {
    const Eigen::Vector3d p = T_camera_world * instance.points[i].cast<double>();
    if (p.z() < 0.1) continue;
    const Eigen::Vector2d px = camera.project(p);
    if (!camera.in_image(px.x(), px.y())) continue;
    const float measured = depth_m.at<float>(static_cast<int>(px.y()), static_cast<int>(px.x()));
    if (!(measured > 0.f) || std::abs(measured - p.z()) > std::max(0.05, 0.03 * p.z())) continue;
    ++v.visible;
    u_lo = std::min(u_lo, px.x()), u_hi = std::max(u_hi, px.x());
    v_lo = std::min(v_lo, px.y()), v_hi = std::max(v_hi, px.y());
  }
  if (v.visible == 0) return v;
  v.box = cv::Rect2d(u_lo, v_lo, u_hi - u_lo + 1, v_hi - v_lo + 1);
  v.visible_share = static_cast<double>(v.visible) / static_cast<double>(std::max<size_t>(1, scored));
  return v;
}

/// The crop of `box` (depth pixels) with a margin, from the colour image, scaled down to fit
/// kBestViewMaxSidePx, as JPEG.
std::string encode_crop(const cv::Mat& rgb, const cv::Rect2d& box, const PinholeIntrinsics& camera) {
  const double sx = static_cast<double>(rgb.cols) / camera.width, sy = static_cast<double>(rgb.rows) / camera.height;
  const double margin = kCropMargin * std::max(box.width, box.height);
  cv::Rect crop(static_cast<int>((box.x - margin) * sx), static_cast<int>((box.y - margin) * sy),
                static_cast<int>((box.width + 2 * margin) * sx), static_cast<int>((box.height + 2 * margin) * sy));
  crop &= cv::Rect(0, 0, rgb.cols, rgb.rows);
  if (crop.width < 2 || crop.height < 2) return {};
  cv::Mat image = rgb(crop);
  const double scale = std::min(1.0, static_cast<double>(kBestViewMaxSidePx) / std::max(crop.width, crop.height));
  if (scale < 1.0) cv::resize(image, image, {}, scale, scale, cv::INTER_AREA);
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, kJpegQuality});
  return {jpeg.begin(), jpeg.end()};
}

}  // namespace

void BestViews::update(const std::vector<ObjectInstance>& instances, const Frame& frame, const Pose& T_world_camera) {
  std::unordered_set<uint32_t> alive;
  for (const ObjectInstance& o : instances) alive.insert(o.id);
  std::erase_if(views_, [&](const auto& entry) { return !alive.count(entry.first); });
  if (frame.rgb.empty() || frame.depth.type() != CV_32FC1 || frame.depth.cols != camera_.width ||
      frame.depth.rows != camera_.height)
    return;
  const Pose T_camera_world = T_world_camera.inverse();
  for (const ObjectInstance& o : instances) {
    const Visibility v = visibility(o, frame.depth, T_camera_world, camera_);
    if (v.visible < kMinVisiblePoints) continue;
    const double score = v.box.area() * v.visible_share;
    View& kept = views_[o.id];
    if (score <= kept.score) continue;
    std::string jpeg = encode_crop(frame.rgb, v.box, camera_);
    if (jpeg.empty()) continue;
    kept = {score, std::move(jpeg)};
  }
}

std::string BestViews::jpeg(uint32_t id) const {
  const auto it = views_.find(id);
  return it == views_.end() ? std::string() : it->second.jpeg;
}

size_t BestViews::bytes() const {
  size_t n = 0;
  for (const auto& [id, view] : views_) n += view.jpeg.size();
  return n;
}

}  // namespace semap
