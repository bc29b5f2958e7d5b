#include "tracking/ferns.hpp"

#include <opencv2/imgproc.hpp>
#include <random>

#include "semap/core/error.hpp"

namespace semap {

FernDatabase::FernDatabase(const FernParams& params) : params_(params) {
  if (params.fern_count < 1 || params.fern_tests < 1 || params.fern_tests > 12 || params.width < 2 ||
      params.height < 2)
    throw Error("FernDatabase", "invalid fern parameters");
  std::mt19937 rng(params.seed);
  std::uniform_int_distribution<int> px(0, params.width - 1), py(0, params.height - 1), ch(0, 3);
  std::uniform_real_distribution<float> colour(0.0f, 255.0f);
  std::uniform_real_distribution<float> depth(float(params.min_depth), float(params.max_depth));
  for (int f = 0; f < params.fern_count; ++f) {
    for (int t = 0; t < params.fern_tests; ++t) {
      Test test{px(rng), py(rng), ch(rng), 0.0f};
      test.threshold = test.channel == 3 ? depth(rng) : colour(rng);
      tests_.push_back(test);
    }
  }
  table_.assign(params.fern_count, std::vector<std::vector<int>>(size_t(1) << params.fern_tests));
}

FernCode FernDatabase::encode(const cv::Mat& rgb, const cv::Mat& depth) const {
  if (rgb.type() != CV_8UC3 || depth.type() != CV_32FC1) throw Error("FernDatabase::encode", "need CV_8UC3 rgb and CV_32FC1 depth");
  cv::Mat small_rgb, small_depth;
  const cv::Size size(params_.width, params_.height);
  cv::resize(rgb, small_rgb, size, 0, 0, cv::INTER_AREA);
  // Nearest keeps invalid (0) depth from blending into valid values.
  cv::resize(depth, small_depth, size, 0, 0, cv::INTER_NEAREST);
  cv::GaussianBlur(small_rgb, small_rgb, cv::Size(3, 3), 0);
  FernCode code(params_.fern_count, 0);
  for (int f = 0; f < params_.fern_count; ++f) {
    uint16_t c = 0;
    for (int t = 0; t < params_.fern_tests; ++t) {
      const Test& test = tests_[size_t(f) * params_.fern_tests + t];
      float value;
      if (test.channel == 3) {
        value = small_depth.at<float>(test.y, test.x);
        if (!std::isfinite(value)) value = 0.0f;
      } else {
        value = small_rgb.at<cv::Vec3b>(test.y, test.x)[test.channel];
      }
      if (value >= test.threshold) c |= uint16_t(1u << t);
    }
    code[f] = c;
  }
  return code;
}

void FernDatabase::add(int id, const FernCode& code) {
  if (int(code.size()) != params_.fern_count) throw Error("FernDatabase::add", "code has the wrong fern count");
  const int position = int(ids_.size());
  ids_.push_back(id);
  for (int f = 0; f < params_.fern_count; ++f) table_[f][code[f]].push_back(position);
}

std::vector<double> FernDatabase::similarities(const FernCode& code) const {
  std::vector<double> sim(ids_.size(), 0.0);
  if (int(code.size()) != params_.fern_count) return sim;
  std::vector<int> counts(ids_.size(), 0);
  for (int f = 0; f < params_.fern_count; ++f)
    for (int position : table_[f][code[f]]) ++counts[position];
  for (size_t i = 0; i < counts.size(); ++i) sim[i] = double(counts[i]) / params_.fern_count;
  return sim;
}

double FernDatabase::max_similarity(const FernCode& code) const {
  double best = 0.0;
  for (double s : similarities(code)) best = std::max(best, s);
  return best;
}

}  // namespace semap
