#include "semap/pipeline/map_merge.hpp"

#include <chrono>
#include <set>

#include "core/camera_difference.hpp"
#include "core/archive.hpp"
#include "core/paths.hpp"
#include "io/output_folder.hpp"
#include "objects/object_mapper.hpp"
#include "pipeline/map_archive.hpp"
#include "semap/core/error.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "semap/mapper.hpp"
#include "semap/pipeline/outputs.hpp"
#include "tracking/map_alignment.hpp"
#include "tracking/tracker.hpp"
#include "tracking/tracker_state.hpp"
#include "tsdf/map_io.hpp"
#include "tsdf/tsdf_merge.hpp"

namespace semap {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// One input map, read and checked.
struct SavedMap {
  fs::path path;
  ArchiveSections sections;
  SemapConfig config;
  CameraModel camera;
  TrackerState tracking;
};

SavedMap read_saved_map(const fs::path& path) {
  SavedMap m{path, read_map_archive(path), {}, {}, {}};
  m.config = decode_config_section(archive_section(m.sections, kConfigSection, path), path);
  m.camera = decode_camera_section(archive_section(m.sections, kCameraSection, path), path);
  if (!m.sections.count(kTrackingSection))
    throw Error(path, "has no keyframes (it was mapped with external poses): it cannot be relocalised into another map");
  m.tracking = decode_tracker_state(m.sections.at(kTrackingSection), path);
  return m;
}

void require_mergeable(const SavedMap& a, const SavedMap& b) {
  if (!(a.camera.depth == b.camera.depth) || a.camera.distortion != b.camera.distortion)
    throw Error(b.path, "was made with another depth camera than " + a.path.string() + " (" +
                            describe_camera_difference(b.camera, a.camera) +
                            "): keyframes compare only within one camera");
  require_same_ferns(a.config.tracking, b.config.tracking, b.path);
  require_same_voxel_layout(a.config.tsdf, b.config.tsdf, b.path.string());
}

/// The aligned maps fused into A's sections (TSDF, objects, keyframes and pose graph).
ArchiveSections fuse(const SavedMap& a, const SavedMap& b, const MapAlignment& alignment, MapMergeResult& r) {
  TsdfMap tsdf = decode_tsdf_section(archive_section(a.sections, kTsdfSection, a.path), a.path, a.config.tsdf);
  const TsdfMap other = decode_tsdf_section(archive_section(b.sections, kTsdfSection, b.path), b.path, a.config.tsdf);
  r.blocks_a = tsdf.num_blocks();
  r.blocks_b = other.num_blocks();
  r.voxels_fused = merge_tsdf(tsdf, other, alignment.T_this_other).voxels_fused;
  r.blocks = tsdf.num_blocks();

  ObjectMapper objects(a.config.objects, a.camera);
  objects.restore_state(archive_section(a.sections, kObjectsSection, a.path), a.path);
  // Best views (issue 43; absent from older maps): B's follow its objects' new ids.
  if (const auto views = a.sections.find(kObjectViewsSection); views != a.sections.end())
    objects.restore_views(views->second, a.path);
  const auto b_views = b.sections.find(kObjectViewsSection);
  r.objects_a = objects.instances().size();
  const ObjectMapMergeCounts counts =
      objects.merge_state(archive_section(b.sections, kObjectsSection, b.path), b.path,
                          alignment.T_this_other.cast<float>(), b_views == b.sections.end() ? nullptr : &b_views->second);
  r.objects_b = counts.merged + counts.added;
  r.objects_merged = counts.merged;
  r.objects = objects.instances().size();

  ArchiveSections out = a.sections;  // camera and configuration are A's
  out[kTsdfSection] = encode_tsdf_section(tsdf);
  out[kObjectsSection] = objects.encode_state();
  out[kObjectViewsSection] = objects.encode_views();
  out[kTrackingSection] = encode_tracker_state(append_tracker_state(a.tracking, b.tracking, alignment.T_this_other, alignment.links));
  return out;
}

std::string recording_name(const fs::path& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();  // "out/"
  return p.filename().empty() ? "recording" : p.filename().string();
}

/// A folder's recordings: its <name>.trajectory.txt files (a merged folder), else its
/// trajectory.txt named after the folder (a `semap run` folder).
std::vector<std::pair<std::string, Trajectory>> recordings_of(const fs::path& dir) {
  static const std::string kSuffix = ".trajectory.txt";
  std::vector<std::pair<std::string, Trajectory>> out;
  std::set<fs::path> named;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && name.size() > kSuffix.size() && name.ends_with(kSuffix)) named.insert(entry.path());
  }
  for (const fs::path& p : named) {
    const std::string name = p.filename().string();
    out.emplace_back(name.substr(0, name.size() - kSuffix.size()), read_tum_trajectory(p));
  }
  if (out.empty() && fs::is_regular_file(dir / "trajectory.txt"))
    out.emplace_back(recording_name(dir), read_tum_trajectory(dir / "trajectory.txt"));
  return out;
}

/// The output folder of a map given as the folder or its map.semap.
fs::path folder_of(const fs::path& p) { return map_file_of(p).parent_path(); }

/// Writes every recording's trajectory in A's world frame; B's names made unique.
std::vector<std::string> write_trajectories(const fs::path& a, const fs::path& b, const Pose& T_a_b, const fs::path& dir) {
  std::vector<std::string> written;
  std::set<std::string> used;
  auto write = [&](std::string name, Trajectory trajectory) {
    for (int k = 2; used.count(name); ++k) name = name + "_" + std::to_string(k);
    used.insert(name);
    write_tum_trajectory(dir / (name + ".trajectory.txt"), trajectory);
    written.push_back(name);
  };
  for (auto& [name, trajectory] : recordings_of(folder_of(a))) write(name, std::move(trajectory));
  for (auto& [name, trajectory] : recordings_of(folder_of(b))) {
    for (StampedPose& p : trajectory) p.T_world_camera = orthonormalized(T_a_b * p.T_world_camera);
    write(name, std::move(trajectory));
  }
  return written;
}

/// merge_map_files; `config` gets A's configuration (the merged map's).
MapMergeResult merge_files(const fs::path& a_path, const fs::path& b_path, const fs::path& out_map, SemapConfig& config) {
  const SavedMap a = read_saved_map(a_path), b = read_saved_map(b_path);
  require_mergeable(a, b);
  config = a.config;
  MapMergeResult r;
  r.keyframes_a = a.tracking.keyframes.size();
  r.keyframes_b = b.tracking.keyframes.size();
  auto t0 = Clock::now();
  Tracker tracker(a.config.tracking, a.camera);
  tracker.resume(a.tracking);
  const MapAlignment alignment = align_maps(tracker, b.tracking);
  r.relocalisation_s = seconds_since(t0);
  r.keyframes_verified = alignment.keyframes_verified;
  r.keyframes_agreeing = alignment.keyframes_agreeing;
  if (!alignment.aligned) {
    r.reason = "does not relocalise into " + a_path.string() + ": " + alignment.reason;
    return r;
  }
  t0 = Clock::now();
  r.T_a_b = alignment.T_this_other;
  write_map_archive(out_map, fuse(a, b, alignment, r));
  r.fusion_s = seconds_since(t0);
  r.merged = true;
  return r;
}

}  // namespace

MapMergeResult merge_map_files(const fs::path& a, const fs::path& b, const fs::path& out_map) {
  SemapConfig config;
  return merge_files(a, b, out_map, config);
}

MapMergeResult merge_maps(const fs::path& a, const fs::path& b, const fs::path& out_dir) {
  for (const fs::path& input : {a, b})
    if (!fs::exists(input)) throw Error(input, "input map is " + describe_path(input));
  std::error_code ec;
  if (fs::equivalent(map_file_of(a), map_file_of(b), ec))
    throw Error(b, "is the same map as " + a.string() + ": merging a map with itself would duplicate its keyframes");
  // Never an input map's folder nor a folder holding one (issue 44).
  const std::vector<fs::path> inputs = {fs::absolute(map_file_of(a)).parent_path(), fs::absolute(map_file_of(b)).parent_path()};
  OutputFolder out(out_dir, {.tool = "merge", .publish_last = {"report.json"}, .inputs = inputs});
  const fs::path dir = out.staging();
  SemapConfig config;
  MapMergeResult r = merge_files(map_file_of(a), map_file_of(b), dir / "map.semap", config);
  if (!r.merged) return r;  // out's destructor removes the staging folder: nothing written
  // The merged map as a Mapper gives the mesh and objects exactly as `semap run` writes them;
  // no segmenter is needed to read it.
  config.segmentation.segmenter = "none";
  const auto mapper = Mapper::load(dir / "map.semap", config);
  write_ply(dir / "mesh.ply", mapper->mesh());
  write_objects(mapper->objects(), dir);
  r.trajectories = write_trajectories(a, b, r.T_a_b, dir);
  write_file_atomic(dir / "report.json", to_json(r).dump(2) + "\n");
  throw_if_interrupted();
  out.publish();
  return r;
}

nlohmann::json to_json(const MapMergeResult& r) {
  nlohmann::json summary = {{"merged", r.merged},
                            {"keyframes_a", r.keyframes_a},
                            {"keyframes_b", r.keyframes_b},
                            {"keyframes_b_relocalised", r.keyframes_verified},
                            {"keyframes_b_agreeing", r.keyframes_agreeing},
                            {"objects_a", r.objects_a},
                            {"objects_b", r.objects_b},
                            {"objects_b_merged_into_a", r.objects_merged},
                            {"objects", r.objects},
                            {"tsdf_blocks_a", r.blocks_a},
                            {"tsdf_blocks_b", r.blocks_b},
                            {"tsdf_blocks", r.blocks},
                            {"voxels_fused", r.voxels_fused},
                            {"relocalisation_s", r.relocalisation_s},
                            {"fusion_s", r.fusion_s}};
  if (!r.merged) summary["reason"] = r.reason;
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({r.T_a_b(i, 0), r.T_a_b(i, 1), r.T_a_b(i, 2), r.T_a_b(i, 3)});
  return {{"summary", summary}, {"T_a_b", rows}, {"trajectories", r.trajectories}};
}

}  // namespace semap
