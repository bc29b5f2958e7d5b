#pragma once
#include <string>

#include "core/params.hpp"

namespace semap {

/// Parameters of the dense semantic TSDF (METHODS.md B3-B7, A6).
struct TsdfConfig {
  double voxel_size = 0.02;       ///< s, metres
  double max_range = 5.0;         ///< depth beyond this is skipped, metres

  void visit(ParamVisitor& v) {
    v.param("voxel_size", voxel_size, "m", "voxel edge length s (truncation delta = 4 s)");
    v.param("max_range", max_range, "m", "depth beyond this is not integrated");
  }
  void validate() const {
    require_param(voxel_size > 0 && voxel_size < 1, "tsdf.voxel_size", "must be in (0, 1) m");
    require_param(max_range > 0, "tsdf.max_range", "must be > 0");
  }
};

}  // namespace semap
