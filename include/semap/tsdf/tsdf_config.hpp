#pragma once
#include <algorithm>
#include <string>

#include "semap/core/depth_noise_model.hpp"
#include "semap/core/params.hpp"

namespace semap {

/// How a frame is fused (METHODS B5-B6).
enum class IntegratorKind {
  projective,  ///< voxels projected into the image (nvblox/Open3D style): the default, fastest
  grouped,     ///< semantic grouped ray casting of seed 003 (B5 + B6)
};
inline constexpr EnumNames<IntegratorKind, 2> kIntegratorNames{
    {{IntegratorKind::projective, "projective"}, {IntegratorKind::grouped, "grouped"}}};

/// What the mesh's vertex colour shows (the class id is written as its own property either way).
enum class MeshColour {
  rgb,           ///< the fused surface colour (the class palette when there is no colour layer)
  class_palette, ///< the class colours of core/labels.hpp
};
inline constexpr EnumNames<MeshColour, 2> kMeshColourNames{{{MeshColour::rgb, "rgb"}, {MeshColour::class_palette, "class"}}};

/// Parameters of the dense semantic TSDF (METHODS.md B3-B7, A6).
struct TsdfConfig {
  // Geometry (METHODS B4, B6).
  double voxel_size = 0.02;        ///< s, metres
  double truncation_voxels = 4.0;  ///< delta = truncation_voxels * s (B6: 4)
  double epsilon_voxels = 1.0;     ///< epsilon = epsilon_voxels * s, start of the drop-off (B6: 1)
  // The depth range has one name in every stage (tracking, tsdf, objects: min/max_depth); the
  // values differ on purpose: fusion keeps 0.1-5 m (more of the room, the weight 1/z^2 already
  // discounts far depth), tracking registers on 0.2-4.5 m, where depth noise (~z^2) is low.
  double min_depth = 0.1;          ///< depth below this is not fused, metres
  double max_depth = 5.0;          ///< depth beyond this is not fused, metres
  IntegratorKind integrator = IntegratorKind::projective;
  int threads = 0;                 ///< worker threads, 0 = all cores
  int allocation_stride = 2;       ///< projective: every n-th pixel (each axis) allocates blocks

  // Weight quantisation (METHODS B3): u8 weight on a log scale,
  // W(q) = weight_unit * (exp(q * ln(1 + weight_max / weight_unit) / 255) - 1).
  double weight_unit = 0.01;   ///< w0: finest weight resolution (weights are 1/z^2, z in m)
  double weight_max = 1000.0;  ///< W_max of B6 (W <- min(W + w, W_max))

  // Labels (B6 compact rule, A6 Bayesian layer).
  bool label_layer = true;       ///< compact vote: label byte + 1-byte vote confidence per voxel
  bool bayes_layer = true;       ///< Bayesian top-k class probabilities per voxel (A6); default by measurement: semap demo (20 % flicker) mIoU 0.943 vs 0.863 compact vote, clean labels equal
  int bayes_top_k = 4;           ///< k classes kept per voxel (2 bytes each)
  double bayes_default_confidence = 0.7;  ///< P(label) when only labels are given
  int bayes_confusion_classes = 4;        ///< m: a wrong label is one of ~m confusable classes (A6 likelihood)
  double bayes_min_probability = 1e-5;    ///< floor of a class probability (keeps Bayes non-absorbing)
  double label_band_voxels = 2.0;  ///< labels update only voxels with |d| <= this * s ...
  /// ... or within this many sigma(z) of the depth noise, at most the truncation: a far surface's
  /// depth scatters beyond 2 voxels (Kinect v1 at 4 m: sigma 2.6 cm), and its fused zero crossing
  /// then missed most frames' labels (TUM fr1_rpy: 21 % of the mesh area never labelled).
  double label_band_sigmas = 3.0;
  /// A mesh vertex whose voxel was never labelled reads the nearest labelled voxel along its
  /// normal within this many voxels, at most the truncation (for the mesh-time rules,
  /// tsdf/voxel_label.hpp; 0 = its own voxel only).
  double label_evidence_reach_voxels = 4.0;
  DepthNoiseModel depth_noise;     ///< the sensor's depth noise (label band)

  // Colour.
  bool colour_layer = true;   ///< RGB per voxel (3 bytes), weighted mean like the sdf; on by default (coloured meshes)

  // Mesh (B7).
  MeshColour mesh_colour = MeshColour::rgb;
  double mesh_min_weight = 0.0;       ///< cube corners need a weight above this to be meshed
  int mesh_min_label_votes = 2;       ///< compact label shown only with this vote margin (else 0)
  double mesh_min_label_probability = 0.9;  ///< Bayesian argmax shown only above this (else 0)
  int mesh_min_label_frames = 3;  ///< Bayesian argmax shown only when it leads the runner-up by this many frames' votes

  // Geometry-aware label decision on the mesh (issue 38, tsdf/label_priors.hpp; gravity and the
  // floor height from core/gravity). Each rule can be switched off to measure it.
  bool label_prior_normals = true;   ///< floor faces up, ceiling down, wall vertical; others unlabelled
  bool label_prior_heights = true;   ///< floor near the floor height, ceiling high (needs a floor)
  bool label_prior_regions = true;   ///< planar regions' fitting majority fills their parts
  double label_prior_max_tilt_deg = 20.0;       ///< normal tolerance of the class rules
  double label_prior_floor_band_m = 0.08;       ///< floor within this of the floor height
  double label_prior_min_ceiling_height_m = 1.8;  ///< ceiling at least this above the floor
  double label_prior_region_normal_deg = 15.0;  ///< region: triangle normal within this of the region's
  double label_prior_region_plane_m = 0.04;     ///< region: triangle centroid within this of its plane
  double label_prior_region_min_area_m2 = 0.25; ///< smaller regions decide nothing
  double label_prior_region_min_share = 0.5;    ///< the region's class holds this share of its labelled area
  bool label_prior_segments = true;             ///< smooth segments' fitting majority fills their unlabelled parts
  double label_prior_segment_k = 0.01;          ///< Felzenszwalb-Huttenlocher K on normal differences (1 - cos)
  double label_prior_segment_min_labelled = 0.3;  ///< a segment decides when this share of its area is labelled
  bool label_prior_likely = true;  ///< a vertex still unlabelled takes its likely fitting class
  double label_prior_likely_probability = 0.0;  ///< ... when it holds this share of the fitting (0: the most probable)
  bool label_prior_other = true;  ///< a ruled-out structural label that nothing fitting replaces becomes `other`
  bool label_prior_fringes = true;  ///< unlabelled seams near labelled surface of their smooth segment take its fitting class
  double label_prior_fringe_m = 0.05;  ///< ... within this distance along the mesh of the labelled surface

  // Memory for long runs.
  double drop_distance = 0.0;  ///< blocks farther than this from the camera are freed, m (0 = keep all)

  /// Odds one label-only frame adds to its label against any other class (METHODS A6 likelihood
  /// of ClassDistribution::from_label): r = c m / (1 - c), at least 1.
  double bayes_frame_odds() const {
    return std::max(1.0, bayes_default_confidence * bayes_confusion_classes / (1.0 - bayes_default_confidence));
  }
  double truncation() const { return truncation_voxels * voxel_size; }
  double epsilon() const { return epsilon_voxels * voxel_size; }

  void visit(ParamVisitor& v) {
    v.param("voxel_size", voxel_size, "m", "voxel edge length s (from 1 mm: memory grows as 1/s^2 per frame)", {0.001, 1.0});
    v.param("truncation_voxels", truncation_voxels, "voxels", "truncation delta = this * s (METHODS B6: 4)", {1.0, 16.0});
    v.param("epsilon_voxels", epsilon_voxels, "voxels", "behind-surface weight drop-off starts at -this * s (B6: 1)", non_negative(16.0));
    v.param("min_depth", min_depth, "m", "depth below this is not fused (tracking has its own range)", non_negative(100.0));
    v.param("max_depth", max_depth, "m", "depth beyond this is not fused", positive(100.0));
    v.param("integrator", integrator, kIntegratorNames,
            "projective (voxels projected into the image) | grouped (semantic grouped ray casting, B5+B6)");
    v.param("threads", threads, "", "integration/meshing threads, 0 = all cores", {0, 1024});
    v.param("allocation_stride", allocation_stride, "px",
            "projective integrator: every n-th pixel in each axis allocates blocks (Open3D uses 4)", {1, 16});
    v.param("weight_unit", weight_unit, "", "finest step of the log-quantised u8 voxel weight", positive(1e6));
    v.param("weight_max", weight_max, "", "maximum accumulated voxel weight W_max (B6)", positive(1e9));
    v.param("label_layer", label_layer, "", "keep the compact label byte with its 1-byte vote confidence");
    v.param("bayes_layer", bayes_layer, "", "keep per-voxel top-k class probabilities (METHODS A6)");
    v.param("bayes_top_k", bayes_top_k, "classes", "classes kept per voxel by the Bayesian layer", {1, 8});
    v.param("bayes_default_confidence", bayes_default_confidence, "", "P(observed label) when no confidence/probabilities are given", {0.0, 0.999, true});
    v.param("bayes_confusion_classes", bayes_confusion_classes, "classes",
            "label-only likelihood: a wrong label falls on one of this many confusable classes, so one frame "
            "multiplies a label's odds by c*m/(1-c) (37 = errors spread over every class)", {1, 37});
    v.param("bayes_min_probability", bayes_min_probability, "", "floor of any class probability in the Bayesian layer", {0.0, 0.1, true});
    v.param("label_band_voxels", label_band_voxels, "voxels", "labels update voxels with |sdf| <= this * s ...", positive(16.0));
    v.param("label_band_sigmas", label_band_sigmas, "",
            "... or <= this many depth-noise sigmas of the measured depth (far, noisy depth), at most the truncation",
            non_negative(100.0));
    v.param("label_evidence_reach_voxels", label_evidence_reach_voxels, "voxels",
            "a mesh vertex whose voxel was never labelled reads the nearest labelled voxel along its normal within this reach, at most the truncation (mesh-time label rules; 0: its own voxel only)",
            {0.0, 8.0});
    depth_noise.visit(v);
    v.param("colour_layer", colour_layer, "", "keep an RGB colour per voxel");
    v.param("mesh_colour", mesh_colour, kMeshColourNames,
            "vertex colour: rgb (colour layer, palette without one) | class (palette); the label property is written either way");
    v.param("mesh_min_weight", mesh_min_weight, "", "cube corners need a weight above this to be meshed", non_negative());
    v.param("mesh_min_label_votes", mesh_min_label_votes, "frames",
            "a vertex shows the compact label only when its vote margin reaches this (else unlabelled)", {0, 255});
    v.param("mesh_min_label_probability", mesh_min_label_probability, "",
            "a vertex shows the Bayesian argmax only when its probability reaches this (else unlabelled)", {0.0, 0.999});
    v.param("mesh_min_label_frames", mesh_min_label_frames, "frames",
            "a vertex shows the Bayesian argmax only when its odds against the runner-up reach r^this, "
            "r = c*m/(1-c) the odds one label-only frame adds (c, m: bayes_default_confidence, bayes_confusion_classes)", {0, 16});
    v.param("label_prior_normals", label_prior_normals, "",
            "mesh labels: a floor vertex must face up, a ceiling down, a wall be vertical (else unlabelled)");
    v.param("label_prior_heights", label_prior_heights, "",
            "mesh labels: floor within label_prior_floor_band_m of the estimated floor, ceiling above label_prior_min_ceiling_height_m");
    v.param("label_prior_regions", label_prior_regions, "",
            "mesh labels: a planar gravity-aligned region's fitting majority class fills its unlabelled and contradicting vertices");
    v.param("label_prior_max_tilt_deg", label_prior_max_tilt_deg, "deg", "normal tolerance of the floor/ceiling/wall rules", {1.0, 60.0});
    v.param("label_prior_floor_band_m", label_prior_floor_band_m, "m", "floor labels lie within this of the floor height", positive(10.0));
    v.param("label_prior_min_ceiling_height_m", label_prior_min_ceiling_height_m, "m", "ceiling labels lie at least this above the floor", non_negative(100.0));
    v.param("label_prior_region_normal_deg", label_prior_region_normal_deg, "deg", "region growing: normal within this of the region's mean", {1.0, 45.0});
    v.param("label_prior_region_plane_m", label_prior_region_plane_m, "m", "region growing: centroid within this of the region's plane", positive(1.0));
    v.param("label_prior_region_min_area_m2", label_prior_region_min_area_m2, "m^2", "regions smaller than this decide nothing", non_negative(1e6));
    v.param("label_prior_region_min_share", label_prior_region_min_share, "", "a region's class holds at least this share of its labelled area", {0.0, 1.0});
    v.param("label_prior_segments", label_prior_segments, "",
            "mesh labels: a smooth segment's majority class labels its unlabelled vertices where it fits their surface");
    v.param("label_prior_segment_k", label_prior_segment_k, "",
            "smooth segments: Felzenszwalb-Huttenlocher K on the normal difference 1 - cos (larger: larger segments)", {1e-5, 1.0});
    v.param("label_prior_segment_min_labelled", label_prior_segment_min_labelled, "",
            "a smooth segment decides only when at least this share of its area is labelled", {0.0, 1.0});
    v.param("label_prior_likely", label_prior_likely, "",
            "mesh labels: a vertex still unlabelled after the regions and the evidence refit takes the class its fused "
            "evidence makes most probable, weighted by the map's class frequencies, among those its surface and its "
            "smooth segment allow (no frames' lead; tsdf/label_priors.hpp)");
    v.param("label_prior_likely_probability", label_prior_likely_probability, "",
            "label_prior_likely: the class's share of the weighted probability of the allowed classes (0: the most probable)",
            {0.0, 1.0});
    v.param("label_prior_other", label_prior_other, "",
            "mesh labels: a vertex whose wall/floor/ceiling label its surface rules out, and that no fitting class "
            "claims, is `other` (an object the network does not name, in front of the structure)");
    v.param("label_prior_fringes", label_prior_fringes, "",
            "mesh labels (last): an unlabelled vertex within label_prior_fringe_m along the mesh of labelled vertices of "
            "its smooth segment takes the class most of their area shows among those its surface fits, ring by ring");
    v.param("label_prior_fringe_m", label_prior_fringe_m, "m",
            "label_prior_fringes: how far along the mesh from the labelled surface a class reaches", non_negative(1.0));
    v.param("drop_distance", drop_distance, "m", "free blocks farther than this from the camera (0 = never)", non_negative(1e6));
  }
  void validate() const {
    check_param_ranges(*this, "tsdf");
    require_param(epsilon_voxels >= 0 && epsilon_voxels < truncation_voxels, "tsdf.epsilon_voxels",
                  "must be in [0, truncation_voxels)");
    require_param(max_depth > min_depth, "tsdf.max_depth", "must be > min_depth");
    require_param(weight_max > weight_unit, "tsdf.weight_max", "must be > weight_unit");
  }
};

}  // namespace semap
