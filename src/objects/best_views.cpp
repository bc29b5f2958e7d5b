#include "objects/best_views.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unordered_set>

#include "core/archive.hpp"

namespace semap {
namespace {

constexpr size_t kMaxScoredPoints = 400;  ///< points per instance projected to score a view
constexpr size_t kMinVisiblePoints = 8;   ///< fewer visible points: no view
constexpr double kCropMargin = 0.15;      ///< crop border around the visible points, share of the box side
constexpr int kJpegQuality = 85;
constexpr uint32_t kViewsFormat = 1;  ///< kObjectViewsSection layout (best_views.hpp)

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

void BestViews::forget_all_but(const std::vector<ObjectInstance>& instances) {
  std::unordered_set<uint32_t> alive;
  for (const ObjectInstance& o : instances) alive.insert(o.id);
  std::erase_if(views_, [&](const auto& entry) { return !alive.count(entry.first); });
}

void BestViews::update(const std::vector<ObjectInstance>& instances, const Frame& frame, const Pose& T_world_camera) {
  forget_all_but(instances);
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
    if (jpeg.empty() || jpeg.size() > kBestViewMaxJpegBytes) continue;
    kept = {score, frame.index, std::move(jpeg)};
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

std::string BestViews::encode(const std::vector<ObjectInstance>& instances) const {
  // Only the views of saved objects: a file the reader (decode) refuses is never written.
  std::vector<uint32_t> ids;
  for (const ObjectInstance& o : instances)
    if (views_.count(o.id)) ids.push_back(o.id);
  std::sort(ids.begin(), ids.end());
  ByteWriter w;
  w.put(kViewsFormat);
  w.put(static_cast<uint64_t>(ids.size()));
  for (const uint32_t id : ids) {
    const View& view = views_.at(id);
    w.put(id), w.put(view.score), w.put(view.keyframe_index);
    w.put_string(view.jpeg);
  }
  return std::move(w.bytes());
}

void BestViews::decode(std::string_view bytes, const std::filesystem::path& path,
                       const std::vector<uint32_t>& alive_ids) {
  ByteReader r(bytes, path, kObjectViewsSection);
  const uint32_t format = r.get<uint32_t>();
  if (format != kViewsFormat)
    r.fail("object views format " + std::to_string(format) + ", this build reads " + std::to_string(kViewsFormat));
  const std::unordered_set<uint32_t> alive(alive_ids.begin(), alive_ids.end());
  constexpr size_t kMinViewBytes = 4 + 8 + 8 + 8;
  const size_t count = r.get_count(kMinViewBytes);  // bounded by the bytes there, before any allocation
  std::unordered_map<uint32_t, View> views;
  uint32_t previous_id = 0;
  for (size_t i = 0; i < count; ++i) {
    const uint32_t id = r.get<uint32_t>();
    if (id <= previous_id) r.fail("object view ids are not ascending");
    if (!alive.count(id)) r.fail("a view of object " + std::to_string(id) + ", which the object map does not hold");
    previous_id = id;
    View view;
    view.score = r.get<double>();
    if (!std::isfinite(view.score) || view.score <= 0.0) r.fail("a view's score is not a positive number");
    view.keyframe_index = r.get<uint64_t>();
    const uint64_t jpeg_bytes = r.get<uint64_t>();
    if (jpeg_bytes > kBestViewMaxJpegBytes)
      r.fail("a view of " + std::to_string(jpeg_bytes) + " bytes (at most " + std::to_string(kBestViewMaxJpegBytes) +
             ")");
    const std::string_view jpeg = r.get_view(static_cast<size_t>(jpeg_bytes));
    // SOI ... EOI: what cv::imencode writes; the report embeds the bytes as they are.
    if (jpeg.size() < 4 || !jpeg.starts_with("\xFF\xD8") || !jpeg.ends_with("\xFF\xD9")) r.fail("a view is not a JPEG");
    view.jpeg = std::string(jpeg);
    views.emplace(id, std::move(view));
  }
  r.expect_end();
  views_ = std::move(views);
}

void BestViews::merge(const BestViews& other, const std::unordered_map<uint32_t, uint32_t>& ids) {
  // In id order: two of its objects may fold into one here, and ties must not depend on hashing.
  std::vector<std::pair<uint32_t, const View*>> others;
  for (const auto& [other_id, view] : other.views_) others.emplace_back(other_id, &view);
  std::sort(others.begin(), others.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [other_id, view] : others) {
    const auto it = ids.find(other_id);
    if (it == ids.end()) continue;
    View& kept = views_[it->second];
    if (view->score > kept.score) kept = *view;
  }
}

}  // namespace semap
