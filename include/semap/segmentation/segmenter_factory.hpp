#pragma once
// The one way to build a segmenter from a spec string (CLI --segmenter / --model, config
// segmentation.segmenter):
//   "yolo:PATH"          YOLO-seg ONNX instance segmentation (YoloSegmenter)
//   "semantic:PATH"      semantic segmentation ONNX model (SemanticSegmenter)
//   "panoptic:SEM+INST"  both on each frame, combined per pixel (PanopticSegmenter, issue 38):
//                        SEM a semantic model (e.g. deeplabv3-mnv2-ade20k32-512.onnx), INST a
//                        YOLO-seg model; instance masks win, semantic labels fill the rest. The
//                        split is after the first ".onnx+" (else the first '+'); each part may
//                        carry its "semantic:" / "yolo:" prefix (the segmenter's name() does).
//                        segmentation.semantic / .yolo configure each network.
//   "groundtruth"        the frame's own label/instance images (GroundTruthSegmenter)
//   "precomputed:DIR"    NAME.label.png/.instances.png/.json from an external tool
//   "PATH.onnx"          kind detected from the graph (2 outputs with a 4-D prototype tensor ->
//                        yolo, 1 output -> semantic)
//   "none" or ""         returns nullptr: the caller runs without segmentation.
//   "default"            (the config's default) returns nullptr here: the run driver
//                        (run_pipeline: `semap run`, semap.run) resolves it to the default
//                        models when it finds them (issue 38); a bare Mapper maps without.
// Network and precomputed outputs are computed on the colour image; when `camera` has a
// separate colour camera (METHODS B2) and config.register_to_depth is set, they are
// resampled to depth pixels (frames must carry depth) before they are returned.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "semap/core/camera.hpp"
#include "semap/segmentation/segmentation_config.hpp"
#include "semap/segmentation/segmenter.hpp"

namespace semap {

/// The spec that asks the run driver for the default models (segmentation.segmenter default).
inline constexpr const char* kDefaultSegmenterSpec = "default";

/// The files and folders a spec reads (model files, the precomputed folder): inputs that an
/// output folder may not be nor contain (issue 44). Throws like make_segmenter for a bad
/// panoptic spec.
std::vector<std::filesystem::path> segmenter_input_paths(const std::string& spec);

/// Throws semap::Error naming the model file (missing, not ONNX, wrong outputs) or the spec.
std::unique_ptr<Segmenter> make_segmenter(const std::string& spec, const SegmentationConfig& config,
                                          const CameraModel& camera);

}  // namespace semap
