// Object cards of report.html (issue 43): class, confidence, size and a thumbnail: the crop of
// the keyframe that saw the object best (ObjectSummary::best_view_jpeg), or, for an object
// without one, its own coloured voxels (ObjectSummary::points/colours) seen level from the
// side the camera was on.
#include <algorithm>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pipeline/report.hpp"
#include "semap/core/labels.hpp"

namespace semap {
namespace {

/// Horizontal direction from the object towards the cameras that saw it (mean camera position
/// of the trajectory when none is in its frame range), so the thumbnail shows its visible side.
Eigen::Vector3d view_direction(const ObjectSummary& o, const Eigen::Vector3d& up, const Trajectory& trajectory) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  size_t n = 0;
  for (const auto& p : trajectory) {
    sum += p.T_world_camera.translation();
    ++n;
  }
  Eigen::Vector3d d = n ? Eigen::Vector3d(sum / n - o.centroid.cast<double>()) : Eigen::Vector3d(up.unitOrthogonal());
  d -= up * up.dot(d);
  return d.norm() > 1e-6 ? d.normalized() : up.unitOrthogonal();
}

/// The object's voxels drawn far-to-near as squares on a white square image.
cv::Mat render_object(const ObjectSummary& o, const Eigen::Vector3d& up, const Eigen::Vector3d& towards_camera,
                      int side_px) {
  cv::Mat image(side_px, side_px, CV_8UC3, cv::Scalar(255, 255, 255));
  if (o.points.empty()) return image;
  const Eigen::Vector3d right = up.cross(towards_camera).normalized();
  std::vector<Eigen::Vector3d> uvd;  // right, up, depth towards the camera
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  for (const auto& p : o.points) {
    const Eigen::Vector3d q = p.cast<double>() - o.centroid.cast<double>();
    uvd.emplace_back(right.dot(q), up.dot(q), towards_camera.dot(q));
    lo = lo.cwiseMin(uvd.back().head<2>());
    hi = hi.cwiseMax(uvd.back().head<2>());
  }
  const double extent = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-3});
  const double scale = 0.9 * side_px / extent;
  const Eigen::Vector2d centre = (lo + hi) / 2;
  // Voxels are ~2-5 cm apart: squares a little larger than their spacing close the surface.
  const int dot_px = std::clamp(static_cast<int>(side_px * 0.06), 2, 8);
  std::vector<size_t> order(uvd.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return uvd[a].z() < uvd[b].z(); });
  const Rgb8 fallback = class_colour(o.class_id);
  for (size_t i : order) {
    const int x = static_cast<int>(side_px / 2 + (uvd[i].x() - centre.x()) * scale);
    const int y = static_cast<int>(side_px / 2 - (uvd[i].y() - centre.y()) * scale);
    const Rgb8 c = i < o.colours.size() ? o.colours[i] : fallback;
    cv::rectangle(image, {x - dot_px / 2, y - dot_px / 2}, {x + dot_px / 2, y + dot_px / 2},
                  cv::Scalar(c.b, c.g, c.r), cv::FILLED);
  }
  return image;
}

}  // namespace

std::vector<ObjectCard> object_cards(const std::vector<ObjectSummary>& objects, const Eigen::Vector3d& up_W,
                                     const Trajectory& trajectory, int thumbnail_px) {
  std::vector<ObjectCard> cards;
  for (const ObjectSummary& o : objects) {
    ObjectCard card{o.id, std::string(class_name(o.class_id)), o.confidence, o.box.extent.cast<double>()};
    if (!o.best_view_jpeg.empty()) {
      card.thumbnail = o.best_view_jpeg;
      card.thumbnail_mime = "image/jpeg";
      card.thumbnail_source = ThumbnailSource::camera_crop;
    } else {
      std::vector<uint8_t> png;
      cv::imencode(".png", render_object(o, up_W, view_direction(o, up_W, trajectory), thumbnail_px), png);
      card.thumbnail.assign(png.begin(), png.end());
    }
    cards.push_back(std::move(card));
  }
  std::sort(cards.begin(), cards.end(), [](const ObjectCard& a, const ObjectCard& b) {
    return a.class_name != b.class_name ? a.class_name < b.class_name : a.confidence > b.confidence;
  });
  return cards;
}

}  // namespace semap
