#pragma once
// The final map refresh: after loop closure moved the frames (METHODS.md A4), the TSDF is
// rebuilt from every fused frame with its optimised pose.
#include <functional>
#include <optional>

#include "tsdf/semantic_tsdf.hpp"

namespace semap {

/// Integrates `input_of(0) ... input_of(frame_count - 1)` (nullopt: the frame is left out)
/// into `start` (an empty TSDF, or the saved map a resumed run continues). Inputs are prepared
/// in parallel (reading, repair, label decoding) and integrated serially in frame order, so one
/// thread still gives byte-identical maps.
SemanticTsdf rebuild_tsdf(SemanticTsdf start, size_t frame_count, int threads,
                          const std::function<std::optional<IntegrationInput>(size_t)>& input_of);

/// How far a pose correction moves a surface point at `range_m` from the camera: the camera
/// shift plus the rotation angle times the range (metres).
double surface_displacement_m(const Pose& before, const Pose& after, double range_m);

}  // namespace semap
