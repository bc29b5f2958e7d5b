#pragma once
#include <string>
#include <vector>

#include "core/params.hpp"

namespace semap {

/// YOLO-seg (YOLOv8/YOLO11 ONNX export) decoding and NMS parameters (METHODS.md C1).
struct YoloConfig {
  int input_size = 0;              ///< square network input; 0 = read from the ONNX graph (fallback 640)
  double input_scale = 1.0 / 255;  ///< network value = (pixel - input_mean) * input_scale
  double input_mean = 0.0;
  bool swap_rb = true;             ///< the model wants RGB (OpenCV images are BGR)
  int pad_value = 114;             ///< letterbox padding grey value
  double score_threshold = 0.25;   ///< candidates under this class score are not considered
  int max_candidates = 300;        ///< best candidates passed to NMS
  std::string nms = "soft";        ///< "soft" (Gaussian Soft-NMS, METHODS C1) or "hard"
  double nms_iou = 0.5;            ///< hard NMS: suppress boxes with IoU above this
  double soft_nms_sigma = 0.5;     ///< Soft-NMS: s_i *= exp(-IoU^2 / sigma)
  double score_floor = 0.25;       ///< Soft-NMS: boxes whose decayed score drops under this are removed
  bool class_agnostic_nms = false; ///< suppress across classes (false: only within a class)
  int max_detections = 100;        ///< per frame, after NMS
  double mask_threshold = 0.5;     ///< mask pixel is on when sigmoid(coeffs . protos) > this
  int min_mask_pixels = 20;        ///< instances with fewer mask pixels are dropped

  void visit(ParamVisitor& v) {
    v.param("input_size", input_size, "px", "square network input; 0 = read from the ONNX graph input shape (640 when dynamic)");
    v.param("input_scale", input_scale, "", "network value = (pixel - input_mean) * input_scale");
    v.param("input_mean", input_mean, "grey", "subtracted from 0..255 pixel values before scaling");
    v.param("swap_rb", swap_rb, "", "feed RGB (true) or BGR (false)");
    v.param("pad_value", pad_value, "grey", "letterbox padding value");
    v.param("score_threshold", score_threshold, "", "minimum class score of a candidate before NMS");
    v.param("max_candidates", max_candidates, "", "best-scoring candidates passed to NMS");
    v.param("nms", nms, "", "soft (Gaussian Soft-NMS, METHODS C1) or hard");
    v.param("nms_iou", nms_iou, "", "hard NMS: IoU above which the lower box is removed");
    v.param("soft_nms_sigma", soft_nms_sigma, "", "Soft-NMS decay s *= exp(-IoU^2/sigma)");
    v.param("score_floor", score_floor, "", "Soft-NMS: decayed scores under this are removed");
    v.param("class_agnostic_nms", class_agnostic_nms, "", "suppress across classes instead of within each class");
    v.param("max_detections", max_detections, "", "instances kept per frame after NMS");
    v.param("mask_threshold", mask_threshold, "", "mask probability above which a pixel belongs to the instance");
    v.param("min_mask_pixels", min_mask_pixels, "px", "instances with smaller masks are dropped");
  }
  void validate() const {
    require_param(input_size == 0 || (input_size >= 32 && input_size % 32 == 0), "segmentation.yolo.input_size",
                  "must be 0 or a multiple of 32");
    require_param(input_scale > 0, "segmentation.yolo.input_scale", "must be > 0");
    require_param(pad_value >= 0 && pad_value <= 255, "segmentation.yolo.pad_value", "must be in [0, 255]");
    require_param(score_threshold >= 0 && score_threshold < 1, "segmentation.yolo.score_threshold", "must be in [0, 1)");
    require_param(max_candidates >= 1, "segmentation.yolo.max_candidates", "must be >= 1");
    require_param(nms == "soft" || nms == "hard", "segmentation.yolo.nms", "must be soft or hard");
    require_param(nms_iou > 0 && nms_iou <= 1, "segmentation.yolo.nms_iou", "must be in (0, 1]");
    require_param(soft_nms_sigma > 0, "segmentation.yolo.soft_nms_sigma", "must be > 0");
    require_param(score_floor >= 0 && score_floor < 1, "segmentation.yolo.score_floor", "must be in [0, 1)");
    require_param(max_detections >= 1, "segmentation.yolo.max_detections", "must be >= 1");
    require_param(mask_threshold > 0 && mask_threshold < 1, "segmentation.yolo.mask_threshold", "must be in (0, 1)");
    require_param(min_mask_pixels >= 0, "segmentation.yolo.min_mask_pixels", "must be >= 0");
  }
};

/// Semantic segmentation ONNX model (METHODS.md A5): logits NCHW or NHWC.
struct SemanticModelConfig {
  int input_width = 0;              ///< 0 = read from the ONNX graph (fallback 513)
  int input_height = 0;
  std::string input_layout = "auto";  ///< auto (from the graph input shape) | nchw | nhwc
  double input_scale = 1.0 / 127.5;   ///< network value = (pixel - input_mean) * input_scale
  double input_mean = 127.5;
  bool swap_rb = true;                ///< the model wants RGB
  bool probabilities = true;          ///< fill SegmentationResult::probabilities (CV_32FC(kNumClasses))
  double min_confidence = 0.0;        ///< pixels whose top probability is below stay unlabelled

  void visit(ParamVisitor& v) {
    v.param("input_width", input_width, "px", "network input width; 0 = from the ONNX graph (513 when dynamic)");
    v.param("input_height", input_height, "px", "network input height; 0 = from the ONNX graph");
    v.param("input_layout", input_layout, "", "auto (from the graph input shape), nchw or nhwc");
    v.param("input_scale", input_scale, "", "network value = (pixel - input_mean) * input_scale");
    v.param("input_mean", input_mean, "grey", "subtracted from 0..255 pixel values before scaling");
    v.param("swap_rb", swap_rb, "", "feed RGB (true) or BGR (false)");
    v.param("probabilities", probabilities, "", "output per-pixel project class probabilities (for Bayesian fusion, METHODS A6)");
    v.param("min_confidence", min_confidence, "", "pixels whose top class probability is below stay unlabelled");
  }
  void validate() const {
    require_param(input_width >= 0 && input_height >= 0, "segmentation.semantic.input_width", "must be >= 0");
    require_param(input_layout == "auto" || input_layout == "nchw" || input_layout == "nhwc",
                  "segmentation.semantic.input_layout", "must be auto, nchw or nhwc");
    require_param(input_scale > 0, "segmentation.semantic.input_scale", "must be > 0");
    require_param(min_confidence >= 0 && min_confidence < 1, "segmentation.semantic.min_confidence", "must be in [0, 1)");
  }
};

/// Temporal label filter (METHODS.md B1).
struct TemporalFilterConfig {
  std::string method = "none";          ///< none | seed (same pixel, previous frames) | warped (reprojected)
  int window = 5;                       ///< frames compared: current + window-1 previous
  int min_agree = 4;                    ///< previous frames that must give the same label (seed: window-1)
  int min_views = 2;                    ///< warped: also keep when all previous frames seeing the point agree and >= this many see it
  double depth_tolerance_m = 0.03;      ///< warped: |z_warped - z_previous| allowed, absolute part
  double depth_tolerance_rel = 0.03;    ///< warped: relative part (times depth)

  void visit(ParamVisitor& v) {
    v.param("method", method, "", "none, seed (label kept if the previous frames gave the same pixel the same label) or warped (previous labels reprojected with depth + pose)");
    v.param("window", window, "frames", "current frame plus window-1 previous ones");
    v.param("min_agree", min_agree, "frames", "previous frames that must agree (the seed: window-1); warped: among those that see the point");
    v.param("min_views", min_views, "frames", "warped: also keep a label when every previous frame that sees the point agrees and at least this many see it");
    v.param("depth_tolerance_m", depth_tolerance_m, "m", "warped: occlusion test, absolute depth tolerance");
    v.param("depth_tolerance_rel", depth_tolerance_rel, "", "warped: occlusion test, tolerance per metre of depth");
  }
  void validate() const {
    require_param(method == "none" || method == "seed" || method == "warped", "segmentation.temporal.method",
                  "must be none, seed or warped");
    require_param(window >= 1 && window <= 32, "segmentation.temporal.window", "must be in [1, 32]");
    require_param(min_agree >= 0 && min_agree <= window - 1, "segmentation.temporal.min_agree", "must be in [0, window-1]");
    require_param(min_views >= 1 && min_views <= window, "segmentation.temporal.min_views", "must be in [1, window]");
    require_param(depth_tolerance_m >= 0 && depth_tolerance_rel >= 0, "segmentation.temporal.depth_tolerance_m",
                  "must be >= 0");
  }
};

/// Parameters of segmentation (METHODS.md C1, A5, B1, B2).
struct SegmentationConfig {
  std::string segmenter = "none";  ///< yolo:PATH | semantic:PATH | groundtruth | precomputed:DIR | none
  int every_n_frames = 5;          ///< run the network on every N-th frame (and on keyframes)
  bool on_keyframes = true;        ///< also run on tracking keyframes
  int async_queue_size = 1;        ///< frames waiting for the network; when full the OLDEST waiting one is dropped
  std::string class_names_file;    ///< model class names, one a line; empty = built-in COCO-80 / VOC-21 by class count
  std::vector<std::string> class_map;  ///< extra "model_name=project_name" entries, override the built-in mapping
  bool register_to_depth = true;   ///< with a separate colour camera, resample results to depth pixels (METHODS B2)
  int threads = 0;                 ///< cv::setNumThreads for the network (process-wide); 0 = leave as is
  YoloConfig yolo;
  SemanticModelConfig semantic;
  TemporalFilterConfig temporal;

  void visit(ParamVisitor& v) {
    v.param("segmenter", segmenter, "", "yolo:PATH, semantic:PATH, groundtruth, precomputed:DIR or none");
    v.param("every_n_frames", every_n_frames, "frames", "run the network on every N-th frame");
    v.param("on_keyframes", on_keyframes, "", "also run the network on tracking keyframes");
    v.param("async_queue_size", async_queue_size, "frames", "frames waiting for the network thread; when full the oldest waiting frame is dropped");
    v.param("class_names_file", class_names_file, "path", "model class names, one a line (index = model class id); empty: built-in COCO-80 (80 classes) or VOC-21 (21 classes)");
    v.param("class_map", class_map, "", "comma-separated model_name=project_name overrides of the class mapping");
    v.param("register_to_depth", register_to_depth, "", "resample labels/masks to depth pixels when the colour camera is separate (METHODS B2)");
    v.param("threads", threads, "", "cv::setNumThreads when a network segmenter is created (process-wide); 0 = leave OpenCV's setting");
    v.section("yolo", "YOLO-seg ONNX instance segmentation (METHODS C1)", [&](ParamVisitor& s) { yolo.visit(s); });
    v.section("semantic", "semantic segmentation ONNX model (METHODS A5)", [&](ParamVisitor& s) { semantic.visit(s); });
    v.section("temporal", "temporal label filter (METHODS B1)", [&](ParamVisitor& s) { temporal.visit(s); });
  }
  void validate() const {
    require_param(every_n_frames >= 1, "segmentation.every_n_frames", "must be >= 1");
    require_param(async_queue_size >= 1, "segmentation.async_queue_size", "must be >= 1");
    require_param(threads >= 0, "segmentation.threads", "must be >= 0");
    for (const auto& entry : class_map)
      require_param(entry.empty() || entry.find('=') != std::string::npos, "segmentation.class_map",
                    "entries must read model_name=project_name");
    yolo.validate();
    semantic.validate();
    temporal.validate();
  }
};

}  // namespace semap
