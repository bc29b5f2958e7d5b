// bench_tsdf: our TSDF integrators against Open3D's ScalableTSDFVolume and its tensor
// t::geometry::VoxelBlockGrid (CPU; what current Open3D users run) on the SAME frames in one
// process (tum_fr1_rpy with ground-truth poses, and a synthetic sequence), 2 threads each, at
// 1, 2 and 5 cm. Prints JSON: ms/frame, ratio Open3D/ours, bytes per allocated voxel, mesh
// extraction time, and the block hash table against std::unordered_map (METHODS B4).
//
//   build/bench/bench_tsdf [--frames 200] [--synthetic-frames 60] [--threads 2]
//                          [--voxels 0.01,0.02,0.05] [--synthetic DIR]
//                          [--variants ours_projective_core,...]  (a subset of ours; Open3D always runs)
//                          [--memory 1]  (0: no peak-RSS child processes)
// Memory (TUM): bytes_per_allocated_voxel for every system, and peak_rss_mb_own_process for the
// default configuration and both Open3D systems, each re-run alone (--memory-child NAME: this
// program re-executed, frames streamed one at a time, peak taken before mesh extraction).
// Each variant's JSON carries map_checksum (FNV-1a over every layer of the sorted blocks): a
// speed-up that keeps the map bit-identical keeps the checksum.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>
#include <unordered_map>
#include <map>
#include <cstring>
#include <sys/resource.h>
#include <unistd.h>

#include "bench/bench_options.hpp"
#include "core/paths.hpp"
#include "semap/io/dataset.hpp"
#include "synth/synth_config.hpp"
#include "tsdf/semantic_tsdf.hpp"

#ifdef SEMAP_HAVE_OPEN3D
#include <dlfcn.h>

#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/geometry/TriangleMesh.h>
#include <open3d/pipelines/integration/ScalableTSDFVolume.h>
#include <open3d/pipelines/integration/UniformTSDFVolume.h>
#include <open3d/t/geometry/Image.h>
#include <open3d/t/geometry/TriangleMesh.h>
#include <open3d/t/geometry/VoxelBlockGrid.h>
#endif

using namespace semap;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

struct Sequence {
  std::string name;
  PinholeIntrinsics K;
  std::vector<IntegrationInput> frames;
  bool real_labels = false;
};

/// Calls fn(intrinsics, input, real_labels) for each of the first max_frames frames with a
/// ground-truth pose, one frame in memory at a time.
template <class Fn>
void for_each_frame(const fs::path& root, int max_frames, Fn&& fn) {
  auto reader = open_dataset(root);
  const PinholeIntrinsics K = reader->camera().depth;
  int used = 0;
  for (size_t i = 0; i < reader->size() && used < max_frames; ++i) {
    Frame f = reader->load(i);
    if (!f.gt_T_world_camera) continue;
    ++used;
    IntegrationInput in = make_integration_input(f, K, *f.gt_T_world_camera);
    const bool real_labels = !in.labels.empty();
    if (!real_labels) {
      // No label ground truth (TUM): synthetic labels (depth bands) so the label layers work.
      in.labels = cv::Mat(in.depth.size(), CV_8UC1);
      for (int v = 0; v < in.depth.rows; ++v)
        for (int u = 0; u < in.depth.cols; ++u)
          in.labels.at<uint8_t>(v, u) = static_cast<uint8_t>(1 + static_cast<int>(in.depth.at<float>(v, u) * 4) % 20);
    }
    fn(K, std::move(in), real_labels);
  }
}

Sequence load_sequence(const std::string& name, const fs::path& root, int max_frames) {
  Sequence seq;
  seq.name = name;
  for_each_frame(root, max_frames, [&](const PinholeIntrinsics& K, IntegrationInput in, bool real_labels) {
    seq.K = K;
    seq.real_labels = real_labels;
    seq.frames.push_back(std::move(in));
  });
  return seq;
}

struct Variant {
  std::string name;
  std::string integrator;
  bool labels, bayes, colour;
};

double cpu_ms() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

/// One system under test; all of them integrate frame i before any moves to frame i + 1, so a
/// machine shared with other work loads them alike (wall and process-CPU time both recorded).
struct Runner {
  std::string name;
  double wall_ms = 0, cpu_ms_total = 0;
  virtual ~Runner() = default;
  /// Process CPU since c0, taken after a pause: worker threads that spin after a parallel
  /// region (TBB's before they sleep) are charged to the system that left them spinning, not
  /// to the next one measured. The main thread sleeps meanwhile (no CPU); wall time is taken
  /// before the pause.
  void charge_cpu(double c0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
    cpu_ms_total += cpu_ms() - c0;
  }
  virtual void integrate(const IntegrationInput& frame) = 0;
  virtual nlohmann::json finish(int threads) = 0;
};

/// FNV-1a over the block indices and every voxel layer, in sorted block order.
uint64_t map_checksum(const TsdfMap& map) {
  uint64_t h = 1469598103934665603ULL;
  auto add = [&](const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ULL;
  };
  for (const Block* b : map.sorted_blocks()) {
    add(b->index.data(), sizeof(int) * 3);
    add(b->voxels.data(), sizeof(b->voxels));
    if (b->label_confidence) add(b->label_confidence.get(), kBlockVoxels);
    if (b->bayes) add(b->bayes.get(), static_cast<size_t>(kBlockVoxels) * map.bayes().bytes_per_voxel());
    if (b->colour) add(b->colour.get(), kBlockVoxels * sizeof(Rgb8));
  }
  return h;
}

struct OursRunner : Runner {
  Variant v;
  std::unique_ptr<SemanticTsdf> tsdf;
  OursRunner(const Variant& variant, double voxel, int threads) : v(variant) {
    name = v.name;
    TsdfConfig cfg;
    cfg.voxel_size = voxel;
    cfg.integrator = *enum_value(kIntegratorNames, v.integrator);
    cfg.threads = threads;
    cfg.label_layer = v.labels;
    cfg.bayes_layer = v.bayes;
    cfg.colour_layer = v.colour;
    cfg.max_depth = 4.0;
    tsdf = std::make_unique<SemanticTsdf>(cfg);
  }
  void integrate(const IntegrationInput& frame) override {
    IntegrationInput in = frame;
    if (!v.labels && !v.bayes) in.labels = cv::Mat();
    if (!v.colour) in.colour = cv::Mat();
    const double c0 = cpu_ms();
    const auto t0 = Clock::now();
    tsdf->integrate(in);
    wall_ms += ms_since(t0);
    charge_cpu(c0);
    const IntegrationStats& s = tsdf->integrator().last_stats();
    ++frames;
    voxel_updates += s.voxel_updates;
    touched_blocks += s.touched_blocks;
    rays += s.rays;
  }
  size_t frames = 0, voxel_updates = 0, touched_blocks = 0, rays = 0;
  nlohmann::json finish(int threads) override {
    const auto t0 = Clock::now();
    const TriangleMesh mesh = MeshExtractor(threads).extract_full(tsdf->map());
    const double mesh_ms = ms_since(t0);
    const TsdfMap& map = tsdf->map();
    nlohmann::json j;
    j["variant"] = v.name;
    j["blocks"] = map.num_blocks();
    j["allocated_voxels"] = map.num_blocks() * kBlockVoxels;
    j["bytes_per_voxel_layers"] = map.bytes_per_voxel();
    j["bytes_per_allocated_voxel_total"] =
        static_cast<double>(map.memory_bytes()) / std::max<size_t>(1, map.num_blocks() * kBlockVoxels);
    j["memory_mb"] = map.memory_bytes() / 1e6;
    j["mesh_ms"] = mesh_ms;
    j["mesh_triangles"] = mesh.triangles.size();
    j["map_checksum"] = map_checksum(map);
    const double n = static_cast<double>(std::max<size_t>(frames, 1));
    j["voxel_updates_per_frame"] = voxel_updates / n;
    j["touched_blocks_per_frame"] = touched_blocks / n;
    if (rays) j["rays_per_frame"] = rays / n;
    return j;
  }
};

#ifdef SEMAP_HAVE_OPEN3D
struct Open3DRunner : Runner {
  std::unique_ptr<open3d::pipelines::integration::ScalableTSDFVolume> volume;
  open3d::camera::PinholeCameraIntrinsic intrinsic;
  Open3DRunner(const PinholeIntrinsics& K, double voxel)
      : intrinsic(K.width, K.height, K.fx, K.fy, K.cx, K.cy) {
    name = "open3d_scalable_rgb8";
    volume = std::make_unique<open3d::pipelines::integration::ScalableTSDFVolume>(
        voxel, 4 * voxel, open3d::pipelines::integration::TSDFVolumeColorType::RGB8);
  }
  void integrate(const IntegrationInput& f) override {
    namespace o3d = open3d;
    o3d::geometry::Image depth, colour;
    depth.Prepare(f.depth.cols, f.depth.rows, 1, 4);
    std::memcpy(depth.data_.data(), f.depth.data, f.depth.total() * 4);
    colour.Prepare(f.colour.cols, f.colour.rows, 3, 1);
    for (int v = 0; v < f.colour.rows; ++v)
      for (int u = 0; u < f.colour.cols; ++u) {
        const cv::Vec3b bgr = f.colour.at<cv::Vec3b>(v, u);
        uint8_t* rgb = colour.data_.data() + 3 * (static_cast<size_t>(v) * f.colour.cols + u);
        rgb[0] = bgr[2];
        rgb[1] = bgr[1];
        rgb[2] = bgr[0];
      }
    auto rgbd = o3d::geometry::RGBDImage::CreateFromColorAndDepth(colour, depth, 1.0, 4.0, false);
    const Eigen::Matrix4d extrinsic = f.T_world_camera.inverse().matrix();
    const double c0 = cpu_ms();
    const auto t0 = Clock::now();
    volume->Integrate(*rgbd, intrinsic, extrinsic);
    wall_ms += ms_since(t0);
    charge_cpu(c0);
  }
  nlohmann::json finish(int) override {
    const auto t0 = Clock::now();
    auto mesh = volume->ExtractTriangleMesh();
    const double mesh_ms = ms_since(t0);
    const size_t res = volume->volume_unit_resolution_;
    const size_t voxels = volume->volume_units_.size() * res * res * res;
    nlohmann::json j;
    j["variant"] = name;
    j["allocated_voxels"] = voxels;
    j["bytes_per_voxel_layers"] = sizeof(open3d::geometry::TSDFVoxel);
    j["memory_mb"] = voxels * sizeof(open3d::geometry::TSDFVoxel) / 1e6;
    j["mesh_ms"] = mesh_ms;
    j["mesh_triangles"] = mesh->triangles_.size();
    return j;
  }
};

/// Open3D's tensor VoxelBlockGrid on the CPU, as its TSDF examples configure it (tsdf Float32,
/// weight and colour UInt16, 16^3 blocks) and fed as they read TUM: uint16 depth (TUM's 1/5000 m
/// units, exactly the dataset's values) and uint8 RGB. Timed: block selection + integration.
struct Open3DVoxelBlockGridRunner : Runner {
  static constexpr float kDepthScale = 5000.0f;
  std::unique_ptr<open3d::t::geometry::VoxelBlockGrid> vbg;
  open3d::core::Tensor intrinsic;
  float depth_max;
  Open3DVoxelBlockGridRunner(const PinholeIntrinsics& K, double voxel, double max_depth) : depth_max(static_cast<float>(max_depth)) {
    namespace core = open3d::core;
    name = "open3d_voxel_block_grid";
    vbg = std::make_unique<open3d::t::geometry::VoxelBlockGrid>(
        std::vector<std::string>{"tsdf", "weight", "color"}, std::vector<core::Dtype>{core::Float32, core::UInt16, core::UInt16},
        std::vector<core::SizeVector>{{1}, {1}, {3}}, static_cast<float>(voxel), 16, 50000, core::Device("CPU:0"));
    intrinsic = core::Tensor::Init<double>({{K.fx, 0, K.cx}, {0, K.fy, K.cy}, {0, 0, 1}});
  }
  void integrate(const IntegrationInput& f) override {
    namespace core = open3d::core;
    const int H = f.depth.rows, W = f.depth.cols;
    core::Tensor depth({H, W, 1}, core::UInt16), colour({H, W, 3}, core::UInt8);
    auto* d = depth.GetDataPtr<uint16_t>();
    auto* c = colour.GetDataPtr<uint8_t>();
    for (int v = 0; v < H; ++v)
      for (int u = 0; u < W; ++u) {
        const float z = f.depth.at<float>(v, u);
        d[static_cast<size_t>(v) * W + u] = std::isfinite(z) && z > 0 ? static_cast<uint16_t>(std::lround(z * kDepthScale)) : 0;
        const cv::Vec3b bgr = f.colour.at<cv::Vec3b>(v, u);
        uint8_t* rgb = c + 3 * (static_cast<size_t>(v) * W + u);
        rgb[0] = bgr[2], rgb[1] = bgr[1], rgb[2] = bgr[0];
      }
    const open3d::t::geometry::Image depth_image(depth), colour_image(colour);
    const Eigen::Matrix4d T_cw = f.T_world_camera.inverse().matrix();
    core::Tensor extrinsic({4, 4}, core::Float64);
    for (int r = 0; r < 4; ++r)
      for (int k = 0; k < 4; ++k) extrinsic[r][k] = T_cw(r, k);
    const double c0 = cpu_ms();
    const auto t0 = Clock::now();
    const core::Tensor blocks = vbg->GetUniqueBlockCoordinates(depth_image, intrinsic, extrinsic, kDepthScale, depth_max, 4.0f);
    vbg->Integrate(blocks, depth_image, colour_image, intrinsic, extrinsic, kDepthScale, depth_max, 4.0f);
    wall_ms += ms_since(t0);
    charge_cpu(c0);
  }
  nlohmann::json finish(int) override {
    const auto t0 = Clock::now();
    const auto mesh = vbg->ExtractTriangleMesh(0.0f);
    const double mesh_ms = ms_since(t0);
    const size_t blocks = vbg->GetHashMap().Size();
    constexpr size_t kVoxelBytes = 4 + 2 + 3 * 2;  // tsdf Float32, weight UInt16, colour 3 x UInt16
    nlohmann::json j;
    j["variant"] = name;
    j["blocks"] = blocks;
    j["allocated_voxels"] = blocks * 16 * 16 * 16;
    j["bytes_per_voxel_layers"] = kVoxelBytes;
    j["memory_mb"] = blocks * 16 * 16 * 16 * kVoxelBytes / 1e6;
    j["mesh_ms"] = mesh_ms;
    j["mesh_triangles"] = mesh.HasTriangleIndices() ? mesh.GetTriangleIndices().GetLength() : 0;
    return j;
  }
};
#endif

nlohmann::json hash_benchmark(const TsdfMap& map) {
  std::vector<BlockIndex> keys;
  for (const auto& b : map.blocks()) keys.push_back(b->index);
  std::mt19937 rng(1);
  std::vector<BlockIndex> queries;
  for (int i = 0; i < 4000000; ++i) {
    BlockIndex k = keys[rng() % keys.size()];
    if (rng() % 4 == 0) k += BlockIndex(0, 0, 1000);  // a miss
    queries.push_back(k);
  }
  BlockHashTable own;
  std::unordered_map<BlockIndex, int32_t, BlockHash> stl;
  auto t0 = Clock::now();
  for (size_t i = 0; i < keys.size(); ++i) own.insert(keys[i], static_cast<int32_t>(i));
  const double own_insert = ms_since(t0);
  t0 = Clock::now();
  for (size_t i = 0; i < keys.size(); ++i) stl.emplace(keys[i], static_cast<int32_t>(i));
  const double stl_insert = ms_since(t0);
  int64_t sum = 0;
  t0 = Clock::now();
  for (const auto& q : queries) sum += own.find(q);
  const double own_find = ms_since(t0);
  t0 = Clock::now();
  for (const auto& q : queries) {
    auto it = stl.find(q);
    sum += it == stl.end() ? -1 : it->second;
  }
  const double stl_find = ms_since(t0);
  nlohmann::json j;
  j["blocks"] = keys.size();
  j["open_addressing_ns_per_lookup"] = own_find * 1e6 / queries.size();
  j["unordered_map_ns_per_lookup"] = stl_find * 1e6 / queries.size();
  j["open_addressing_ns_per_insert"] = own_insert * 1e6 / keys.size();
  j["unordered_map_ns_per_insert"] = stl_insert * 1e6 / keys.size();
  j["checksum"] = sum;
  return j;
}

std::vector<Variant> all_variants() {
  return {
      {"ours_projective_core", "projective", false, false, false},
      {"ours_grouped_core", "grouped", false, false, false},
      {"ours_projective_labels_rgb", "projective", true, false, true},
      {"ours_grouped_labels_rgb", "grouped", true, false, true},
      {"ours_projective_labels_bayes_rgb", "projective", true, true, true},
      {"ours_grouped_labels_bayes_rgb", "grouped", true, true, true},
  };
}
/// The product's default configuration (TsdfConfig's integrator and layers).
constexpr const char* kDefaultVariant = "ours_projective_labels_bayes_rgb";

std::unique_ptr<Runner> make_runner(const std::string& name, const PinholeIntrinsics& K, double voxel, int threads) {
#ifdef SEMAP_HAVE_OPEN3D
  if (name == "open3d_scalable_rgb8") return std::make_unique<Open3DRunner>(K, voxel);
  if (name == "open3d_voxel_block_grid") return std::make_unique<Open3DVoxelBlockGridRunner>(K, voxel, 4.0);
#endif
  for (const Variant& v : all_variants())
    if (v.name == name) return std::make_unique<OursRunner>(v, voxel, threads);
  throw std::runtime_error("unknown system " + name);
}

double current_rss_mb() {
  long pages = 0, resident = 0;
  if (FILE* f = std::fopen("/proc/self/statm", "r")) {
    if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    std::fclose(f);
  }
  return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB
}

/// --memory-child: one system alone in this process, fed TUM frame by frame (one frame in
/// memory); prints its peak RSS (before mesh extraction) and its own memory figures.
int memory_child(const std::string& system, const fs::path& root, int frames, double voxel, int threads) {
  std::unique_ptr<Runner> runner;
  double rss_before = 0;
  for_each_frame(root, frames, [&](const PinholeIntrinsics& K, IntegrationInput in, bool) {
    if (!runner) {
      runner = make_runner(system, K, voxel, threads);
      rss_before = current_rss_mb();
    }
    runner->integrate(in);
  });
  if (!runner) return 1;
  nlohmann::json j;
  j["peak_rss_mb"] = peak_rss_mb();
  j["rss_before_integration_mb"] = rss_before;
  j["figures"] = runner->finish(threads);
  std::cout << j.dump() << std::endl;
  return 0;
}

/// Runs memory_child for `system` in a fresh process (this program re-executed).
nlohmann::json memory_in_child(const char* self, const std::string& system, int frames, double voxel, int threads) {
  const std::string cmd = std::string("'") + self + "' --memory-child " + system + " --frames " + std::to_string(frames) +
                          " --voxels " + std::to_string(voxel) + " --threads " + std::to_string(threads);
  std::string text;
  if (FILE* p = ::popen(cmd.c_str(), "r")) {
    char buf[4096];
    while (size_t n = std::fread(buf, 1, sizeof(buf), p)) text.append(buf, n);
    if (::pclose(p) != 0) text.clear();
  }
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) throw std::runtime_error("memory child failed: " + cmd);
  return j;
}

/// Issue 20 memory figures, next to each other: bytes per allocated voxel (all layers, block
/// and hash overhead included for ours) and the peak RSS of the default configuration and of
/// both Open3D systems, each alone in its own process (the same binary: the same libraries).
void add_memory_figures(nlohmann::json& systems, const char* self, int frames, double voxel, int threads) {
  for (nlohmann::json& j : systems) {
    const std::string name = j["variant"];
    const bool ours = name.rfind("ours_", 0) == 0;
    j["bytes_per_allocated_voxel"] = ours ? j["bytes_per_allocated_voxel_total"] : j["bytes_per_voxel_layers"];
    if (ours && name != kDefaultVariant) continue;
    const nlohmann::json child = memory_in_child(self, name, frames, voxel, threads);
    j["peak_rss_mb_own_process"] = child["peak_rss_mb"];
    j["rss_before_integration_mb"] = child["rss_before_integration_mb"];
    j["map_memory_mb_own_process"] = child["figures"]["memory_mb"];
    std::cerr << "memory " << voxel << " " << name << ": peak RSS " << child["peak_rss_mb"] << " MB (before integration "
              << child["rss_before_integration_mb"] << " MB), " << j["bytes_per_allocated_voxel"] << " B/voxel\n";
  }
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> out;
  for (const std::string& item : split_list(s)) out.push_back(std::stod(item));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  // CPU time is measured for the whole process: Open3D's OpenMP threads, spinning after each
  // of its frames, would be charged to the integrator that runs next. libgomp reads its wait
  // policy when it loads, so the bench re-executes itself once with the passive policy.
  if (!std::getenv("OMP_WAIT_POLICY")) {
    setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
    execv("/proc/self/exe", argv);
  }
  int frames = 200, synthetic_frames = 60, threads = 2;
  std::vector<double> voxels = {0.01, 0.02, 0.05};
  fs::path synthetic_dir;
  std::vector<std::string> only_variants;
  std::string memory_system;  // --memory-child
  bool memory = true;
  const auto exit_code = bench::parse_options(
      argc, argv, 1,
      "[--frames 200] [--synthetic-frames 60] [--threads 2] [--voxels 0.01,0.02,0.05] [--synthetic DIR]\n"
      "       [--variants ours_projective_core,...] [--memory 1]",
      [&](const std::string& a, const std::string& v) {
        if (a == "--frames") frames = std::stoi(v);
        else if (a == "--synthetic-frames") synthetic_frames = std::stoi(v);
        else if (a == "--threads") threads = std::stoi(v);
        else if (a == "--voxels") voxels = parse_list(v);
        else if (a == "--synthetic") synthetic_dir = v;
        else if (a == "--variants") only_variants = split_list(v);
        else if (a == "--memory-child") memory_system = v;
        else if (a == "--memory") memory = v != "0";
        else return false;
        return true;
      });
  if (exit_code) return *exit_code;
  const fs::path tum = data_dir(fs::path(SEMAP_SHARED_DIR) / "data") / "tum_fr1_rpy";
  if (!memory_system.empty()) return memory_child(memory_system, tum, frames, voxels.at(0), threads);
  std::vector<Sequence> sequences;
  if (fs::exists(tum)) sequences.push_back(load_sequence("tum_fr1_rpy", tum, frames));
  fs::path tmp;
  if (synthetic_dir.empty() && synthetic_frames > 0) {
    tmp = fs::temp_directory_path() / ("bench_tsdf_synth_" + std::to_string(::getpid()));
    SynthConfig cfg;
    cfg.frames = synthetic_frames;
    cfg.seed = 7;
    generate_dataset(cfg, tmp);
    synthetic_dir = tmp;
  }
  if (!synthetic_dir.empty()) sequences.push_back(load_sequence("synthetic", synthetic_dir, synthetic_frames));

  std::vector<Variant> variants = all_variants();
  if (!only_variants.empty())
    std::erase_if(variants, [&](const Variant& v) {
      return std::find(only_variants.begin(), only_variants.end(), v.name) == only_variants.end();
    });
  nlohmann::json out;
  out["threads"] = threads;
  for (const Sequence& seq : sequences) {
    nlohmann::json js;
    js["frames"] = seq.frames.size();
    js["width"] = seq.K.width;
    js["height"] = seq.K.height;
    js["labels"] = seq.real_labels ? "ground truth" : "synthetic depth bands";
    for (double voxel : voxels) {
      std::vector<std::unique_ptr<Runner>> runners;
      for (const Variant& v : variants) runners.push_back(std::make_unique<OursRunner>(v, voxel, threads));
#ifdef SEMAP_HAVE_OPEN3D
      if (auto set_threads = reinterpret_cast<void (*)(int)>(dlsym(RTLD_DEFAULT, "omp_set_num_threads")))
        set_threads(threads);  // Open3D's OpenMP (libgomp, loaded with Open3D), without linking it here
      runners.push_back(std::make_unique<Open3DRunner>(seq.K, voxel));
      runners.push_back(std::make_unique<Open3DVoxelBlockGridRunner>(seq.K, voxel, 4.0));
#endif
      for (const IntegrationInput& frame : seq.frames)
        for (auto& r : runners) r->integrate(frame);
      const double n = static_cast<double>(seq.frames.size());
      nlohmann::json jv = nlohmann::json::array();
#ifdef SEMAP_HAVE_OPEN3D
      const Runner& o3d = *runners[runners.size() - 2];  // ScalableTSDFVolume
      const Runner& vbg = *runners.back();               // VoxelBlockGrid
#endif
      for (auto& r : runners) {
        nlohmann::json j = r->finish(threads);
        j["ms_per_frame"] = r->wall_ms / n;
        j["cpu_ms_per_frame"] = r->cpu_ms_total / n;
#ifdef SEMAP_HAVE_OPEN3D
        j["ratio_open3d_over_ours"] = o3d.wall_ms / r->wall_ms;
        j["cpu_ratio_open3d_over_ours"] = o3d.cpu_ms_total / r->cpu_ms_total;
        j["ratio_open3d_vbg_over_ours"] = vbg.wall_ms / r->wall_ms;
        j["cpu_ratio_open3d_vbg_over_ours"] = vbg.cpu_ms_total / r->cpu_ms_total;
#endif
        std::cerr << seq.name << " " << voxel << " " << r->name << " " << j["ms_per_frame"] << " ms/frame, cpu "
                  << j["cpu_ms_per_frame"] << " ms/frame\n";
        jv.push_back(j);
      }
      if (seq.name == "tum_fr1_rpy" && memory) add_memory_figures(jv, argv[0], static_cast<int>(seq.frames.size()), voxel, threads);
      if (seq.name == "tum_fr1_rpy" && voxel == 0.02 && !variants.empty() && variants[0].name == "ours_projective_core")
        out["block_hash"] = hash_benchmark(static_cast<OursRunner&>(*runners[0]).tsdf->map());
      std::ostringstream key;
      key << voxel * 100 << "cm";
      js[key.str()] = jv;
    }
    out[seq.name] = js;
  }
  if (!tmp.empty()) fs::remove_all(tmp);
  std::cout << out.dump(2) << std::endl;
  return 0;
}
