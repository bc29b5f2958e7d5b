#include "segmentation/registration.hpp"

#include <opencv2/imgproc.hpp>

namespace semap {

bool needs_registration(const CameraModel& camera) {
  if (!camera.colour) return false;
  return !(camera.colour->intrinsics == camera.depth) ||
         !camera.colour->T_depth_colour.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12);
}

cv::Mat colour_lookup_map(const cv::Mat& depth_m, const CameraModel& camera) {
  CV_Assert(depth_m.type() == CV_32FC1);
  const PinholeIntrinsics& kd = camera.depth;
  const PinholeIntrinsics& kc = camera.colour_intrinsics();
  const Pose T_colour_depth = camera.colour ? camera.colour->T_depth_colour.inverse() : Pose::Identity();
  const Eigen::Matrix3d R = T_colour_depth.linear();
  const Eigen::Vector3d t = T_colour_depth.translation();
  cv::Mat map(depth_m.size(), CV_32FC2, cv::Scalar(-1.f, -1.f));
  cv::parallel_for_(cv::Range(0, depth_m.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const float* z = depth_m.ptr<float>(v);
      cv::Vec2f* out = map.ptr<cv::Vec2f>(v);
      for (int u = 0; u < depth_m.cols; ++u) {
        if (!(z[u] > 0.f) || !std::isfinite(z[u])) continue;
        const Eigen::Vector3d pc = R * kd.backproject(u, v, z[u]) + t;
        if (pc.z() <= 1e-6) continue;
        const Eigen::Vector2d px = kc.project(pc);
        // Pixel centres are integers: keep points whose nearest pixel lies inside the image.
        if (px.x() < -0.5 || px.y() < -0.5 || px.x() > kc.width - 0.5 || px.y() > kc.height - 0.5) continue;
        out[u] = cv::Vec2f(static_cast<float>(px.x()), static_cast<float>(px.y()));
      }
    }
  });
  return map;
}

cv::Mat register_image(const cv::Mat& colour_image, const cv::Mat& lookup_map, int interpolation) {
  cv::Mat out;
  if (colour_image.channels() <= 4) {
    cv::remap(colour_image, out, lookup_map, cv::noArray(), interpolation, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    return out;
  }
  // remap handles at most 4 channels: split the rest.
  std::vector<cv::Mat> planes, registered;
  cv::split(colour_image, planes);
  for (const auto& p : planes) {
    cv::Mat r;
    cv::remap(p, r, lookup_map, cv::noArray(), interpolation, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    registered.push_back(r);
  }
  cv::merge(registered, out);
  return out;
}

SegmentationResult register_result(const SegmentationResult& result, const cv::Mat& lookup_map) {
  SegmentationResult out;
  out.frame_index = result.frame_index;
  out.timestamp = result.timestamp;
  if (!result.labels.empty()) out.labels = register_image(result.labels, lookup_map, cv::INTER_NEAREST);
  if (!result.instance_ids.empty()) out.instance_ids = register_image(result.instance_ids, lookup_map, cv::INTER_NEAREST);
  if (!result.confidence.empty()) out.confidence = register_image(result.confidence, lookup_map, cv::INTER_NEAREST);
  if (!result.probabilities.empty())
    out.probabilities = register_image(result.probabilities, lookup_map, cv::INTER_NEAREST);
  for (const auto& inst : result.instances) {
    InstanceDetection r = inst;
    r.mask = register_image(inst.mask, lookup_map, cv::INTER_NEAREST);
    if (cv::countNonZero(r.mask) == 0) continue;
    r.box = cv::boundingRect(r.mask);
    out.instances.push_back(std::move(r));
  }
  return out;
}

}  // namespace semap
