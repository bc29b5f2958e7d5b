#include "tsdf/integrator.hpp"

#include <tbb/info.h>

#include <array>
#include <cstdlib>
#include <string>

#include "semap/core/error.hpp"
#include "tsdf/integrator_common.hpp"
#ifdef SEMAP_TSDF_X86
#include <cpuid.h>
#endif

// The integrators live in grouped_integrator.cpp and projective_integrator.cpp, what they share
// in integrator_common.hpp and ray_traversal.hpp; here: the set-up both run, the factory, B5 for tests.
namespace semap {
namespace integrator_detail {
namespace {

int arena_threads(const TsdfConfig& cfg) { return cfg.threads > 0 ? cfg.threads : tbb::info::default_concurrency(); }

}  // namespace

FrameSetup setup_frame(const TsdfMap& map, const IntegrationInput& in) {
  const TsdfConfig& cfg = map.config();
  if (in.depth.empty() || in.depth.type() != CV_32FC1) throw Error("integrate", "depth must be a non-empty CV_32FC1 image");
  auto check = [&](const cv::Mat& m, int type, const char* what) {
    if (m.empty()) return false;
    if (m.rows != in.depth.rows || m.cols != in.depth.cols)
      throw Error("integrate", std::string(what) + " size differs from depth");
    if (type >= 0 && m.type() != type) throw Error("integrate", std::string(what) + " has the wrong pixel type");
    return true;
  };
  FrameSetup f;
  f.width = in.depth.cols;
  f.height = in.depth.rows;
  f.fx = static_cast<float>(in.intrinsics.fx);
  f.fy = static_cast<float>(in.intrinsics.fy);
  f.cx = static_cast<float>(in.intrinsics.cx);
  f.cy = static_cast<float>(in.intrinsics.cy);
  if (!(f.fx > 0 && f.fy > 0)) throw Error("integrate", "intrinsics need fx, fy > 0");
  f.R_wc = in.T_world_camera.linear().cast<float>();
  f.t_wc = in.T_world_camera.translation().cast<float>();
  if (!f.R_wc.allFinite() || !f.t_wc.allFinite()) throw Error("integrate", "pose is not finite");
  f.R_cw = f.R_wc.transpose();
  f.t_cw = -(f.R_cw * f.t_wc);
  f.s = map.voxel_size();
  f.delta = static_cast<float>(cfg.truncation());
  f.eps = static_cast<float>(cfg.epsilon());
  f.label_band_min = static_cast<float>(cfg.label_band_voxels * cfg.voxel_size);
  f.label_band_sigmas = static_cast<float>(cfg.label_band_sigmas);
  f.depth_noise = cfg.depth_noise;
  f.min_range = static_cast<float>(cfg.min_depth);
  f.max_range = static_cast<float>(cfg.max_depth);
  f.default_confidence = static_cast<float>(cfg.bayes_default_confidence);
  f.confusion_classes = cfg.bayes_confusion_classes;
  f.labels = check(in.labels, CV_8UC1, "labels");
  f.confidence = check(in.confidence, CV_32FC1, "confidence");
  f.colour = check(in.colour, CV_8UC3, "colour");
  if (check(in.probabilities, -1, "probabilities")) {
    if (in.probabilities.depth() != CV_32F) throw Error("integrate", "probabilities must be CV_32FC(n)");
    f.probabilities = true;
    f.prob_channels = in.probabilities.channels();
  }
  return f;
}

VoxelUpdater make_updater(const TsdfMap& map, const FrameSetup& f) {
  return VoxelUpdater{map.weights(),         map.bayes(),           f.delta, f.eps, static_cast<float>(map.config().weight_max),
                      map.has_label_layer(), map.has_bayes_layer(), map.has_colour_layer()};
}

bool have_avx2_f16c() {
#ifdef SEMAP_TSDF_X86
  // F16C through cpuid: clang 14's __builtin_cpu_supports does not know "f16c".
  static const bool yes = [] {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    const bool f16c = __get_cpuid(1, &eax, &ebx, &ecx, &edx) && (ecx & bit_F16C);
    return !std::getenv("SEMAP_TSDF_BASELINE_ISA") && __builtin_cpu_supports("avx2") && f16c;
  }();
  return yes;
#else
  return false;
#endif
}

ArenaIntegrator::ArenaIntegrator(const TsdfConfig& cfg) : arena_(arena_threads(cfg)), worker_cpu_(arena_) {}

void ArenaIntegrator::integrate(TsdfMap& map, const IntegrationInput& in) {
  const FrameSetup f = setup_frame(map, in);
  stats_ = {};
  arena_.execute([&] { run(map, in, f); });
  if (map.config().drop_distance > 0) map.remove_blocks_beyond(f.t_wc, static_cast<float>(map.config().drop_distance));
}

}  // namespace integrator_detail

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const TsdfConfig& config) {
  if (kind == IntegratorKind::grouped) return integrator_detail::make_grouped_integrator(config);
  return integrator_detail::make_projective_integrator(config);
}

PointGroup group_points(const std::vector<LabelledPoint>& points) {
  PointGroup g;
  std::array<float, kNumClasses> weight{};
  for (const LabelledPoint& p : points) {
    weight[p.label] += p.weight;
    g.total_weight += p.weight;
  }
  for (int l = 0; l < kNumClasses; ++l)
    if (weight[l] > weight[g.label]) g.label = static_cast<ClassId>(l);
  g.label_weight = weight[g.label];
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (const LabelledPoint& p : points)
    if (p.label == g.label) sum += p.weight * p.position;
  g.point = g.label_weight > 0 ? Eigen::Vector3f(sum / g.label_weight) : Eigen::Vector3f::Zero();
  return g;
}

}  // namespace semap
