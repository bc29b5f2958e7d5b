#include "semap/segmentation/segmenter_factory.hpp"

#include "semap/core/error.hpp"
#include "segmentation/groundtruth_segmenter.hpp"
#include "segmentation/onnx_model_info.hpp"
#include "segmentation/panoptic_segmenter.hpp"
#include "segmentation/registration.hpp"
#include "segmentation/semantic_segmenter.hpp"
#include "segmentation/yolo_segmenter.hpp"

namespace semap {
namespace {

// Resamples colour-camera results at depth pixels (METHODS B2).
class DepthRegisteredSegmenter : public Segmenter {
 public:
  DepthRegisteredSegmenter(std::unique_ptr<Segmenter> inner, const CameraModel& camera)
      : inner_(std::move(inner)), camera_(camera) {}
  SegmentationResult segment(const Frame& frame) override {
    SegmentationResult r = inner_->segment(frame);
    if (frame.depth.empty()) return r;
    return register_result(r, colour_lookup_map(frame.depth, camera_));
  }
  std::string name() const override { return inner_->name(); }

 private:
  std::unique_ptr<Segmenter> inner_;
  CameraModel camera_;
};

std::string detect_kind(const std::string& path) {
  const OnnxModelInfo info = read_onnx_model_info(path);
  if (info.outputs.size() == 2) return "yolo";
  if (info.outputs.size() == 1) return "semantic";
  throw Error(path, "cannot tell the model kind from its " + std::to_string(info.outputs.size()) +
                        " outputs: use yolo:PATH or semantic:PATH");
}

std::string strip_prefix(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0 ? s.substr(prefix.size()) : s;
}

/// "SEMANTIC+INSTANCE" (each optionally "semantic:"/"yolo:"-prefixed, as name() writes them):
/// split after the first ".onnx" followed by '+', else at the first '+'.
std::pair<std::string, std::string> split_panoptic(const std::string& spec, const std::string& rest) {
  size_t plus = rest.find(".onnx+");
  plus = plus == std::string::npos ? rest.find('+') : plus + 5;
  if (plus == std::string::npos || plus == 0 || plus + 1 >= rest.size())
    throw Error("segmenter '" + spec + "'", "panoptic needs two models: panoptic:SEMANTIC.onnx+INSTANCE.onnx");
  return {strip_prefix(rest.substr(0, plus), "semantic:"), strip_prefix(rest.substr(plus + 1), "yolo:")};
}

}  // namespace

std::vector<std::filesystem::path> segmenter_input_paths(const std::string& spec) {
  if (spec.empty() || spec == "none" || spec == kDefaultSegmenterSpec || spec == "groundtruth") return {};
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) return {spec};
  const std::string kind = spec.substr(0, colon), path = spec.substr(colon + 1);
  if (kind != "panoptic") return {path};
  const auto [semantic_path, instance_path] = split_panoptic(spec, path);
  return {semantic_path, instance_path};
}

std::unique_ptr<Segmenter> make_segmenter(const std::string& spec, const SegmentationConfig& config,
                                          const CameraModel& camera) {
  if (spec.empty() || spec == "none" || spec == kDefaultSegmenterSpec) return nullptr;
  if (spec == "groundtruth") return std::make_unique<GroundTruthSegmenter>();
  std::string kind, path;
  if (const size_t colon = spec.find(':'); colon != std::string::npos) {
    kind = spec.substr(0, colon);
    path = spec.substr(colon + 1);
  } else if (spec.size() > 5 && spec.substr(spec.size() - 5) == ".onnx") {
    path = spec;
    kind = detect_kind(path);
  } else {
    throw Error("segmenter '" + spec + "'", "unknown spec: use yolo:PATH, semantic:PATH, panoptic:SEMANTIC+INSTANCE, groundtruth, precomputed:DIR or none");
  }
  if (path.empty()) throw Error("segmenter '" + spec + "'", "missing path after '" + kind + ":'");
  const auto registered = [&](std::unique_ptr<Segmenter> seg) -> std::unique_ptr<Segmenter> {
    if (!config.register_to_depth || !needs_registration(camera)) return seg;
    return std::make_unique<DepthRegisteredSegmenter>(std::move(seg), camera);
  };
  std::unique_ptr<Segmenter> seg;
  if (kind == "yolo") seg = std::make_unique<YoloSegmenter>(path, config);
  else if (kind == "semantic") seg = std::make_unique<SemanticSegmenter>(path, config);
  else if (kind == "precomputed") seg = std::make_unique<PrecomputedSegmenter>(path, config);
  else if (kind == "panoptic") {
    // Each network registered on its own: the Mapper runs them on their own frames (issue 38).
    const auto [semantic_path, instance_path] = split_panoptic(spec, path);
    auto semantic = registered(std::make_unique<SemanticSegmenter>(semantic_path, config));  // first: its errors first
    return std::make_unique<PanopticSegmenter>(std::move(semantic),
                                               registered(std::make_unique<YoloSegmenter>(instance_path, config)),
                                               config.panoptic.min_instance_score);
  } else
    throw Error("segmenter '" + spec + "'",
                "unknown kind '" + kind + "': use yolo, semantic, panoptic, precomputed, groundtruth or none");
  return registered(std::move(seg));
}

}  // namespace semap
