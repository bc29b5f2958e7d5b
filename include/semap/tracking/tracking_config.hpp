#pragma once
#include <algorithm>
#include <cstdint>

#include "semap/core/depth_noise_model.hpp"
#include "semap/core/params.hpp"

namespace semap {

/// Point-to-plane ICP with projective association, coarse to fine (METHODS.md A2 step 4):
/// the section `tracking.icp`. registration.hpp's icp_point_to_plane() takes it as it is.
struct IcpParams {
  int levels = 3;                  ///< pyramid levels (level 0 = full resolution)
  int iterations_fine = 4;         ///< Gauss-Newton iterations at level 0
  int iterations_mid = 6;          ///< at level 1
  int iterations_coarse = 10;      ///< at levels >= 2
  int stride = 4;                  ///< source pixel step at level 0, halved per level up
  int min_stride = 2;              ///< the halved step never goes below this at levels >= 1 (2: a quarter of the coarsest level's pixels, same ATE)
  double max_distance = 0.10;      ///< correspondence gate at level 0, metres (x2 per level up)
  double max_normal_angle_deg = 35.0;  ///< normal compatibility gate, degrees
  double huber_delta = 0.01;       ///< Huber threshold of the point-to-plane residual, metres
  double convergence_update = 5e-4;  ///< stop level 0 when |update| falls below (rad, m); the Huber/association noise floor is 3-7e-4 (1e-3 loses 0.5 cm on fr1_rpy)
  double convergence_level_scale = 2.0;  ///< level l stops below convergence_update * scale^l (coarse pixels resolve less)
  double converged_update = 2e-3;  ///< last update above this = ICP not converged (tracking loss), (rad, m)
  /// Photometric term (joint geometric + photometric ICP as in ElasticFusion / Open3D's hybrid
  /// odometry): weight of the squared intensity residual relative to the squared point-to-plane
  /// residual in metres, (sigma_geo / sigma_I)^2 with sigma_geo ~ 1 cm, sigma_I ~ 5 grey levels.
  /// 0 = geometry only.
  double photometric_weight = 0.3;
  double photometric_huber = 0.1;  ///< Huber threshold of the intensity residual (intensity 0..1)
  double photometric_max_depth_difference = 0.05;  ///< occlusion test of the photometric term, metres
  bool photometric_bias = false;   ///< estimate a brightness offset between frame and keyframe (auto exposure)

  /// Gauss-Newton iterations at pyramid level l.
  int iterations_at(int l) const { return l == 0 ? iterations_fine : l == 1 ? iterations_mid : iterations_coarse; }

  void visit(ParamVisitor& v) {
    v.param("levels", levels, "", "ICP pyramid levels (coarse to fine)", {1, 5});
    v.param("iterations_fine", iterations_fine, "", "ICP iterations at full resolution", {0, 100});
    v.param("iterations_mid", iterations_mid, "", "ICP iterations at half resolution", {0, 100});
    v.param("iterations_coarse", iterations_coarse, "", "ICP iterations at coarser levels", {0, 100});
    v.param("stride", stride, "px", "source pixel step at full resolution", {1, 8});
    v.param("min_stride", min_stride, "px", "smallest source pixel step at the coarser levels", {1, 8});
    v.param("max_distance", max_distance, "m", "correspondence gate at full resolution (doubles per level)", positive(2.0));
    v.param("max_normal_angle_deg", max_normal_angle_deg, "deg", "normal compatibility gate", {0.0, 90.0, true});
    v.param("huber_delta", huber_delta, "m", "Huber threshold on point-to-plane residuals", positive(1.0));
    v.param("convergence_update", convergence_update, "rad|m", "update norm that ends a level", positive(1.0));
    v.param("convergence_level_scale", convergence_level_scale, "", "stop threshold factor per pyramid level up", {1.0, 10.0});
    v.param("converged_update", converged_update, "rad|m", "final update above this = ICP not converged", positive(1.0));
    v.param("photometric_weight", photometric_weight, "m^2", "joint ICP: weight of intensity residuals vs point-to-plane residuals (0 = off)", non_negative(100.0));
    v.param("photometric_huber", photometric_huber, "", "Huber threshold of intensity residuals (0..1)", positive(1.0));
    v.param("photometric_max_depth_difference", photometric_max_depth_difference, "m", "photometric residuals need the target depth this close", positive(1.0));
    v.param("photometric_bias", photometric_bias, "", "estimate a brightness offset (auto exposure) in the photometric term");
  }
};

/// Joint median filter depth repair (METHODS.md A1): the keys `tracking.depth_repair*`.
/// One default set (issue 42): radius 2 and min_support 3, the values `semap run` has used
/// (the Mapper and the tracker repair with the tracking config); the filter's own former
/// defaults (3, 1) were used by no caller.
struct DepthRepairParams {
  int radius = 2;                ///< window radius r, pixels
  double gray_threshold = 12.0;  ///< t_gray, grey levels (0..255)
  int min_support = 3;           ///< fewer same-grey valid neighbours -> pixel stays invalid
  bool enabled = true;           ///< fill invalid depth pixels (valid ones never change)

  /// Flat keys under `tracking` (user-facing, and stored in saved maps' configs).
  void visit(ParamVisitor& v) {
    v.param("depth_repair", enabled, "", "fill invalid depth with the joint median filter (A1)");
    v.param("depth_repair_radius", radius, "px", "joint median window radius r (A1)", {1, 15});
    v.param("depth_repair_gray_threshold", gray_threshold, "grey levels", "t_gray: neighbours whose grey differs more are ignored (A1)", non_negative(255.0));
    v.param("depth_repair_min_support", min_support, "px", "minimum same-grey valid neighbours to fill a pixel", {1, 961});
  }
};

/// Voting RANSAC over 3D-3D feature matches (METHODS.md A2 step 3) and how far its estimate is
/// trusted: the keys `tracking.ransac_*`. registration.hpp's ransac_rigid() reads iterations,
/// inlier_distance, min_inliers and seed.
struct RansacParams {
  int iterations = 200;            ///< 3-point samples per RANSAC
  double inlier_distance = 0.04;   ///< vote threshold on 3D point distance, metres
  int min_inliers = 15;            ///< fewer inliers -> feature estimate not used
  /// A feature estimate this well supported is trusted even where it disagrees with the
  /// constant-velocity prior (wide baselines, sudden motion, issue 16): inlier count ...
  int trusted_inliers = 40;
  double trusted_ratio = 0.3;      ///< ... and inliers / matches
  double icp_agreement = 0.05;     ///< ICP refined within this of the RANSAC estimate (metres; radians / 0.5 m lever) to keep its support
  int wide_iterations = 1000;      ///< RANSAC samples of the wide-baseline attempt (only when the prior failed)
  /// Random seed of one RANSAC run: not a key, the tracker derives it from tracking.seed and
  /// the frame / keyframe (deterministic).
  uint32_t seed = 1;

  void visit(ParamVisitor& v) {
    v.param("ransac_iterations", iterations, "", "voting RANSAC samples (A2)", {1, 1000000});
    v.param("ransac_inlier_distance", inlier_distance, "m", "3D distance under which a match votes", positive(1.0));
    v.param("ransac_min_inliers", min_inliers, "", "fewer inliers: the feature estimate is not used", {3, 100000});
    v.param("ransac_trusted_inliers", trusted_inliers, "", "this many inliers (and the ratio) make the feature estimate trusted against the motion prior", {3, 100000});
    v.param("ransac_trusted_ratio", trusted_ratio, "", "inliers / matches a trusted feature estimate needs", fraction());
    v.param("ransac_icp_agreement", icp_agreement, "m", "ICP must stay this close to the RANSAC estimate to keep its support (rotation: rad x 0.5 m)", positive(1.0));
    v.param("wide_ransac_iterations", wide_iterations, "", "RANSAC samples when the motion prior failed", {1, 1000000});
  }
};

/// Verification of a registration before it is trusted (issue 42, METHODS.md A2 "tracking
/// loss"): the section `tracking.verify`. Bounds derive from the depth sensor's noise model
/// (Kinect v1 axial noise, Nguyen et al. 2012: sigma(z) = base + quadratic * (z - 0.4 m)^2)
/// or are scale-free ratios; none is fitted to a sequence. registration_check.hpp applies them.
struct VerificationParams {
  bool enabled = true;                 ///< off: registrations are judged as before issue 42
  /// Dense depth residual: the frame's depth warped into the reference with the candidate pose.
  DepthNoiseModel depth_noise;         ///< the sensor's sigma(z)
  double residual_sigmas = 3.0;        ///< a warped point agrees within this many sigma(z) ...
  double residual_pose_tolerance_m = 0.01;  ///< ... plus this (the pose's own error, depth edges), metres
  int residual_level = 2;              ///< pyramid level the dense residual is computed at (2 = quarter resolution)
  /// Agreeing share of the warped points the reference saw (agreeing + in its free space) below
  /// which the pose is wrong: a point the reference saw through cannot be there. Right poses on
  /// the shared sequences measure >= 0.7 (depth edges, noise), a pose 30 cm off along the view < 0.1.
  double min_consistent_fraction = 0.6;
  /// Agreeing share of all warped points the reference saw (points hidden behind its surface
  /// included) below which the pose explains too little: a pose pushed 30 cm away hides almost
  /// all (< 0.1); right poses on the shared sequences measure >= 0.35 (occlusions, edges).
  double min_agreeing_share = 0.2;
  /// Inlier spread: ORB inliers on a grid x grid partition of the image must occupy this many
  /// cells for the feature estimate to be trusted (matches on one patch pin down little).
  int spread_grid = 4;
  int spread_min_cells = 3;
  /// Second hypothesis: a distinct RANSAC model (fewer than half of its votes from the best's
  /// inliers: other matches explain the frame) with at least this share of the best's votes =
  /// ambiguous (repetitive structure matched to the wrong copy).
  double ambiguity_vote_ratio = 0.8;
  /// Conditioning: smallest eigenvalue of the point-to-plane information of the frame's
  /// coarsest pyramid level per point, rotation scaled by the scene's lever (scale-free; 1/3
  /// for three orthogonal planes, ~0 for one plane; Kinect-noise normals of one wall 2 m away
  /// give ~0.0045, a room ~0.03, the shared sequences' views >= 0.0099). Below it a pose
  /// without trusted features is under-constrained.
  double min_information_eigenvalue = 0.007;

  void visit(ParamVisitor& v) {
    v.param("enabled", enabled, "", "verify each registration before trusting it (issue 42)");
    depth_noise.visit(v);
    v.param("residual_sigmas", residual_sigmas, "", "dense residual bound in depth-noise sigmas", positive(100.0));
    v.param("residual_pose_tolerance_m", residual_pose_tolerance_m, "m", "dense residual bound added for the pose's own error", non_negative(1.0));
    v.param("residual_level", residual_level, "", "pyramid level of the dense residual (0 = full resolution)", {0, 4});
    v.param("min_consistent_fraction", min_consistent_fraction, "", "share of warped points that must agree with the reference depth (the rest lie in its free space)", fraction());
    v.param("min_agreeing_share", min_agreeing_share, "", "share of warped points the reference saw that must agree with its depth (hidden ones included)", fraction());
    v.param("spread_grid", spread_grid, "cells", "grid side for the inlier spread", {1, 64});
    v.param("spread_min_cells", spread_min_cells, "cells", "grid cells the ORB inliers must occupy for trusted features", {0, 4096});
    v.param("ambiguity_vote_ratio", ambiguity_vote_ratio, "", "a distinct RANSAC model with this share of the best's votes makes the match ambiguous", {0.0, 1.0, true});
    v.param("min_information_eigenvalue", min_information_eigenvalue, "", "smallest scaled point-to-plane information eigenvalue per point (coarsest level) a pose without trusted features needs", {0.0, 1.0});
  }
};

/// Random ferns encoding of keyframes (METHODS.md A3): the keys `tracking.fern_*`. A saved
/// map's keyframes are only recognised with the same values (map_archive checks them).
struct FernParams {
  int fern_count = 500;  ///< m ferns
  int fern_tests = 4;    ///< n binary tests per fern
  int width = 80;        ///< downsampled encoding width, pixels
  int height = 60;       ///< downsampled encoding height, pixels
  /// Range of the random depth thresholds (metres) and the test seed: not keys, the tracker
  /// sets them from tracking.min_depth / max_depth / seed.
  double min_depth = 0.2, max_depth = 4.5;
  uint32_t seed = 1;

  void visit(ParamVisitor& v) {
    v.param("fern_count", fern_count, "", "m random ferns (A3)", {1, 10000});
    v.param("fern_tests", fern_tests, "", "n binary tests per fern (code has 2^n values)", {1, 12});
    v.param("fern_width", width, "px", "encoding image width", {8, 4096});
    v.param("fern_height", height, "px", "encoding image height", {8, 4096});
  }
};

/// Parameters of tracking (METHODS.md A1-A4). Every tunable of src/tracking lives here, in
/// sections (depth repair, RANSAC, ICP, ferns); ranges are declared once in visit(),
/// validate() derives from them. The YAML keys of depth_repair, ransac and ferns stay flat
/// under `tracking` (saved maps store their config); the ICP has its own section `icp`.
struct TrackingConfig {
  // --- A1 depth repair (joint median filter) ---
  DepthRepairParams depth_repair;

  // --- depth range used by tracking ---
  double min_depth = 0.2;              ///< metres
  double max_depth = 4.5;              ///< metres

  // --- A2 features + voting RANSAC ---
  int orb_features = 700;              ///< ORB keypoints per frame
  /// ORB keypoints of the wide-baseline attempt (issue 42): a denser set of the frame and of its
  /// reference keyframe, extracted only when the per-frame registration failed (a wide
  /// baseline leaves too few of orb_features in common; 0: no such attempt).
  int orb_wide_features = 2000;
  int orb_levels = 4;                  ///< ORB scale pyramid levels
  double orb_scale_factor = 1.2;       ///< ORB pyramid scale step
  int orb_fast_threshold = 15;         ///< FAST corner threshold, grey levels
  double match_ratio = 0.8;            ///< Lowe ratio test (best / second best Hamming distance)
  int match_max_hamming = 64;          ///< matches with a larger Hamming distance are dropped, bits
  RansacParams ransac;
  int seed = 1;                        ///< RANSAC / ferns random seed (deterministic)

  // --- A2 ICP ---
  IcpParams icp;
  /// Wide-baseline attempt: the correspondence gate grows with the motion the start pose may
  /// be off by (RANSAC inlier spread, or the prior's step), gate = max(icp.max_distance,
  /// this * expected error).
  double wide_icp_gate_factor = 2.0;
  double wide_icp_max_distance = 0.3;  ///< upper bound of that level-0 gate, metres

  // --- tracking loss (A2) ---
  double loss_max_icp_rmse = 0.03;     ///< ICP residual RMSE above this = lost, metres
  double loss_min_overlap = 0.20;      ///< fewer than this fraction of source points matched = lost
  double loss_max_translation_jump = 0.30;  ///< without trusted feature support: a jump from the motion prior above this = lost, metres
  double loss_max_rotation_jump_deg = 30.0; ///< same for rotation, degrees
  /// The trajectory's pose of a lost frame (issue 42): interpolated between the verified frames
  /// before and after it when they are at most this far apart in time; else (and at 0) the last
  /// verified pose, as track() reports it. Seconds.
  double lost_pose_max_gap_s = 5.0;
  VerificationParams verify;          ///< checks a registration must pass (issue 42)
  int relocalisation_candidates = 3;   ///< keyframes (by fern similarity) tried when lost
  int relocalisation_recent = 2;       ///< plus this many most recent keyframes
  double relocalisation_min_overlap = 0.4;  ///< ICP overlap a relocalisation needs (no prior to check it against)
  // Map merging (issue 19): the other map's keyframes are relocalised into this one; the
  // alignments they imply must agree (two maps' drift differs, so not exactly).
  double merge_agreement_m = 0.10;    ///< alignments within this translation support each other, metres
  double merge_agreement_deg = 5.0;   ///< ... and within this rotation, degrees
  int merge_min_agreeing = 2;         ///< relocalised keyframes that must agree (1 when the other map has one)

  // --- keyframes ---
  double keyframe_translation = 0.12;  ///< motion from the reference keyframe that makes a new one, metres
  double keyframe_rotation_deg = 12.0; ///< same for rotation, degrees
  double keyframe_min_overlap = 0.5;  ///< ICP overlap below this makes a new keyframe (fraction)
  double keyframe_max_icp_rmse = 0.02;   ///< ICP RMSE above this makes a new keyframe (before it reaches the loss limit), metres
  int keyframe_min_inliers = 30;       ///< fewer RANSAC inliers make a new keyframe (features thinning out)
  bool keyframe_reuse = true;          ///< track against an older keyframe near the current pose instead of making a new one
  double keyframe_reuse_max_score = 0.8;  ///< max (dt/keyframe_translation + drot/keyframe_rotation) for reuse
  /// Frame-to-model (METHODS.md A2, issue 42): a new keyframe's ICP target is the fused model's
  /// surface along its pixel rays (its own depth where the model has none yet), when the
  /// pipeline hands the tracker a model view (Tracker::set_model_view); the frames tracked
  /// against it register to the model's projected point cloud instead of one depth image.
  /// Off by default: `semap run --segmenter none` (2026-12-08, 2 threads) measured redkitchen
  /// better with it (ATE 3.17 -> 2.83 cm, RPE 1.84 -> 1.83 deg/s) but fr1_rpy worse (1.46 -> 1.84
  /// cm, 2.03 -> 2.15 deg/s: during fast rotation the fused surface is smeared), at 46 instead of
  /// 67 fps (the ray casts). The keyframe's ICP residual against the model does not tell the two
  /// apart (median 1.5 cm on both), so there is no per-keyframe choice yet.
  bool model_keyframes = false;

  // --- A3 random ferns ---
  FernParams ferns;
  double fern_new_keyframe_similarity = 0.0;  ///< max similarity below this -> new keyframe (fraction of ferns)
  double loop_min_similarity = 0.45;   ///< loop candidate needs at least this similarity (fraction); revisits of real Kinect views score 0.45-0.55 (exposure, viewpoint), geometric verification rejects false candidates
  int loop_min_keyframe_gap = 8;       ///< candidates must be this many keyframes older
  int loop_candidates = 3;             ///< best candidates verified geometrically per keyframe
  double loop_max_icp_rmse = 0.02;     ///< geometric verification: ICP RMSE limit, metres
  double loop_min_overlap = 0.35;      ///< geometric verification: ICP overlap limit (fraction)
  double loop_max_pose_disagreement = 0.5;  ///< reject a loop whose correction exceeds this, metres
  int local_edge_keyframes = 0;        ///< recently referenced keyframes (nearest by pose, not the parent) each new keyframe is registered against (0 = parent chain only; 3 measured better on TUM fr1_rpy, worse on 7-Scenes: off by default)
  double local_edge_max_score = 3.0;   ///< ... within this pose distance in keyframe spacings (translation / keyframe_translation + rotation / keyframe_rotation_deg)

  // --- A4 pose graph ---
  bool pose_graph = true;              ///< optimise keyframe poses (odometry + loop edges)
  int pose_graph_iterations = 50;      ///< Ceres iterations per optimisation
  double pose_graph_loop_huber = 1.0;  ///< robust loss scale on loop edges (whitened units)
  double information_effective_points = 300.0;  ///< ICP matches are correlated: Hessian rescaled to this many independent points
  double information_min_sigma = 0.003;  ///< floor on the registration noise used for edge information, metres
  bool background_loop_closure = true; ///< loop detection + optimisation on a worker thread (false = deterministic)
  bool parallel = false;               ///< row-parallel loops (cv::parallel_for_) inside tracking; off: serial, less CPU per frame when the pipeline shares the cores (OpenCV's own calls are unaffected)

  void visit(ParamVisitor& v) {
    depth_repair.visit(v);
    v.param("min_depth", min_depth, "m", "nearer depth is ignored by tracking", non_negative(100.0));
    v.param("max_depth", max_depth, "m", "farther depth is ignored by tracking", positive(100.0));
    v.param("orb_features", orb_features, "", "ORB keypoints per frame (A2)", {10, 100000});
    v.param("orb_wide_features", orb_wide_features, "", "ORB keypoints of the wide-baseline attempt, extracted only when the per-frame registration failed (0: no such attempt)", {0, 100000});
    v.param("orb_levels", orb_levels, "", "ORB pyramid levels", {1, 12});
    v.param("orb_scale_factor", orb_scale_factor, "", "ORB pyramid scale step", {1.0, 4.0, true});
    v.param("orb_fast_threshold", orb_fast_threshold, "grey levels", "FAST corner threshold", {1, 255});
    v.param("match_ratio", match_ratio, "", "ratio test on Hamming distances (best/second)", {0.0, 1.0, true});
    v.param("match_max_hamming", match_max_hamming, "bits", "matches farther than this are dropped", {0, 256});
    ransac.visit(v);
    v.param("seed", seed, "", "random seed for RANSAC and ferns");
    v.section("icp", "point-to-plane + photometric ICP, coarse to fine (A2 step 4)", [&](ParamVisitor& s) { icp.visit(s); });
    v.param("wide_icp_gate_factor", wide_icp_gate_factor, "", "wide-baseline ICP gate = this x the start pose's expected error", positive(20.0));
    v.param("wide_icp_max_distance", wide_icp_max_distance, "m", "upper bound of the wide-baseline level-0 gate", positive(2.0));
    v.param("loss_max_icp_rmse", loss_max_icp_rmse, "m", "ICP RMSE above this means tracking is lost", positive(1.0));
    v.param("loss_min_overlap", loss_min_overlap, "", "matched fraction below this means lost", {0.0, 1.0});
    v.param("loss_max_translation_jump", loss_max_translation_jump, "m", "jump from the motion prior that an estimate without trusted features may not make", positive(100.0));
    v.param("loss_max_rotation_jump_deg", loss_max_rotation_jump_deg, "deg", "same for rotation", positive(180.0));
    v.param("lost_pose_max_gap_s", lost_pose_max_gap_s, "s", "a lost frame's trajectory pose is interpolated between the verified frames around it when they are at most this far apart in time (0: held at the last verified pose)", non_negative(3600.0));
    v.section("verify", "checks each registration must pass before it is trusted (issue 42)", [&](ParamVisitor& s) { verify.visit(s); });
    v.param("relocalisation_candidates", relocalisation_candidates, "", "keyframes (by fern similarity) tried when relocalising", {0, 1000});
    v.param("relocalisation_recent", relocalisation_recent, "", "most recent keyframes also tried when relocalising", {0, 1000});
    v.param("relocalisation_min_overlap", relocalisation_min_overlap, "", "ICP overlap a relocalisation needs", fraction());
    v.param("merge_agreement_m", merge_agreement_m, "m", "map merging: relocalised keyframes whose alignments of the two maps agree within this support each other", positive(10.0));
    v.param("merge_agreement_deg", merge_agreement_deg, "deg", "map merging: same for rotation", positive(180.0));
    v.param("merge_min_agreeing", merge_min_agreeing, "keyframes", "map merging: agreeing relocalised keyframes needed to merge (1 when the other map has one keyframe)", {1, 100000});
    v.param("keyframe_translation", keyframe_translation, "m", "translation that makes a new keyframe", positive(100.0));
    v.param("keyframe_rotation_deg", keyframe_rotation_deg, "deg", "rotation that makes a new keyframe", positive(180.0));
    v.param("keyframe_min_overlap", keyframe_min_overlap, "", "ICP overlap below this makes a new keyframe", fraction());
    v.param("keyframe_max_icp_rmse", keyframe_max_icp_rmse, "m", "ICP RMSE above this makes a new keyframe", positive(1.0));
    v.param("keyframe_min_inliers", keyframe_min_inliers, "", "fewer RANSAC inliers make a new keyframe", {0, 100000});
    v.param("keyframe_reuse", keyframe_reuse, "", "re-use an older keyframe near the current pose");
    v.param("keyframe_reuse_max_score", keyframe_reuse_max_score, "", "pose-distance score limit for re-use", non_negative(100.0));
    v.param("model_keyframes", model_keyframes, "", "keyframe ICP targets from the fused model's surface (frame-to-model, A2) when the pipeline provides it");
    ferns.visit(v);
    v.param("fern_new_keyframe_similarity", fern_new_keyframe_similarity, "", "dissimilar frames become keyframes", fraction());
    v.param("loop_min_similarity", loop_min_similarity, "", "fern similarity of a loop candidate", fraction());
    v.param("loop_min_keyframe_gap", loop_min_keyframe_gap, "keyframes", "loop candidates are at least this old", {1, 1000000});
    v.param("loop_candidates", loop_candidates, "", "candidates verified per keyframe", {0, 1000});
    v.param("loop_max_icp_rmse", loop_max_icp_rmse, "m", "loop verification ICP RMSE limit", positive(1.0));
    v.param("loop_min_overlap", loop_min_overlap, "", "loop verification overlap limit", fraction());
    v.param("loop_max_pose_disagreement", loop_max_pose_disagreement, "m", "largest accepted loop correction", positive(100.0));
    v.param("local_edge_keyframes", local_edge_keyframes, "keyframes", "earlier keyframes near by pose each new keyframe gets a graph edge to (0 = parent chain only)", {0, 100});
    v.param("local_edge_max_score", local_edge_max_score, "keyframe spacings", "how near: translation / keyframe_translation + rotation / keyframe_rotation_deg", non_negative(100.0));
    v.param("pose_graph", pose_graph, "", "optimise keyframe poses with Ceres (A4)");
    v.param("pose_graph_iterations", pose_graph_iterations, "", "Ceres iterations per optimisation", {1, 10000});
    v.param("pose_graph_loop_huber", pose_graph_loop_huber, "", "Huber scale on loop edges (whitened)", positive(1000.0));
    v.param("information_effective_points", information_effective_points, "", "independent points assumed for edge information", positive(1e9));
    v.param("information_min_sigma", information_min_sigma, "m", "noise floor for edge information", positive(1.0));
    v.param("background_loop_closure", background_loop_closure, "", "loop closure on a worker thread (false = deterministic)");
    v.param("parallel", parallel, "", "row-parallel loops inside tracking (false = serial, less CPU per frame)");
  }
  void validate() const {
    check_param_ranges(*this, "tracking");
    require_param(max_depth > min_depth, "tracking.max_depth", "need min_depth < max_depth");
    require_param(verify.spread_min_cells <= verify.spread_grid * verify.spread_grid, "tracking.verify.spread_min_cells",
                  "must be <= spread_grid^2");
    require_param(ransac.trusted_inliers >= ransac.min_inliers, "tracking.ransac_trusted_inliers", "must be >= ransac_min_inliers");
  }
};

}  // namespace semap
