#include "semap/segmentation/segmenter_factory.hpp"

#include "semap/core/error.hpp"
#include "segmentation/groundtruth_segmenter.hpp"
#include "segmentation/onnx_model_info.hpp"
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

}  // namespace

std::unique_ptr<Segmenter> make_segmenter(const std::string& spec, const SegmentationConfig& config,
                                          const CameraModel& camera) {
  if (spec.empty() || spec == "none") return nullptr;
  if (spec == "groundtruth") return std::make_unique<GroundTruthSegmenter>();
  std::string kind, path;
  if (const size_t colon = spec.find(':'); colon != std::string::npos) {
    kind = spec.substr(0, colon);
    path = spec.substr(colon + 1);
  } else if (spec.size() > 5 && spec.substr(spec.size() - 5) == ".onnx") {
    path = spec;
    kind = detect_kind(path);
  } else {
    throw Error("segmenter '" + spec + "'", "unknown spec: use yolo:PATH, semantic:PATH, groundtruth, precomputed:DIR or none");
  }
  if (path.empty()) throw Error("segmenter '" + spec + "'", "missing path after '" + kind + ":'");
  std::unique_ptr<Segmenter> seg;
  if (kind == "yolo") seg = std::make_unique<YoloSegmenter>(path, config);
  else if (kind == "semantic") seg = std::make_unique<SemanticSegmenter>(path, config);
  else if (kind == "precomputed") seg = std::make_unique<PrecomputedSegmenter>(path, config);
  else
    throw Error("segmenter '" + spec + "'", "unknown kind '" + kind + "': use yolo, semantic, precomputed, groundtruth or none");
  if (config.register_to_depth && needs_registration(camera))
    seg = std::make_unique<DepthRegisteredSegmenter>(std::move(seg), camera);
  return seg;
}

}  // namespace semap
