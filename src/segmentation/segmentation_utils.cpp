#include "segmentation/segmentation_utils.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"

namespace semap {

cv::Mat letterbox_image(const cv::Mat& image, cv::Size input, int pad_value, Letterbox& t) {
  t.input = input;
  t.scale = std::min(double(input.width) / image.cols, double(input.height) / image.rows);
  const int w = std::clamp(int(std::lround(image.cols * t.scale)), 1, input.width);
  const int h = std::clamp(int(std::lround(image.rows * t.scale)), 1, input.height);
  t.pad_x = int(std::lround((input.width - w) / 2.0 - 0.1));
  t.pad_y = int(std::lround((input.height - h) / 2.0 - 0.1));
  cv::Mat out(input, image.type(), cv::Scalar::all(pad_value));
  cv::Mat resized;
  if (w == image.cols && h == image.rows) resized = image;
  else cv::resize(image, resized, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  resized.copyTo(out(cv::Rect(t.pad_x, t.pad_y, w, h)));
  return out;
}

void paint_instances(SegmentationResult& result, cv::Size size) {
  result.labels = cv::Mat::zeros(size, CV_8UC1);
  result.instance_ids = cv::Mat::zeros(size, CV_16UC1);
  std::vector<size_t> order(result.instances.size());
  std::iota(order.begin(), order.end(), 0);
  // Paint low scores first so the best instance ends on top.
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return result.instances[a].score < result.instances[b].score; });
  for (size_t i : order) {
    const auto& inst = result.instances[i];
    if (inst.mask.empty() || inst.mask.size() != size) continue;
    result.labels.setTo(inst.class_id, inst.mask);
    result.instance_ids.setTo(inst.id, inst.mask);
  }
}

void check_instance_count(size_t count, cv::Size size, const std::string& where) {
  const uint64_t pixels = uint64_t(std::max(size.area(), 1));
  const uint64_t max_count = kMaxInstanceMaskBytes / pixels;
  if (count > max_count)
    throw Error(where, std::to_string(count) + " instances in one " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                           " frame: more than the " + std::to_string(max_count) + " whose masks fit in " +
                           std::to_string(kMaxInstanceMaskBytes >> 20) + " MiB");
}

std::vector<float> one_hot_scores(ClassId c, float score) {
  std::vector<float> s(kNumClasses, 0.f);
  if (c < kNumClasses) s[c] = score;
  return s;
}

}  // namespace semap
