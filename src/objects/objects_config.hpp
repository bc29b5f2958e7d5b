#pragma once
#include "core/params.hpp"

namespace semap {

/// Parameters of the object map (METHODS.md C2-C5).
struct ObjectsConfig {
  int optimise_every = 50;  ///< T, frames between map optimisations (C5)

  void visit(ParamVisitor& v) {
    v.param("optimise_every", optimise_every, "frames", "T: optimise the object map every T frames (C5)");
  }
  void validate() const { require_param(optimise_every >= 1, "objects.optimise_every", "must be >= 1"); }
};

}  // namespace semap
