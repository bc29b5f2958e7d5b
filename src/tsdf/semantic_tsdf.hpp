#pragma once
// The dense semantic map as the pipeline uses it: one object owning the voxel-hashed TSDF
// (tsdf_map.hpp), the configured integrator (integrator.hpp) and the incremental mesher.
//
//   SemanticTsdf tsdf(config.tsdf);
//   tsdf.integrate(make_integration_input(frame, camera.depth, T_world_camera));
//   TriangleMesh mesh = tsdf.extract_mesh();          // only changed blocks re-meshed
//   tsdf.write_mesh(out / "mesh.ply");                // x y z red green blue label
//   tsdf.save(out / "map.semap");  auto again = SemanticTsdf::load(out / "map.semap", config.tsdf);
#include <filesystem>
#include <memory>

#include "semap/core/frame.hpp"
#include "tsdf/integrator.hpp"
#include "tsdf/mesh_extractor.hpp"

namespace semap {

/// Frame -> integration input: depth, labels (if any) and rgb (when it has the depth size).
IntegrationInput make_integration_input(const Frame& frame, const PinholeIntrinsics& depth_intrinsics,
                                        const Pose& T_world_camera);

class SemanticTsdf {
 public:
  explicit SemanticTsdf(const TsdfConfig& config);
  explicit SemanticTsdf(TsdfMap&& map);

  void integrate(const IntegrationInput& input);
  TriangleMesh extract_mesh();
  /// Extracts (incrementally) and writes a binary PLY with red green blue label.
  void write_mesh(const std::filesystem::path& path);
  void save(const std::filesystem::path& path) const;
  static SemanticTsdf load(const std::filesystem::path& path, const TsdfConfig& base = TsdfConfig{});

  TsdfMap& map() { return map_; }
  const TsdfMap& map() const { return map_; }
  Integrator& integrator() { return *integrator_; }

 private:
  TsdfMap map_;
  std::unique_ptr<Integrator> integrator_;
  MeshExtractor mesher_;
};

}  // namespace semap
