#include "segmentation/yolo_segmenter.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "segmentation/onnx_model_info.hpp"

namespace semap {
namespace {

// Anchor count of a YOLOv8 head with strides 8, 16, 32.
int anchor_count(cv::Size input) {
  int n = 0;
  for (int s : {8, 16, 32}) n += ((input.width + s - 1) / s) * ((input.height + s - 1) / s);
  return n;
}

}  // namespace

YoloSegmenter::YoloSegmenter(const std::filesystem::path& model_path, const SegmentationConfig& config)
    : model_path_(model_path), config_(config) {
  config_.validate();
  const OnnxModelInfo info = read_onnx_model_info(model_path);
  const auto& in_shape = info.inputs.front().shape;
  if (in_shape.size() != 4 || (in_shape[1] > 0 && in_shape[1] != 3))
    throw Error(model_path, "not a YOLO-seg model: input must be [1,3,H,W]");
  if (info.outputs.size() != 2)
    throw Error(model_path, "not a YOLO-seg model: expected 2 outputs (detections, mask prototypes), found " +
                                std::to_string(info.outputs.size()));
  if (config_.yolo.input_size > 0) {
    input_size_ = {config_.yolo.input_size, config_.yolo.input_size};
  } else {
    input_size_ = {in_shape[3] > 0 ? int(in_shape[3]) : 640, in_shape[2] > 0 ? int(in_shape[2]) : 640};
  }
  net_ = load_onnx_net(model_path);
  output_names_ = net_.getUnconnectedOutLayersNames();
  if (config_.threads > 0) cv::setNumThreads(config_.threads);
  // Class count from the graph's output shape when static, else after the first forward pass.
  for (const auto& out : info.outputs) {
    if (out.shape.size() != 3) continue;
    int nm = -1;
    for (const auto& o : info.outputs)
      if (o.shape.size() == 4 && o.shape[1] > 0) nm = int(o.shape[1]);
    const int64_t c = out.shape[1] > 0 && out.shape[2] > 0 ? std::min(out.shape[1], out.shape[2]) : -1;
    if (nm > 0 && c > 4 + nm) setup_classes(int(c) - 4 - nm);
  }
  spdlog::debug("{}: YOLO-seg input {}x{}, {} classes", model_path.string(), input_size_.width, input_size_.height,
                num_classes_);
}

void YoloSegmenter::setup_classes(int num_classes) {
  if (num_classes == num_classes_) return;
  num_classes_ = num_classes;
  mapping_ = make_class_mapping(config_, num_classes, model_path_.string(), config_.yolo.class_names_file);
}

YoloSegmenter::Candidates YoloSegmenter::run_network(const cv::Mat& bgr) {
  if (bgr.empty() || bgr.type() != CV_8UC3) throw Error(model_path_, "YOLO segmenter needs an 8-bit BGR image");
  Candidates c;
  c.image_size = bgr.size();
  const cv::Mat input = letterbox_image(bgr, input_size_, config_.yolo.pad_value, c.letterbox);
  const double mean = config_.yolo.input_mean;
  cv::Mat blob = cv::dnn::blobFromImage(input, config_.yolo.input_scale, cv::Size(), cv::Scalar(mean, mean, mean),
                                        config_.yolo.swap_rb, false, CV_32F);
  std::vector<cv::Mat> outs;
  try {
    net_.setInput(blob);
    net_.forward(outs, output_names_);
  } catch (const cv::Exception& e) {
    throw Error(model_path_, std::string("forward pass failed: ") + e.err);
  }
  const cv::Mat* det = nullptr;
  const cv::Mat* proto = nullptr;
  for (const auto& o : outs) {
    if (o.dims == 3) det = &o;
    else if (o.dims == 4) proto = &o;
  }
  if (!det || !proto) throw Error(model_path_, "not a YOLO-seg model: outputs are not [1,C,N] + [1,nm,H,W]");
  return candidates_from_outputs(*det, *proto, c.letterbox, c.image_size);
}

YoloSegmenter::Candidates YoloSegmenter::candidates_from_outputs(const cv::Mat& det_tensor, const cv::Mat& proto_tensor,
                                                                 const Letterbox& letterbox, cv::Size image_size) {
  const cv::Mat* det = &det_tensor;
  const cv::Mat* proto = &proto_tensor;
  if (det->dims != 3 || proto->dims != 4 || det->type() != CV_32F || proto->type() != CV_32F)
    throw Error(model_path_, "not a YOLO-seg model: outputs are not float [1,C,N] + [1,nm,H,W]");
  Candidates c;
  c.image_size = image_size;
  c.letterbox = letterbox;
  const int nm = proto->size[1];
  c.proto_size = {proto->size[3], proto->size[2]};
  // Layout: [1, C, N] (Ultralytics default) or [1, N, C]; N matches the stride-8/16/32 anchors.
  const int a = det->size[1], b = det->size[2];
  const int expected_n = anchor_count(letterbox.input);
  const bool channels_first = b == expected_n ? true : a == expected_n ? false : a < b;
  const int channels = channels_first ? a : b, n = channels_first ? b : a;
  if (channels <= 4 + nm) throw Error(model_path_, "not a YOLO-seg model: detection tensor has too few channels");
  setup_classes(channels - 4 - nm);
  const int nc = num_classes_;

  cv::Mat d2(a, b, CV_32F, const_cast<float*>(det->ptr<float>()));
  cv::Mat rows;  // n x channels
  if (channels_first) cv::transpose(d2, rows);
  else rows = d2;

  // Best-scoring anchors over the threshold.
  std::vector<std::pair<float, int>> scored;
  for (int i = 0; i < n; ++i) {
    const float* r = rows.ptr<float>(i);
    const float* s = r + 4;
    const int best = int(std::max_element(s, s + nc) - s);
    if (s[best] >= config_.yolo.score_threshold) scored.push_back({s[best], i});
  }
  std::stable_sort(scored.begin(), scored.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  if (int(scored.size()) > config_.yolo.max_candidates) scored.resize(config_.yolo.max_candidates);

  const Letterbox& lb = c.letterbox;
  c.coefficients.create(int(scored.size()), nm, CV_32F);
  for (size_t k = 0; k < scored.size(); ++k) {
    const float* r = rows.ptr<float>(scored[k].second);
    const float* s = r + 4;
    const int best = int(std::max_element(s, s + nc) - s);
    // Box: input pixels -> image pixels (undo the letterbox), clipped to the image.
    const double x1 = std::clamp((r[0] - r[2] / 2 - lb.pad_x) / lb.scale, 0.0, double(image_size.width));
    const double y1 = std::clamp((r[1] - r[3] / 2 - lb.pad_y) / lb.scale, 0.0, double(image_size.height));
    const double x2 = std::clamp((r[0] + r[2] / 2 - lb.pad_x) / lb.scale, 0.0, double(image_size.width));
    const double y2 = std::clamp((r[1] + r[3] / 2 - lb.pad_y) / lb.scale, 0.0, double(image_size.height));
    c.boxes.push_back({cv::Rect2f(float(x1), float(y1), float(x2 - x1), float(y2 - y1)), s[best], best});
    c.class_scores.emplace_back(s, s + nc);
    std::copy(r + 4 + nc, r + 4 + nc + nm, c.coefficients.ptr<float>(int(k)));
  }
  c.prototypes = cv::Mat(nm, c.proto_size.area(), CV_32F, const_cast<float*>(proto->ptr<float>())).clone();
  return c;
}

SegmentationResult YoloSegmenter::decode(const Candidates& c) {
  const YoloConfig& yc = config_.yolo;
  const std::vector<NmsResult> kept =
      yc.nms == NmsMethod::hard ? hard_nms(c.boxes, yc.nms_iou, yc.class_agnostic_nms, yc.max_detections)
                       : soft_nms(c.boxes, yc.soft_nms_sigma, yc.score_floor, yc.class_agnostic_nms, yc.max_detections);
  SegmentationResult result;
  if (kept.empty()) {
    paint_instances(result, c.image_size);
    return result;
  }
  // Mask logits on the prototype grid: coeffs (k x nm) . protos (nm x HpWp).
  cv::Mat coeffs(int(kept.size()), c.coefficients.cols, CV_32F);
  for (size_t k = 0; k < kept.size(); ++k) c.coefficients.row(kept[k].index).copyTo(coeffs.row(int(k)));
  const cv::Mat logits = coeffs * c.prototypes;
  const Letterbox& lb = c.letterbox;
  const double stride_x = double(lb.input.width) / c.proto_size.width;
  const double stride_y = double(lb.input.height) / c.proto_size.height;
  // sigmoid(x) > t  <=>  x > log(t / (1 - t)).
  const double logit_threshold = std::log(yc.mask_threshold / (1.0 - yc.mask_threshold));
  const cv::Rect image_rect(0, 0, c.image_size.width, c.image_size.height);

  uint16_t next_id = 1;
  for (size_t k = 0; k < kept.size(); ++k) {
    const ScoredBox& sb = c.boxes[kept[k].index];
    const cv::Rect roi = cv::Rect(cv::Point(int(std::floor(sb.box.x)), int(std::floor(sb.box.y))),
                                  cv::Point(int(std::ceil(sb.box.x + sb.box.width)),
                                            int(std::ceil(sb.box.y + sb.box.height)))) & image_rect;
    if (roi.area() <= 0) continue;
    const cv::Mat grid = logits.row(int(k)).reshape(1, c.proto_size.height);
    // Image pixel centre (x + 0.5) -> input coordinate (x + 0.5) * scale + pad -> prototype
    // cell coordinate u / stride - 0.5; only the box is sampled (= crop to the box).
    const double ax = lb.scale / stride_x, ay = lb.scale / stride_y;
    cv::Matx23d to_grid(ax, 0, ax * roi.x + (0.5 * lb.scale + lb.pad_x) / stride_x - 0.5,
                        0, ay, ay * roi.y + (0.5 * lb.scale + lb.pad_y) / stride_y - 0.5);
    cv::Mat roi_logits;
    cv::warpAffine(grid, roi_logits, to_grid, roi.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_REPLICATE);
    cv::Mat roi_mask = roi_logits > logit_threshold;
    const int pixels = cv::countNonZero(roi_mask);
    if (pixels == 0 || pixels < yc.min_mask_pixels) continue;
    InstanceDetection inst;
    inst.id = next_id++;
    inst.class_id = mapping_.map(sb.class_id);
    inst.score = kept[k].score;
    // Model scores are independent sigmoids: a project class takes the max of its model classes.
    inst.class_scores.assign(kNumClasses, 0.f);
    const auto& ms = c.class_scores[kept[k].index];
    for (size_t m = 0; m < ms.size(); ++m) {
      const ClassId p = mapping_.map(int(m));
      inst.class_scores[p] = std::max(inst.class_scores[p], ms[m]);
    }
    inst.mask = cv::Mat::zeros(c.image_size, CV_8UC1);
    roi_mask.copyTo(inst.mask(roi));
    inst.box = cv::boundingRect(roi_mask) + roi.tl();
    result.instances.push_back(std::move(inst));
  }
  paint_instances(result, c.image_size);
  return result;
}

SegmentationResult YoloSegmenter::segment_image(const cv::Mat& bgr) { return decode(run_network(bgr)); }

SegmentationResult YoloSegmenter::segment(const Frame& frame) {
  SegmentationResult r = segment_image(frame.rgb);
  r.frame_index = frame.index;
  r.timestamp = frame.timestamp;
  return r;
}

}  // namespace semap
