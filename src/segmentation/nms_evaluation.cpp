#include "segmentation/nms_evaluation.hpp"

#include <algorithm>
#include <map>
#include <opencv2/imgproc.hpp>
#include <random>

namespace semap {
namespace {

std::map<uint16_t, int> instance_sizes(const cv::Mat& instances) {
  std::map<uint16_t, int> sizes;
  for (int y = 0; y < instances.rows; ++y) {
    const uint16_t* p = instances.ptr<uint16_t>(y);
    for (int x = 0; x < instances.cols; ++x)
      if (p[x]) ++sizes[p[x]];
  }
  return sizes;
}

}  // namespace

CandidateSet jittered_candidates(const cv::Mat& labels, const cv::Mat& instances, const JitterCandidateParams& params) {
  CandidateSet set;
  std::mt19937_64 rng(params.seed);
  std::normal_distribution<double> noise(0.0, params.jitter);
  std::uniform_real_distribution<double> base(params.min_score, params.max_score);
  const cv::Rect image(0, 0, instances.cols, instances.rows);
  for (const auto& [iid, pixels] : instance_sizes(instances)) {
    if (pixels < params.min_pixels) continue;
    const cv::Mat mask = instances == iid;
    const cv::Rect box = cv::boundingRect(mask);
    std::vector<int> hist(256, 0);
    for (int y = box.y; y < box.y + box.height; ++y)
      for (int x = box.x; x < box.x + box.width; ++x)
        if (mask.at<uint8_t>(y, x)) ++hist[labels.at<uint8_t>(y, x)];
    const int cls = int(std::max_element(hist.begin(), hist.end()) - hist.begin());
    const double s0 = base(rng);
    for (int k = 0; k < params.per_instance; ++k) {
      const double dx1 = noise(rng) * box.width, dx2 = noise(rng) * box.width;
      const double dy1 = noise(rng) * box.height, dy2 = noise(rng) * box.height;
      cv::Rect2f jb(float(box.x + dx1), float(box.y + dy1), float(box.width - dx1 + dx2), float(box.height - dy1 + dy2));
      if (jb.width < 2 || jb.height < 2) continue;
      const cv::Rect roi = cv::Rect(jb) & image;
      if (roi.area() <= 0) continue;
      cv::Mat m = cv::Mat::zeros(instances.size(), CV_8UC1);
      mask(roi).copyTo(m(roi));
      const double align = box_iou(jb, cv::Rect2f(box));
      set.boxes.push_back({jb, float(s0 * align), cls});
      set.masks.push_back(std::move(m));
    }
  }
  return set;
}

RecallFigures match_masks(const cv::Mat& instances, const std::vector<cv::Mat>& kept_masks, int min_pixels,
                          double iou_threshold) {
  RecallFigures f;
  f.kept = int(kept_masks.size());
  struct Pair {
    double iou;
    int gt, det;
  };
  std::vector<Pair> pairs;
  std::vector<uint16_t> gt_ids;
  for (const auto& [iid, pixels] : instance_sizes(instances)) {
    if (pixels < min_pixels) continue;
    const cv::Mat g = instances == iid;
    const int gi = int(gt_ids.size());
    gt_ids.push_back(iid);
    for (int d = 0; d < int(kept_masks.size()); ++d) {
      const int inter = cv::countNonZero(g & kept_masks[d]);
      if (!inter) continue;
      const double iou = double(inter) / cv::countNonZero(g | kept_masks[d]);
      if (iou >= iou_threshold) pairs.push_back({iou, gi, d});
    }
  }
  f.ground_truth = int(gt_ids.size());
  std::sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.iou > b.iou; });
  std::vector<bool> gt_used(gt_ids.size(), false), det_used(kept_masks.size(), false);
  for (const Pair& p : pairs) {
    if (gt_used[p.gt] || det_used[p.det]) continue;
    gt_used[p.gt] = det_used[p.det] = true;
    ++f.matched;
  }
  return f;
}

}  // namespace semap
