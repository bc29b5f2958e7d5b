#include "segmentation/temporal_filter.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"

namespace semap {

TemporalLabelFilter::TemporalLabelFilter(const TemporalFilterConfig& config, const PinholeIntrinsics& intrinsics)
    : config_(config), intrinsics_(intrinsics) {
  config_.validate();
}

cv::Mat TemporalLabelFilter::keep_mask_seed(const cv::Mat& labels) const {
  cv::Mat agree = cv::Mat::zeros(labels.size(), CV_8UC1);
  for (const Past& p : history_) agree += (p.labels == labels) / 255;
  return (agree >= config_.min_agree) & (labels > 0);
}

cv::Mat TemporalLabelFilter::keep_mask_warped(const cv::Mat& labels, const cv::Mat& depth,
                                              const Pose& T_world_camera) const {
  cv::Mat keep = cv::Mat::zeros(labels.size(), CV_8UC1);
  // Current camera -> each previous camera.
  std::vector<Eigen::Matrix3f> R;
  std::vector<Eigen::Vector3f> t;
  for (const Past& p : history_) {
    const Pose T_prev_cur = p.T_world_camera.inverse() * T_world_camera;
    R.push_back(T_prev_cur.linear().cast<float>());
    t.push_back(T_prev_cur.translation().cast<float>());
  }
  const PinholeIntrinsics& k = intrinsics_;
  const float tol_abs = float(config_.depth_tolerance_m), tol_rel = float(config_.depth_tolerance_rel);
  cv::parallel_for_(cv::Range(0, labels.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const uint8_t* l = labels.ptr<uint8_t>(v);
      const float* z = depth.ptr<float>(v);
      uint8_t* out = keep.ptr<uint8_t>(v);
      for (int u = 0; u < labels.cols; ++u) {
        if (!l[u] || !(z[u] > 0.f)) continue;
        const Eigen::Vector3f pc = k.backproject(u, v, z[u]).cast<float>();
        int agree = 0, disagree = 0;
        for (size_t f = 0; f < history_.size(); ++f) {
          const Eigen::Vector3f q = R[f] * pc + t[f];
          if (q.z() <= 1e-4f) continue;
          const int pu = int(std::lround(k.fx * q.x() / q.z() + k.cx));
          const int pv = int(std::lround(k.fy * q.y() / q.z() + k.cy));
          const Past& p = history_[f];
          if (pu < 0 || pv < 0 || pu >= p.labels.cols || pv >= p.labels.rows) continue;
          const float dz = p.depth.at<float>(pv, pu);
          if (!(dz > 0.f) || std::abs(dz - q.z()) > tol_abs + tol_rel * q.z()) continue;  // occluded / no depth
          (p.labels.at<uint8_t>(pv, pu) == l[u] ? agree : disagree)++;
        }
        const bool keep = agree >= config_.min_agree || (disagree == 0 && agree >= config_.min_views);
        out[u] = keep ? 255 : 0;
      }
    }
  });
  return keep;
}

cv::Mat TemporalLabelFilter::apply(const cv::Mat& labels, const cv::Mat& depth, const Pose& T_world_camera) {
  if (labels.type() != CV_8UC1) throw Error("temporal label filter", "labels must be CV_8UC1");
  if (config_.method == TemporalMethod::none) return labels.clone();
  const bool warped = config_.method == TemporalMethod::warped;
  if (warped && (depth.type() != CV_32FC1 || depth.size() != labels.size()))
    throw Error("temporal label filter", "warped filter needs CV_32FC1 depth of the label image's size");
  if (!history_.empty() && history_.front().labels.size() != labels.size()) history_.clear();
  cv::Mat keep = warped ? keep_mask_warped(labels, depth, T_world_camera) : keep_mask_seed(labels);
  cv::Mat out = cv::Mat::zeros(labels.size(), CV_8UC1);
  labels.copyTo(out, keep);
  history_.push_front({labels.clone(), warped ? depth.clone() : cv::Mat(), T_world_camera});
  while (int(history_.size()) > config_.window - 1) history_.pop_back();
  return out;
}

SegmentationResult TemporalLabelFilter::apply(const SegmentationResult& result, const cv::Mat& depth,
                                              const Pose& T_world_camera) {
  if (result.labels.empty()) return result;
  SegmentationResult out = result;
  out.labels = apply(result.labels, depth, T_world_camera);
  const cv::Mat dropped = (out.labels == 0) & (result.labels > 0);
  if (!out.instance_ids.empty()) {
    out.instance_ids = result.instance_ids.clone();
    out.instance_ids.setTo(0, dropped);
  }
  out.instances.clear();
  for (const auto& inst : result.instances) {
    InstanceDetection r = inst;
    r.mask = inst.mask.clone();
    if (r.mask.size() == dropped.size()) r.mask.setTo(0, dropped);
    if (cv::countNonZero(r.mask) == 0) continue;
    r.box = cv::boundingRect(r.mask);
    out.instances.push_back(std::move(r));
  }
  return out;
}

}  // namespace semap
