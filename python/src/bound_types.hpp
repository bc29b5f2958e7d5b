#pragma once
// C++ types behind the Python classes that more than one binding file uses.
#include "semap/core/point_cloud.hpp"
#include "semap/mapper.hpp"

namespace semap::python {

/// semap.FrameResult: the Mapper's result plus the binding's own time.
struct PyFrameResult {
  FrameResult result;
  double binding_ms = 0.0;  ///< add_frame() time outside Mapper::add_frame (checks, conversions, GIL)
};

/// semap.Mesh: owns the extracted mesh; its arrays are views into it.
struct PyMesh {
  TriangleMesh mesh;
};

}  // namespace semap::python
