#pragma once
#include "core/params.hpp"

namespace semap {

/// Parameters of tracking (METHODS.md A1-A4).
struct TrackingConfig {
  bool depth_repair = true;  ///< joint median filter (A1)

  void visit(ParamVisitor& v) {
    v.param("depth_repair", depth_repair, "", "fill invalid depth with the joint median filter (A1)");
  }
  void validate() const {}
};

}  // namespace semap
