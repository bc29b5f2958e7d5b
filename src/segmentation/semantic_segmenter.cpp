#include "segmentation/semantic_segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "segmentation/onnx_model_info.hpp"

namespace semap {

SemanticSegmenter::SemanticSegmenter(const std::filesystem::path& model_path, const SegmentationConfig& config)
    : model_path_(model_path), config_(config) {
  config_.validate();
  const OnnxModelInfo info = read_onnx_model_info(model_path);
  const auto& s = info.inputs.front().shape;
  if (s.size() != 4) throw Error(model_path, "not an image segmentation model: input must be 4-D");
  if (info.outputs.size() != 1)
    throw Error(model_path, "not a semantic segmentation model: expected 1 output (logits), found " +
                                std::to_string(info.outputs.size()));
  const InputLayout layout = config_.semantic.input_layout;
  // auto: a channel axis of 3 at position 3 (and not at 1) means NHWC.
  nhwc_input_ = layout == InputLayout::nhwc || (layout == InputLayout::automatic && s[3] == 3 && s[1] != 3);
  const int64_t h = nhwc_input_ ? s[1] : s[2], w = nhwc_input_ ? s[2] : s[3];
  input_size_ = {config_.semantic.input_width > 0 ? config_.semantic.input_width : (w > 0 ? int(w) : 513),
                 config_.semantic.input_height > 0 ? config_.semantic.input_height : (h > 0 ? int(h) : 513)};
  net_ = load_onnx_net(model_path);
  if (config_.threads > 0) cv::setNumThreads(config_.threads);
}

SegmentationResult SemanticSegmenter::segment_image(const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3) throw Error(model_path_, "semantic segmenter needs an 8-bit BGR image");
  const auto& sc = config_.semantic;
  cv::Mat blob;
  if (nhwc_input_) {
    cv::Mat resized, rgb, f;
    cv::resize(bgr, resized, input_size_, 0, 0, cv::INTER_LINEAR);
    if (sc.swap_rb) cv::cvtColor(resized, rgb, cv::COLOR_BGR2RGB);
    else rgb = resized;
    rgb.convertTo(f, CV_32F, sc.input_scale, -sc.input_mean * sc.input_scale);
    const int dims[4] = {1, input_size_.height, input_size_.width, 3};
    blob.create(4, dims, CV_32F);
    std::memcpy(blob.ptr<float>(), f.ptr<float>(), sizeof(float) * size_t(f.total()) * 3);
  } else {
    blob = cv::dnn::blobFromImage(bgr, sc.input_scale, input_size_,
                                  cv::Scalar(sc.input_mean, sc.input_mean, sc.input_mean), sc.swap_rb, false, CV_32F);
  }
  cv::Mat out;
  try {
    net_.setInput(blob);
    out = net_.forward().clone();
  } catch (const cv::Exception& e) {
    throw Error(model_path_, std::string("forward pass failed: ") + e.err);
  }
  if (out.dims != 4 || out.size[0] != 1) throw Error(model_path_, "not a semantic segmentation model: output must be 4-D logits");

  // Logit layout: the two axes whose ratio matches the input aspect are spatial; if both
  // readings fit, the class list size decides, else the smaller channel count (classes << pixels).
  const int d1 = out.size[1], d2 = out.size[2], d3 = out.size[3];
  const double aspect = double(input_size_.height) / input_size_.width;
  auto fits = [&](int h, int w) { return std::abs(double(h) / w - aspect) < 0.05; };
  const bool nchw_fits = fits(d2, d3), nhwc_fits = fits(d1, d2);
  bool nhwc_out;
  if (nchw_fits != nhwc_fits) nhwc_out = nhwc_fits;
  else if (num_classes_ > 0) nhwc_out = d3 == num_classes_;
  else nhwc_out = d3 < d1;
  const int nc = nhwc_out ? d3 : d1, oh = nhwc_out ? d1 : d2, ow = nhwc_out ? d2 : d3;
  if (nc != num_classes_) {
    num_classes_ = nc;
    mapping_ = make_class_mapping(config_, nc, model_path_.string(), config_.semantic.class_names_file);
  }
  // Per-pixel softmax over model classes, summed into project classes.
  cv::Mat probs(oh, ow, CV_32FC(kNumClasses), cv::Scalar::all(0));
  const float* logits = out.ptr<float>();
  const size_t plane = size_t(oh) * ow;
  cv::parallel_for_(cv::Range(0, oh), [&](const cv::Range& rows) {
    std::vector<float> e(nc);
    for (int y = rows.start; y < rows.end; ++y) {
      float* p = probs.ptr<float>(y);
      for (int x = 0; x < ow; ++x) {
        const size_t pix = size_t(y) * ow + x;
        float mx = -INFINITY;
        for (int c = 0; c < nc; ++c) {
          e[c] = nhwc_out ? logits[pix * nc + c] : logits[c * plane + pix];
          mx = std::max(mx, e[c]);
        }
        float sum = 0.f;
        for (int c = 0; c < nc; ++c) sum += (e[c] = std::exp(e[c] - mx));
        float* dst = p + size_t(x) * kNumClasses;
        for (int c = 0; c < nc; ++c) dst[mapping_.map(c)] += e[c] / sum;
      }
    }
  });
  SegmentationResult r;
  cv::Mat full;
  if (probs.size() == bgr.size()) full = probs;
  else cv::resize(probs, full, bgr.size(), 0, 0, cv::INTER_LINEAR);
  r.labels.create(bgr.size(), CV_8UC1);
  r.confidence.create(bgr.size(), CV_32FC1);
  const float min_conf = float(sc.min_confidence);
  cv::parallel_for_(cv::Range(0, bgr.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      const float* p = full.ptr<float>(y);
      uint8_t* l = r.labels.ptr<uint8_t>(y);
      float* conf = r.confidence.ptr<float>(y);
      for (int x = 0; x < bgr.cols; ++x) {
        const float* q = p + size_t(x) * kNumClasses;
        const int best = int(std::max_element(q, q + kNumClasses) - q);
        l[x] = q[best] >= min_conf ? uint8_t(best) : 0;
        conf[x] = q[best];
      }
    }
  });
  if (sc.probabilities) r.probabilities = full;
  return r;
}

SegmentationResult SemanticSegmenter::segment(const Frame& frame) {
  SegmentationResult r = segment_image(frame.rgb);
  r.frame_index = frame.index;
  r.timestamp = frame.timestamp;
  return r;
}

}  // namespace semap
