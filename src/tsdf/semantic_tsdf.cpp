#include "tsdf/semantic_tsdf.hpp"

#include "semap/io/ply_io.hpp"
#include "tsdf/map_io.hpp"

namespace semap {

IntegrationInput make_integration_input(const Frame& frame, const PinholeIntrinsics& depth_intrinsics,
                                        const Pose& T_world_camera) {
  IntegrationInput in;
  in.depth = frame.depth;
  in.intrinsics = depth_intrinsics;
  in.T_world_camera = T_world_camera;
  if (!frame.labels.empty() && frame.labels.size() == frame.depth.size()) in.labels = frame.labels;
  if (!frame.rgb.empty() && frame.rgb.size() == frame.depth.size() && frame.rgb.type() == CV_8UC3) in.colour = frame.rgb;
  return in;
}

SemanticTsdf::SemanticTsdf(const TsdfConfig& config)
    : map_(config), integrator_(make_integrator(config.integrator, config)), mesher_(config.threads) {}

SemanticTsdf::SemanticTsdf(TsdfMap&& map)
    : map_(std::move(map)),
      integrator_(make_integrator(map_.config().integrator, map_.config())),
      mesher_(map_.config().threads) {}

void SemanticTsdf::integrate(const IntegrationInput& input) { integrator_->integrate(map_, input); }

TriangleMesh SemanticTsdf::extract_mesh() { return mesher_.extract(map_); }

void SemanticTsdf::write_mesh(const std::filesystem::path& path) { write_ply(path, extract_mesh()); }

void SemanticTsdf::save(const std::filesystem::path& path) const { save_map(map_, path); }

SemanticTsdf SemanticTsdf::load(const std::filesystem::path& path, const TsdfConfig& base) {
  return SemanticTsdf(load_map(path, base));
}

}  // namespace semap
