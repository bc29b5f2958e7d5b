#pragma once
// Merging two saved maps of the same place made independently (issue 19): `semap merge A B
// --out C`, semap.merge_maps in Python, and the fleet's merge tree.
//
//   const MapMergeResult r = semap::merge_maps("mon/map.semap", "tue/map.semap", "merged");
//   if (!r.merged) std::puts(r.reason.c_str());   // nothing written
//
// How: B's keyframes are relocalised into A's keyframe database (METHODS.md A3 + A2, as a lost
// frame is) and the alignments they imply must agree (tracking/map_alignment.hpp); B's TSDF is
// resampled into A's grid and fused (sdf, colour, compact and Bayesian labels), B's objects
// join A's object map (merged with the ones they overlap, C5 tests 3 + 4), B's keyframes and
// pose graph are appended in A's world frame with the verifying registrations as loop edges.
// The result is a complete map.semap: it can be resumed (`semap run --resume`) or merged again.
// A and B are only read. Both must be tracked maps (keyframes) of the same camera and tsdf
// settings; the configuration is A's.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "semap/core/pose.hpp"

namespace semap {

struct MapMergeResult {
  bool merged = false;
  std::string reason;                 ///< why not, when not merged ("does not relocalise into A: ...")
  Pose T_a_b = Pose::Identity();      ///< B's world frame in A's (metres)
  size_t keyframes_a = 0, keyframes_b = 0;
  size_t keyframes_verified = 0;      ///< B's keyframes that relocalised into A
  size_t keyframes_agreeing = 0;      ///< of those, agreeing on T_a_b
  size_t objects_a = 0, objects_b = 0;
  size_t objects_merged = 0;          ///< B's objects folded into one of A's
  size_t objects = 0;                 ///< in the merged map
  size_t blocks_a = 0, blocks_b = 0, blocks = 0;  ///< TSDF blocks
  size_t voxels_fused = 0;            ///< A-grid voxels that received B's measurements
  double relocalisation_s = 0.0, fusion_s = 0.0;
  /// Recording name -> trajectory file written (merge_maps with an output folder).
  std::vector<std::string> trajectories;
};

/// report.json of `semap merge`: {"summary": {...}, "T_a_b": 4x4 rows}.
nlohmann::json to_json(const MapMergeResult& result);

/// Merges map B into map A's world frame and writes the merged map.semap to `out_map` (only
/// when merged). `a`, `b`: map.semap files. Throws semap::Error naming the file for an
/// unreadable map, one without keyframes, another camera or other tsdf settings.
MapMergeResult merge_map_files(const std::filesystem::path& a, const std::filesystem::path& b,
                               const std::filesystem::path& out_map);

/// merge_map_files on two output folders (of `semap run`, or of an earlier merge; a map.semap
/// file is taken as its folder), published into `out_dir` as a whole when merged (staging
/// folder, io/output_folder.hpp; nothing is written otherwise): map.semap, mesh.ply,
/// objects.json + objects/<id>.ply, report.json, and every recording's trajectory in A's world
/// frame as <recording>.trajectory.txt (a run folder's trajectory.txt is named after the
/// folder; a merged folder's <recording>.trajectory.txt files are carried on, B's moved by
/// T_a_b; a repeated name gets _2). Throws semap::Error for a missing input or `out_dir` being
/// an input's folder, and as merge_map_files.
MapMergeResult merge_maps(const std::filesystem::path& a, const std::filesystem::path& b,
                          const std::filesystem::path& out_dir);

}  // namespace semap
