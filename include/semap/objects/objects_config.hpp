#pragma once
#include <string>

#include "semap/core/params.hpp"

namespace semap {

/// C2: how a frame's masks become object segments.
enum class SegmentationMode { supervoxel, backprojection };
inline constexpr EnumNames<SegmentationMode, 2> kSegmentationModeNames{
    {{SegmentationMode::supervoxel, "supervoxel"}, {SegmentationMode::backprojection, "backprojection"}}};

/// C4: which instances are a segment's candidates (and have their association count raised).
enum class AssociationGate {
  centroid,  ///< as printed: centroid distance below association_distance
  extent,    ///< the instance's box, grown by association_box_margin, meets the segment's box
};
inline constexpr EnumNames<AssociationGate, 2> kAssociationGateNames{
    {{AssociationGate::centroid, "centroid"}, {AssociationGate::extent, "extent"}}};

/// C5 test (4): the label distributions the Jensen-Shannon divergence compares.
enum class MergeDistribution {
  augmented,  ///< as printed: mean scores with the residual 1 - sum as component 0 ("other")
  evidence,   ///< the classes' shares of the summed scores (the residual left out)
};
inline constexpr EnumNames<MergeDistribution, 2> kMergeDistributionNames{
    {{MergeDistribution::augmented, "augmented"}, {MergeDistribution::evidence, "evidence"}}};

/// Parameters of the object map (METHODS.md C2-C5).
struct ObjectsConfig {
  // --- C2: per-keyframe segmentation ---
  SegmentationMode segmentation_mode = SegmentationMode::supervoxel;  ///< C2 guided clustering, or plain mask back-projection
  int pixel_stride = 2;            ///< use every N-th pixel when building the frame cloud (C2 clustering)
  int point_stride = 1;            ///< every N-th pixel gives object points (<= pixel_stride: joins its cell's segment)
  double dense_depth_tolerance = 0.02;  ///< m per m of depth: a dense point joins its cell's segment within this depth gap
  double max_depth = 5.0;          ///< m, ignore depth beyond this
  double voxel_resolution = 0.01;  ///< m, VCCS voxel size
  double seed_resolution = 0.06;   ///< m, VCCS seed spacing (supervoxel size)
  double colour_importance = 0.2;  ///< VCCS colour weight
  double spatial_importance = 0.4; ///< VCCS spatial weight
  double normal_importance = 1.0;  ///< VCCS normal weight
  double supervoxel_adopt_radius = 0.03;  ///< m, points VCCS leaves unowned join the nearest supervoxel within this (0: dropped)
  double plane_max_curvature = 0.04;  ///< supervoxels below this curvature may belong to a support plane (C2.4)
  double plane_max_angle_deg = 10.0;  ///< deg, max normal angle between supervoxels of one plane
  double plane_max_distance = 0.02;   ///< m, max point-to-plane distance of a supervoxel centre
  int plane_min_supervoxels = 4;      ///< smaller planar regions get plane label 0
  double plane_min_extent = 0.3;      ///< m, a support plane's centres must span at least this
  double convex_sanity_angle_deg = 60.0;  ///< deg, LCCP sanity criterion: min angle between c_i-c_j and n_i x n_j
  double weight_different_masks = 3.0;  ///< omega_diff (C2.3), must exceed weight_background
  double weight_background = 1.0;       ///< omega_bg (C2.3), > 0
  double felzenszwalb_k = 2.0;          ///< K of the graph clustering (C2.5)
  bool point_mask_refinement = true;    ///< extension to C2.6: a segment keeps only points whose own pixel has its mask; VCCS-unowned points follow their mask
  int min_segment_points = 50;          ///< object segments with fewer points are dropped
  double mask_min_score = 0.0;          ///< detections below this score are ignored
  double mask_depth_gate_k = 0.0;       ///< > 0: mask pixels beyond median +- k * sigma_MAD of the mask's depth are background (0: off; k = 3 cost D10 GT-mask WOv 0.79 -> 0.78 and did not shrink redkitchen boxes)
  double mask_depth_gate_min = 0.1;     ///< m per m of median depth: the gate is never narrower than this

  // --- C3/C4: map and association ---
  double map_voxel_size = 0.01;       ///< m, instance point sets are voxel-downsampled to this
  double association_distance = 1.0;  ///< m, d_assoc: centroid distance gate (C4)
  /// Extent by default: with the 1 m centroid gate every instance of a cluttered kitchen is a
  /// candidate of dozens of segments, so s_i grew for all of them and C5 never deleted one.
  AssociationGate association_gate = AssociationGate::extent;
  double association_box_margin = 0.05;  ///< m, extent gate: the instance's box is grown by this
  double association_class_share = 0.2;  ///< a segment merges only into an instance whose evidence gives its class this share (0: any class, as printed)
  double overlap_distance = 0.03;     ///< m, d_point: a segment point overlaps when an instance point is this close
  double overlap_ratio = 0.5;         ///< r: overlap fraction above which a segment merges (C4)
  bool reverse_containment = true;    ///< extension: also merge when the segment covers an instance of its class
  double reverse_containment_ratio = 0.8;  ///< fraction of the instance's points the segment must cover

  // --- C5: optimisation ---
  bool enable_optimisation = true;  ///< run C5 every optimise_every frames
  bool enable_merge = true;         ///< C5 merge of stable pairs
  bool enable_delete = true;        ///< C5 deletion of rarely associated instances
  int optimise_every = 50;          ///< T, frames between map optimisations (C5)
  int stable_min_associations = 5;  ///< s_i at or above this promotes to STABLE
  double delete_fraction = 0.1;     ///< delete when s_i + n_i < delete_fraction * T (and unseen recently)
  int recent_frames = 10;           ///< frames: instances seen this recently are never deleted
  double merge_coassociation = 0.7; ///< co-association count must exceed this fraction of s_i or s_j
  double merge_overlap_ratio = 0.3; ///< geometric overlap (C4 formula, smaller onto larger) needed to merge
  double merge_containment_ratio = 0.5;  ///< extension to C5 (3): or this fraction of the smaller's points inside the larger's box
  double merge_body_link_distance = 0.1;  ///< m, C5 containment: the larger instance's box is that of its largest cluster linked within this (0: all points)
  double merge_max_js = 0.3;        ///< nats, max Jensen-Shannon divergence of the label distributions
  /// Evidence by default: a detector that gives one class and its score (YOLO) leaves a residual
  /// of 0.5-0.7 that dominates the augmented vectors, so a cup (0.3) on a table (0.4) scored JS
  /// 0.25 < 0.3 and redkitchen's table, chairs and mugs merged into one object.
  MergeDistribution merge_distribution = MergeDistribution::evidence;
  double class_min_share = 0.5;     ///< the argmax class needs this share of the class evidence, else other (C3)
  bool absorb_fragments = true;     ///< extension: a deleted instance's points join a stable same-class instance it overlaps (C5 tests 3, 4)
  bool final_optimisation = true;   ///< finish() runs one more optimisation, ignoring recency
  bool accumulate_between_keyframes = true;  ///< extension to C3: ObjectMapper::accumulate() adds the masks' points of non-keyframes to matching instances
  double box_cluster_distance = 0.05;  ///< exported boxes: points of the largest cluster with this linking distance (m, 0 = all points)
  double box_trim_fraction = 0.01;     ///< exported boxes: this fraction of the points is ignored at each end of every axis
  bool points_on_surface = true;       ///< exported points (objects.json, objects/<id>.ply, boxes) projected onto the fused TSDF surface
  bool drop_points_of_other_classes = true;  ///< exported points the fused TSDF labels as another class are left out (a minority of the object's)

  void visit(ParamVisitor& v) {
    const ParamRange<int> at_least_one{1};
    v.param("segmentation_mode", segmentation_mode, kSegmentationModeNames, "supervoxel (C2 guided clustering) or backprojection (masks only)");
    v.param("pixel_stride", pixel_stride, "px", "use every N-th pixel for the frame cloud", {1, 64});
    v.param("point_stride", point_stride, "px", "every N-th pixel gives object points; finer than pixel_stride joins its cell's segment", {1, 64});
    v.param("dense_depth_tolerance", dense_depth_tolerance, "m/m", "max depth gap (per m of depth) of a dense point to its cell's sample", positive(1.0));
    v.param("max_depth", max_depth, "m", "ignore depth beyond this", positive(100.0));
    v.param("voxel_resolution", voxel_resolution, "m", "VCCS voxel size (C2.1)", {0.001, 0.5});
    v.param("seed_resolution", seed_resolution, "m", "VCCS seed spacing (C2.1)", positive(5.0));
    v.param("colour_importance", colour_importance, "", "VCCS colour weight", non_negative());
    v.param("spatial_importance", spatial_importance, "", "VCCS spatial weight", non_negative());
    v.param("normal_importance", normal_importance, "", "VCCS normal weight", non_negative());
    v.param("supervoxel_adopt_radius", supervoxel_adopt_radius, "m", "unowned VCCS points join the nearest supervoxel within this; 0 drops them (C2.1)", non_negative(1.0));
    v.param("plane_max_curvature", plane_max_curvature, "", "max supervoxel curvature for support planes (C2.4)", non_negative(1.0));
    v.param("plane_max_angle_deg", plane_max_angle_deg, "deg", "max normal angle within a support plane", {0.0, 90.0});
    v.param("plane_max_distance", plane_max_distance, "m", "max distance of a supervoxel centre to its plane", non_negative(1.0));
    v.param("plane_min_supervoxels", plane_min_supervoxels, "", "min supervoxels of a support plane", at_least_one);
    v.param("plane_min_extent", plane_min_extent, "m", "min extent of a support plane", non_negative(100.0));
    v.param("convex_sanity_angle_deg", convex_sanity_angle_deg, "deg", "LCCP sanity criterion angle (C2.4)", {0.0, 90.0});
    v.param("weight_different_masks", weight_different_masks, "", "omega_diff (C2.3), must exceed weight_background", positive());
    v.param("weight_background", weight_background, "", "omega_bg (C2.3)", positive());
    v.param("felzenszwalb_k", felzenszwalb_k, "", "K of the graph clustering (C2.5)", positive());
    v.param("point_mask_refinement", point_mask_refinement, "", "extension to C2.6: a segment keeps only the points whose pixel carries its mask; points in no supervoxel follow their mask");
    v.param("min_segment_points", min_segment_points, "points", "drop smaller object segments", at_least_one);
    v.param("mask_min_score", mask_min_score, "", "ignore detections below this score", fraction());
    v.param("mask_depth_gate_k", mask_depth_gate_k, "", "mask pixels farther than k robust sigmas (1.4826 MAD) from the mask's median depth are background; 0 off", non_negative());
    v.param("mask_depth_gate_min", mask_depth_gate_min, "m/m", "minimum half-width of the mask depth gate, per m of median depth", non_negative());
    v.param("map_voxel_size", map_voxel_size, "m", "voxel size of instance point sets (C3)", {0.001, 1.0});
    v.param("association_distance", association_distance, "m", "d_assoc centroid gate (C4)", positive(100.0));
    v.param("association_gate", association_gate, kAssociationGateNames, "C4 candidates: centroid (distance below association_distance, as printed) or extent (the instance's box, grown by association_box_margin, meets the segment's box)");
    v.param("association_box_margin", association_box_margin, "m", "extent gate: margin added to the instance's box", non_negative(1.0));
    v.param("association_class_share", association_class_share, "", "extension to C4: a segment merges only into an instance whose class evidence gives the segment's class at least this share; 0 class-agnostic as printed (a mug mask bleeding onto the table joined the table)", fraction());
    v.param("overlap_distance", overlap_distance, "m", "d_point of the overlap test (C4)", positive(1.0));
    v.param("overlap_ratio", overlap_ratio, "", "r, overlap fraction to merge a segment (C4)", fraction());
    v.param("reverse_containment", reverse_containment, "", "extension to C4: merge when the segment covers most of a same-class instance");
    v.param("reverse_containment_ratio", reverse_containment_ratio, "", "fraction of the instance covered for reverse_containment", fraction());
    v.param("enable_optimisation", enable_optimisation, "", "run the C5 optimisation");
    v.param("enable_merge", enable_merge, "", "C5 merge of stable pairs");
    v.param("enable_delete", enable_delete, "", "C5 deletion of rare instances");
    v.param("optimise_every", optimise_every, "frames", "T: optimise the object map every T frames (C5)", at_least_one);
    v.param("stable_min_associations", stable_min_associations, "", "s_i needed for STABLE (C5)", {0});
    v.param("delete_fraction", delete_fraction, "", "delete when s_i + n_i < fraction * T (C5)", non_negative());
    v.param("recent_frames", recent_frames, "frames", "instances seen this recently are kept (C5)", {0});
    v.param("merge_coassociation", merge_coassociation, "", "co-association fraction for merging (C5)", fraction());
    v.param("merge_overlap_ratio", merge_overlap_ratio, "", "overlap needed for merging (C5 test 3): points of the smaller within d_point of the larger", fraction());
    v.param("merge_containment_ratio", merge_containment_ratio, "", "extension to C5 test 3: or this fraction of the smaller's points inside the larger's box (views of an object from opposite sides share no surface); 1 off", fraction());
    v.param("merge_body_link_distance", merge_body_link_distance, "m", "extension to C5 test 3: the containment box is that of the larger instance's largest cluster linked within this distance, trimmed by box_trim_fraction (stray points a bleeding mask left across a touching neighbour made the two one object); 0 = the box of all points", non_negative(1.0));
    v.param("merge_max_js", merge_max_js, "nats", "max JS divergence for merging (C5)", {0.0, 0.6932});
    v.param("merge_distribution", merge_distribution, kMergeDistributionNames, "label distributions of the C5 JS test (4): evidence (class shares of the summed scores) or augmented (mean scores + residual as other, as printed)");
    v.param("class_min_share", class_min_share, "", "an object takes the class with the most evidence only when it holds this share of the class evidence, else other (C3)", fraction());
    v.param("absorb_fragments", absorb_fragments, "", "extension to C5: points of a deleted instance overlapping a stable one of its class join it");
    v.param("final_optimisation", final_optimisation, "", "finish() optimises once more, ignoring recency");
    v.param("accumulate_between_keyframes", accumulate_between_keyframes, "", "extension to C3: segmented frames between object keyframes add their mask points to instances they overlap (never create, never count)");
    v.param("box_cluster_distance", box_cluster_distance, "m", "exported boxes enclose the largest cluster of the instance's points linked within this distance (0 = all points)", non_negative(1.0));
    v.param("box_trim_fraction", box_trim_fraction, "", "exported boxes ignore this fraction of the points at each end of every axis (stray depth-edge points)", {0.0, 0.49});
    v.param("points_on_surface", points_on_surface, "", "exported object points (and their boxes) are moved onto the fused TSDF surface: one frame's back-projection carries its depth noise, the TSDF averages every frame (the map keeps the raw points for association)");
    v.param("drop_points_of_other_classes", drop_points_of_other_classes, "", "with points_on_surface: exported points where the fused TSDF label (the mesh's) names another class are left out, when they are a minority of the object's (a mask that bled over a cup put the cup in the table; where most points disagree the object's class is in doubt, not its points)");
  }
  /// Ranges come from visit(); the rules between parameters are here.
  void validate() const {
    check_param_ranges(*this, "objects");
    require_param(seed_resolution > voxel_resolution, "objects.seed_resolution", "must exceed voxel_resolution");
    require_param(weight_different_masks > weight_background, "objects.weight_different_masks",
                  "must exceed weight_background");
  }
};

}  // namespace semap
