#pragma once
#include "semap/core/params.hpp"

namespace semap {

/// Parameters of tracking (METHODS.md A1-A4). Every tunable of src/tracking lives here.
struct TrackingConfig {
  // --- A1 depth repair (joint median filter) ---
  bool depth_repair = true;            ///< fill invalid depth pixels (valid ones never change)
  int depth_repair_radius = 2;         ///< window radius r, pixels
  double depth_repair_gray_threshold = 12.0;  ///< t_gray, grey levels (0..255)
  int depth_repair_min_support = 3;    ///< fewer same-grey valid neighbours -> pixel stays invalid

  // --- depth range used by tracking ---
  double min_depth = 0.2;              ///< metres
  double max_depth = 4.5;              ///< metres

  // --- A2 features + voting RANSAC ---
  int orb_features = 700;              ///< ORB keypoints per frame
  int orb_levels = 4;                  ///< ORB scale pyramid levels
  double orb_scale_factor = 1.2;       ///< ORB pyramid scale step
  int orb_fast_threshold = 15;         ///< FAST corner threshold, grey levels
  double match_ratio = 0.8;            ///< Lowe ratio test (best / second best Hamming distance)
  int match_max_hamming = 64;          ///< matches with a larger Hamming distance are dropped, bits
  int ransac_iterations = 200;         ///< 3-point samples per RANSAC
  double ransac_inlier_distance = 0.04;  ///< vote threshold on 3D point distance, metres
  int ransac_min_inliers = 15;         ///< fewer inliers -> feature estimate not trusted
  int seed = 1;                        ///< RANSAC / ferns random seed (deterministic)

  // --- A2 point-to-plane ICP (projective association, coarse to fine) ---
  int icp_levels = 3;                  ///< pyramid levels (level 0 = full resolution)
  int icp_iterations_fine = 4;         ///< Gauss-Newton iterations at level 0
  int icp_iterations_mid = 6;          ///< at level 1
  int icp_iterations_coarse = 10;      ///< at levels >= 2
  int icp_stride = 4;                  ///< pixel step over the source image at level 0 (halved per level)
  int icp_min_stride = 2;              ///< the halved step never goes below this at levels >= 1 (2: a quarter of the coarsest level's pixels, same ATE, METHODS.md A2)
  double icp_max_distance = 0.10;      ///< correspondence distance gate at level 0, metres (x2 per level up)
  double icp_max_normal_angle_deg = 35.0;  ///< normal compatibility gate, degrees
  double icp_huber_delta = 0.01;       ///< Huber threshold of the point-to-plane residual, metres
  double icp_convergence_update = 5e-4;  ///< stop level 0 when |update| falls below (rad, m); the Huber/association noise floor is 3-7e-4, 1e-5 only ran iterations to the cap (same ATE; 1e-3 loses 0.5 cm on fr1_rpy)
  double icp_convergence_level_scale = 2.0;  ///< level l stops below icp_convergence_update * scale^l (coarse pixels resolve less)
  double icp_converged_update = 2e-3;  ///< last update above this = ICP not converged (tracking loss), (rad, m)
  double icp_photometric_weight = 0.3;  ///< weight of the intensity residual against the point-to-plane one, m^2 (0 = geometry only): (sigma_geo / sigma_I)^2 with sigma_geo ~ 1 cm, sigma_I ~ 5 grey levels
  double icp_photometric_huber = 0.1;   ///< Huber threshold of the intensity residual (intensity 0..1)
  double icp_photometric_max_depth_difference = 0.05;  ///< occlusion test of the photometric term, metres
  bool icp_photometric_bias = false;    ///< estimate a brightness offset between frame and keyframe (auto exposure)

  // --- tracking loss (A2) ---
  double loss_max_icp_rmse = 0.03;     ///< ICP residual RMSE above this = lost, metres
  double loss_min_overlap = 0.20;      ///< fewer than this fraction of source points matched = lost
  double loss_max_translation_jump = 0.30;  ///< jump from the motion prior above this = lost, metres
  double loss_max_rotation_jump_deg = 30.0; ///< jump from the motion prior above this = lost, degrees
  int relocalisation_candidates = 3;   ///< keyframes (by fern similarity) tried when lost

  // --- keyframes ---
  double keyframe_translation = 0.12;  ///< motion from the reference keyframe that makes a new one, metres
  double keyframe_rotation_deg = 12.0; ///< same for rotation, degrees
  double keyframe_min_overlap = 0.5;  ///< ICP overlap below this makes a new keyframe (fraction)
  bool keyframe_reuse = true;          ///< track against an older keyframe near the current pose instead of making a new one
  double keyframe_reuse_max_score = 0.8;  ///< max (dt/keyframe_translation + drot/keyframe_rotation) for reuse

  // --- A3 random ferns ---
  int fern_count = 500;                ///< m ferns
  int fern_tests = 4;                  ///< n binary tests per fern
  int fern_width = 80;                 ///< downsampled encoding width, pixels
  int fern_height = 60;                ///< downsampled encoding height, pixels
  double fern_new_keyframe_similarity = 0.0;  ///< max similarity below this -> new keyframe (fraction of ferns)
  double loop_min_similarity = 0.45;   ///< loop candidate needs at least this similarity (fraction); revisits of real Kinect views score 0.45-0.55 (exposure, viewpoint), geometric verification rejects false candidates
  int loop_min_keyframe_gap = 8;       ///< candidates must be this many keyframes older
  int loop_candidates = 3;             ///< best candidates verified geometrically per keyframe
  double loop_max_icp_rmse = 0.02;     ///< geometric verification: ICP RMSE limit, metres
  double loop_min_overlap = 0.35;      ///< geometric verification: ICP overlap limit (fraction)
  double loop_max_pose_disagreement = 0.5;  ///< reject a loop whose correction exceeds this, metres

  // --- A4 pose graph ---
  bool pose_graph = true;              ///< optimise keyframe poses (odometry + loop edges)
  int pose_graph_iterations = 50;      ///< Ceres iterations per optimisation
  double pose_graph_loop_huber = 1.0;  ///< robust loss scale on loop edges (whitened units)
  double information_effective_points = 300.0;  ///< ICP matches are correlated: Hessian rescaled to this many independent points
  double information_min_sigma = 0.003;  ///< floor on the registration noise used for edge information, metres
  bool background_loop_closure = true; ///< loop detection + optimisation on a worker thread (false = deterministic)
  bool parallel = false;               ///< row-parallel loops (cv::parallel_for_) inside tracking; off: serial, less CPU per frame when the pipeline shares the cores (OpenCV's own calls are unaffected)

  void visit(ParamVisitor& v) {
    v.param("depth_repair", depth_repair, "", "fill invalid depth with the joint median filter (A1)");
    v.param("depth_repair_radius", depth_repair_radius, "px", "joint median window radius r (A1)");
    v.param("depth_repair_gray_threshold", depth_repair_gray_threshold, "grey levels", "t_gray: neighbours whose grey differs more are ignored (A1)");
    v.param("depth_repair_min_support", depth_repair_min_support, "px", "minimum same-grey valid neighbours to fill a pixel");
    v.param("min_depth", min_depth, "m", "nearer depth is ignored by tracking");
    v.param("max_depth", max_depth, "m", "farther depth is ignored by tracking");
    v.param("orb_features", orb_features, "", "ORB keypoints per frame (A2)");
    v.param("orb_levels", orb_levels, "", "ORB pyramid levels");
    v.param("orb_scale_factor", orb_scale_factor, "", "ORB pyramid scale step");
    v.param("orb_fast_threshold", orb_fast_threshold, "grey levels", "FAST corner threshold");
    v.param("match_ratio", match_ratio, "", "ratio test on Hamming distances (best/second)");
    v.param("match_max_hamming", match_max_hamming, "bits", "matches farther than this are dropped");
    v.param("ransac_iterations", ransac_iterations, "", "voting RANSAC samples (A2)");
    v.param("ransac_inlier_distance", ransac_inlier_distance, "m", "3D distance under which a match votes");
    v.param("ransac_min_inliers", ransac_min_inliers, "", "fewer inliers: use the motion prior instead");
    v.param("seed", seed, "", "random seed for RANSAC and ferns");
    v.param("icp_levels", icp_levels, "", "ICP pyramid levels (coarse to fine)");
    v.param("icp_iterations_fine", icp_iterations_fine, "", "ICP iterations at full resolution");
    v.param("icp_iterations_mid", icp_iterations_mid, "", "ICP iterations at half resolution");
    v.param("icp_iterations_coarse", icp_iterations_coarse, "", "ICP iterations at coarser levels");
    v.param("icp_stride", icp_stride, "px", "source pixel step at full resolution");
    v.param("icp_min_stride", icp_min_stride, "px", "smallest source pixel step at the coarser levels");
    v.param("icp_max_distance", icp_max_distance, "m", "correspondence gate at full resolution (doubles per level)");
    v.param("icp_max_normal_angle_deg", icp_max_normal_angle_deg, "deg", "normal compatibility gate");
    v.param("icp_huber_delta", icp_huber_delta, "m", "Huber threshold on point-to-plane residuals");
    v.param("icp_convergence_update", icp_convergence_update, "rad|m", "update norm that ends a level");
    v.param("icp_convergence_level_scale", icp_convergence_level_scale, "", "stop threshold factor per pyramid level up");
    v.param("icp_converged_update", icp_converged_update, "rad|m", "final update above this = ICP not converged");
    v.param("icp_photometric_weight", icp_photometric_weight, "m^2", "joint ICP: weight of intensity residuals vs point-to-plane residuals (0 = off)");
    v.param("icp_photometric_huber", icp_photometric_huber, "", "Huber threshold of intensity residuals (0..1)");
    v.param("icp_photometric_max_depth_difference", icp_photometric_max_depth_difference, "m", "photometric residuals need the target depth this close");
    v.param("icp_photometric_bias", icp_photometric_bias, "", "estimate a brightness offset (auto exposure) in the photometric term");
    v.param("loss_max_icp_rmse", loss_max_icp_rmse, "m", "ICP RMSE above this means tracking is lost");
    v.param("loss_min_overlap", loss_min_overlap, "", "matched fraction below this means lost");
    v.param("loss_max_translation_jump", loss_max_translation_jump, "m", "implausible jump from the motion prior");
    v.param("loss_max_rotation_jump_deg", loss_max_rotation_jump_deg, "deg", "implausible rotation jump");
    v.param("relocalisation_candidates", relocalisation_candidates, "", "keyframes tried when relocalising");
    v.param("keyframe_translation", keyframe_translation, "m", "translation that makes a new keyframe");
    v.param("keyframe_rotation_deg", keyframe_rotation_deg, "deg", "rotation that makes a new keyframe");
    v.param("keyframe_min_overlap", keyframe_min_overlap, "", "ICP overlap below this makes a new keyframe");
    v.param("keyframe_reuse", keyframe_reuse, "", "re-use an older keyframe near the current pose");
    v.param("keyframe_reuse_max_score", keyframe_reuse_max_score, "", "pose-distance score limit for re-use");
    v.param("fern_count", fern_count, "", "m random ferns (A3)");
    v.param("fern_tests", fern_tests, "", "n binary tests per fern (code has 2^n values)");
    v.param("fern_width", fern_width, "px", "encoding image width");
    v.param("fern_height", fern_height, "px", "encoding image height");
    v.param("fern_new_keyframe_similarity", fern_new_keyframe_similarity, "", "dissimilar frames become keyframes");
    v.param("loop_min_similarity", loop_min_similarity, "", "fern similarity of a loop candidate");
    v.param("loop_min_keyframe_gap", loop_min_keyframe_gap, "keyframes", "loop candidates are at least this old");
    v.param("loop_candidates", loop_candidates, "", "candidates verified per keyframe");
    v.param("loop_max_icp_rmse", loop_max_icp_rmse, "m", "loop verification ICP RMSE limit");
    v.param("loop_min_overlap", loop_min_overlap, "", "loop verification overlap limit");
    v.param("loop_max_pose_disagreement", loop_max_pose_disagreement, "m", "largest accepted loop correction");
    v.param("pose_graph", pose_graph, "", "optimise keyframe poses with Ceres (A4)");
    v.param("pose_graph_iterations", pose_graph_iterations, "", "Ceres iterations per optimisation");
    v.param("pose_graph_loop_huber", pose_graph_loop_huber, "", "Huber scale on loop edges (whitened)");
    v.param("information_effective_points", information_effective_points, "", "independent points assumed for edge information");
    v.param("information_min_sigma", information_min_sigma, "m", "noise floor for edge information");
    v.param("background_loop_closure", background_loop_closure, "", "loop closure on a worker thread (false = deterministic)");
    v.param("parallel", parallel, "", "row-parallel loops inside tracking (false = serial, less CPU per frame)");
  }
  void validate() const {
    require_param(depth_repair_radius >= 1 && depth_repair_radius <= 15, "tracking.depth_repair_radius", "must be in [1, 15]");
    require_param(depth_repair_gray_threshold >= 0, "tracking.depth_repair_gray_threshold", "must be >= 0");
    require_param(depth_repair_min_support >= 1, "tracking.depth_repair_min_support", "must be >= 1");
    require_param(min_depth >= 0 && max_depth > min_depth, "tracking.max_depth", "need 0 <= min_depth < max_depth");
    require_param(orb_features >= 10, "tracking.orb_features", "must be >= 10");
    require_param(orb_levels >= 1 && orb_levels <= 12, "tracking.orb_levels", "must be in [1, 12]");
    require_param(orb_scale_factor > 1.0, "tracking.orb_scale_factor", "must be > 1");
    require_param(match_ratio > 0 && match_ratio <= 1, "tracking.match_ratio", "must be in (0, 1]");
    require_param(ransac_iterations >= 1, "tracking.ransac_iterations", "must be >= 1");
    require_param(ransac_inlier_distance > 0, "tracking.ransac_inlier_distance", "must be > 0");
    require_param(ransac_min_inliers >= 3, "tracking.ransac_min_inliers", "must be >= 3");
    require_param(icp_levels >= 1 && icp_levels <= 5, "tracking.icp_levels", "must be in [1, 5]");
    require_param(icp_iterations_fine >= 0 && icp_iterations_mid >= 0 && icp_iterations_coarse >= 0,
                  "tracking.icp_iterations_fine", "iterations must be >= 0");
    require_param(icp_stride >= 1 && icp_stride <= 8, "tracking.icp_stride", "must be in [1, 8]");
    require_param(icp_min_stride >= 1 && icp_min_stride <= 8, "tracking.icp_min_stride", "must be in [1, 8]");
    require_param(icp_max_distance > 0, "tracking.icp_max_distance", "must be > 0");
    require_param(icp_max_normal_angle_deg > 0 && icp_max_normal_angle_deg <= 90, "tracking.icp_max_normal_angle_deg", "must be in (0, 90]");
    require_param(icp_convergence_level_scale >= 1, "tracking.icp_convergence_level_scale", "must be >= 1");
    require_param(icp_huber_delta > 0, "tracking.icp_huber_delta", "must be > 0");
    require_param(icp_photometric_weight >= 0, "tracking.icp_photometric_weight", "must be >= 0");
    require_param(icp_photometric_huber > 0, "tracking.icp_photometric_huber", "must be > 0");
    require_param(icp_photometric_max_depth_difference > 0, "tracking.icp_photometric_max_depth_difference", "must be > 0");
    require_param(loss_max_icp_rmse > 0, "tracking.loss_max_icp_rmse", "must be > 0");
    require_param(loss_min_overlap >= 0 && loss_min_overlap < 1, "tracking.loss_min_overlap", "must be in [0, 1)");
    require_param(keyframe_translation > 0 && keyframe_rotation_deg > 0, "tracking.keyframe_translation", "keyframe thresholds must be > 0");
    require_param(fern_count >= 1 && fern_count <= 10000, "tracking.fern_count", "must be in [1, 10000]");
    require_param(fern_tests >= 1 && fern_tests <= 12, "tracking.fern_tests", "must be in [1, 12]");
    require_param(fern_width >= 8 && fern_height >= 8, "tracking.fern_width", "encoding must be at least 8x8");
    require_param(loop_min_keyframe_gap >= 1, "tracking.loop_min_keyframe_gap", "must be >= 1");
    require_param(pose_graph_iterations >= 1, "tracking.pose_graph_iterations", "must be >= 1");
    require_param(information_effective_points > 0, "tracking.information_effective_points", "must be > 0");
    require_param(information_min_sigma > 0, "tracking.information_min_sigma", "must be > 0");
  }
};

}  // namespace semap
