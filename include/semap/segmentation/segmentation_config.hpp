#pragma once
// Parameters of segmentation (METHODS.md C1, A5, B1, B2). Each parameter's default is its
// member initialiser; its unit, doc and valid range are declared once, in visit().
#include <string>
#include <vector>

#include "semap/core/params.hpp"

namespace semap {

enum class NmsMethod { soft, hard };
inline constexpr EnumNames<NmsMethod, 2> kNmsMethodNames{{{NmsMethod::soft, "soft"}, {NmsMethod::hard, "hard"}}};

/// YOLO-seg (YOLOv8/YOLO11 ONNX export) decoding and NMS parameters (METHODS.md C1).
struct YoloConfig {
  int input_size = 0;
  double input_scale = 1.0 / 255;
  double input_mean = 0.0;
  bool swap_rb = true;  // OpenCV images are BGR; the exported models want RGB
  int pad_value = 114;
  double score_threshold = 0.25;
  int max_candidates = 300;
  NmsMethod nms = NmsMethod::soft;
  double nms_iou = 0.5;
  double soft_nms_sigma = 0.5;
  double score_floor = 0.25;
  bool class_agnostic_nms = false;
  int max_detections = 100;
  double mask_threshold = 0.5;
  int min_mask_pixels = 20;
  std::string class_names_file;

  void visit(ParamVisitor& v) {
    v.param("input_size", input_size, "px", "square network input; 0 = read from the ONNX graph input shape (640 when dynamic)", {0, 4096});
    v.param("input_scale", input_scale, "", "network value = (pixel - input_mean) * input_scale", positive());
    v.param("input_mean", input_mean, "grey", "subtracted from 0..255 pixel values before scaling", {-255.0, 255.0});
    v.param("swap_rb", swap_rb, "", "feed RGB (true) or BGR (false)");
    v.param("pad_value", pad_value, "grey", "letterbox padding value", {0, 255});
    v.param("score_threshold", score_threshold, "", "minimum class score of a candidate before NMS", {0.0, 0.999});
    v.param("max_candidates", max_candidates, "", "best-scoring candidates passed to NMS", {1, 100000});
    v.param("nms", nms, kNmsMethodNames, "soft (Gaussian Soft-NMS, METHODS C1) or hard");
    v.param("nms_iou", nms_iou, "", "hard NMS: IoU above which the lower box is removed", {0.0, 1.0, true});
    v.param("soft_nms_sigma", soft_nms_sigma, "", "Soft-NMS decay s *= exp(-IoU^2/sigma)", positive(100.0));
    v.param("score_floor", score_floor, "", "Soft-NMS: decayed scores under this are removed", {0.0, 0.999});
    v.param("class_agnostic_nms", class_agnostic_nms, "", "suppress across classes instead of within each class");
    v.param("max_detections", max_detections, "", "instances kept per frame after NMS", {1, 10000});
    v.param("mask_threshold", mask_threshold, "", "mask probability above which a pixel belongs to the instance", {0.0, 0.999, true});
    v.param("min_mask_pixels", min_mask_pixels, "px", "instances with smaller masks are dropped", {0, 1 << 24});
    v.param("class_names_file", class_names_file, "path", "this network's class names (wins over segmentation.class_names_file; a panoptic run has two networks)");
  }
  void validate() const {
    check_param_ranges(*this, "segmentation.yolo");
    require_param(input_size == 0 || (input_size >= 32 && input_size % 32 == 0), "segmentation.yolo.input_size",
                  "must be 0 or a multiple of 32");
  }
};

enum class InputLayout { automatic, nchw, nhwc };
inline constexpr EnumNames<InputLayout, 3> kInputLayoutNames{
    {{InputLayout::automatic, "auto"}, {InputLayout::nchw, "nchw"}, {InputLayout::nhwc, "nhwc"}}};

/// Semantic segmentation ONNX model (METHODS.md A5): logits NCHW or NHWC.
struct SemanticModelConfig {
  int input_width = 0;
  int input_height = 0;
  InputLayout input_layout = InputLayout::automatic;
  double input_scale = 1.0 / 127.5;
  double input_mean = 127.5;
  bool swap_rb = true;
  bool probabilities = true;
  double min_confidence = 0.0;
  std::string class_names_file;

  void visit(ParamVisitor& v) {
    v.param("input_width", input_width, "px", "network input width; 0 = from the ONNX graph (513 when dynamic)", {0, 4096});
    v.param("input_height", input_height, "px", "network input height; 0 = from the ONNX graph", {0, 4096});
    v.param("input_layout", input_layout, kInputLayoutNames, "auto (from the graph input shape), nchw or nhwc");
    v.param("input_scale", input_scale, "", "network value = (pixel - input_mean) * input_scale", positive());
    v.param("input_mean", input_mean, "grey", "subtracted from 0..255 pixel values before scaling", {-255.0, 255.0});
    v.param("swap_rb", swap_rb, "", "feed RGB (true) or BGR (false)");
    v.param("probabilities", probabilities, "", "output per-pixel project class probabilities (for Bayesian fusion, METHODS A6)");
    v.param("min_confidence", min_confidence, "", "pixels whose top class probability is below stay unlabelled", {0.0, 0.999});
    v.param("class_names_file", class_names_file, "path", "this network's class names (wins over segmentation.class_names_file; a panoptic run has two networks)");
  }
  void validate() const { check_param_ranges(*this, "segmentation.semantic"); }
};

/// Panoptic segmentation from two networks (issue 38, README "Default models").
struct PanopticConfig {
  double min_instance_score = 0.5;  // measured on redkitchen: README "Default models"
  // The semantic network costs several times the instance network (README "Default models"): on
  // its own, sparser schedule the surfaces still get labels from many views (the camera moves a
  // few cm between frames at 30 Hz) while tracking and the instance network keep their rate.
  int semantic_every_n_frames = 10;
  bool semantic_on_keyframes = true;

  void visit(ParamVisitor& v) {
    v.param("semantic_every_n_frames", semantic_every_n_frames, "frames",
            "run the semantic network on every N-th frame (the instance network follows segmentation.every_n_frames)",
            {1, 1000000});
    v.param("semantic_on_keyframes", semantic_on_keyframes, "", "also run the semantic network on tracking keyframes");
    v.param("min_instance_score", min_instance_score, "",
            "instances at or above this score overwrite the semantic labels inside their masks; weaker ones only "
            "feed the object map", {0.0, 1.0});
  }
  void validate() const { check_param_ranges(*this, "segmentation.panoptic"); }
};

enum class TemporalMethod { none, seed, warped };
inline constexpr EnumNames<TemporalMethod, 3> kTemporalMethodNames{
    {{TemporalMethod::none, "none"}, {TemporalMethod::seed, "seed"}, {TemporalMethod::warped, "warped"}}};

/// Temporal label filter (METHODS.md B1).
struct TemporalFilterConfig {
  TemporalMethod method = TemporalMethod::none;  // by measurement: README "temporal label filter"
  int window = 5;
  int min_agree = 4;
  int min_views = 2;
  double depth_tolerance_m = 0.03;
  double depth_tolerance_rel = 0.03;

  void visit(ParamVisitor& v) {
    v.param("method", method, kTemporalMethodNames, "none, seed (label kept if the previous frames gave the same pixel the same label) or warped (previous labels reprojected with depth + pose)");
    v.param("window", window, "frames", "current frame plus window-1 previous ones", {1, 32});
    v.param("min_agree", min_agree, "frames", "previous frames that must agree (the seed: window-1); warped: among those that see the point", {0, 31});
    v.param("min_views", min_views, "frames", "warped: also keep a label when every previous frame that sees the point agrees and at least this many see it", {1, 32});
    v.param("depth_tolerance_m", depth_tolerance_m, "m", "warped: occlusion test, absolute depth tolerance", non_negative(1.0));
    v.param("depth_tolerance_rel", depth_tolerance_rel, "", "warped: occlusion test, tolerance per metre of depth", non_negative(1.0));
  }
  void validate() const {
    check_param_ranges(*this, "segmentation.temporal");
    require_param(min_agree <= window - 1, "segmentation.temporal.min_agree", "must be in [0, window-1]");
    require_param(min_views <= window, "segmentation.temporal.min_views", "must be in [1, window]");
  }
};

/// What happens to a frame the schedule sends to the network while the network is busy and
/// async_queue_size frames already wait.
enum class WhenBusy {
  wait,         ///< the frame waits for room: nothing the schedule asks for is dropped (recordings)
  drop_oldest,  ///< the oldest waiting frame is dropped: tracking never waits (live cameras)
};
inline constexpr EnumNames<WhenBusy, 2> kWhenBusyNames{{{WhenBusy::wait, "wait"}, {WhenBusy::drop_oldest, "drop_oldest"}}};

struct SegmentationConfig {
  std::string segmenter = "default";  // semap run: the default models when found (issue 38)
  int every_n_frames = 5;
  bool on_keyframes = true;
  int async_queue_size = 1;
  // Recordings by default: maps then do not depend on timing (threads > 1 gives the same
  // objects); `semap run` on a live camera uses drop_oldest.
  WhenBusy when_busy = WhenBusy::wait;
  std::string class_names_file;
  std::vector<std::string> class_map;
  bool register_to_depth = true;
  int threads = 0;
  YoloConfig yolo;
  SemanticModelConfig semantic;
  PanopticConfig panoptic;
  TemporalFilterConfig temporal;

  void visit(ParamVisitor& v) {
    v.param("segmenter", segmenter, "", "yolo:PATH, semantic:PATH, panoptic:SEMANTIC.onnx+INSTANCE.onnx, groundtruth, precomputed:DIR, none (geometry and colour only) or default (semap run: the default models when installed, else none)");
    v.param("every_n_frames", every_n_frames, "frames", "run the network on every N-th frame", {1, 1000000});
    v.param("on_keyframes", on_keyframes, "", "also run the network on tracking keyframes");
    v.param("async_queue_size", async_queue_size, "frames", "frames waiting for the network thread", {1, 64});
    v.param("when_busy", when_busy, kWhenBusyNames,
            "network busy and the queue full: wait (no scheduled frame is dropped; tracking waits for room) or "
            "drop_oldest (the oldest waiting frame is dropped; tracking never waits)");
    v.param("class_names_file", class_names_file, "path", "model class names, one a line (index = model class id); empty: built-in COCO-80 (80 classes), VOC-21 (21) or ADE20K-32 (32)");
    v.param("class_map", class_map, "", "comma-separated model_name=project_name overrides of the class mapping");
    v.param("register_to_depth", register_to_depth, "", "resample labels/masks to depth pixels when the colour camera is separate (METHODS B2)");
    v.param("threads", threads, "", "cv::setNumThreads when a network segmenter is created (process-wide); 0 = leave OpenCV's setting", {0, 256});
    v.section("yolo", "YOLO-seg ONNX instance segmentation (METHODS C1)", [&](ParamVisitor& s) { yolo.visit(s); });
    v.section("semantic", "semantic segmentation ONNX model (METHODS A5)", [&](ParamVisitor& s) { semantic.visit(s); });
    v.section("panoptic", "panoptic:SEMANTIC+INSTANCE: how the two networks combine (issue 38)", [&](ParamVisitor& s) { panoptic.visit(s); });
    v.section("temporal", "temporal label filter (METHODS B1)", [&](ParamVisitor& s) { temporal.visit(s); });
  }
  void validate() const {
    check_param_ranges(*this, "segmentation");
    for (const auto& entry : class_map)
      require_param(entry.empty() || entry.find('=') != std::string::npos, "segmentation.class_map",
                    "entries must read model_name=project_name");
    yolo.validate();
    semantic.validate();
    panoptic.validate();
    temporal.validate();
  }
};

}  // namespace semap
