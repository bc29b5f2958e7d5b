#pragma once
#include <string>

#include "core/params.hpp"

namespace semap {

/// Parameters of segmentation (METHODS.md C1, B1, B2).
struct SegmentationConfig {
  int every_n_frames = 5;  ///< run the network on every N-th frame (and on keyframes)

  void visit(ParamVisitor& v) {
    v.param("every_n_frames", every_n_frames, "frames", "run the network on every N-th frame");
  }
  void validate() const { require_param(every_n_frames >= 1, "segmentation.every_n_frames", "must be >= 1"); }
};

}  // namespace semap
