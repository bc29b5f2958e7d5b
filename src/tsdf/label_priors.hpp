#pragma once
// Geometry-aware label decision (issue 38): the classes' physical places, applied to the mesh's
// vertex labels after the fused evidence is decided (VoxelLabelRule), so that a label that
// contradicts the surface it lands on loses to the evidence that fits. Up and the floor height
// come from core/gravity (the cameras' mean up refined by horizontal surfaces); the normal rule
// needs only up, so it works when no floor is visible; the height rules need the floor.
//
// Rules (each switched by its tsdf.label_prior_* parameter, all on by default):
//  - normals: floor must face up, ceiling down (within max_tilt_deg of the vertical axis, as
//    wound: semap's meshes face free space), wall must be vertical (normal within max_tilt_deg
//    of horizontal). A vertex whose smoothed normal contradicts its label is unlabelled.
//  - heights (floor found): floor lies within floor_band_m of the floor height, a ceiling at
//    least min_ceiling_height_m above it; others contradict.
//  - regions: the mesh is grown into planar, gravity-aligned regions (facing up, facing down or
//    vertical; each triangle's smoothed normal within region_normal_deg of the region's mean
//    normal and its centroid within region_plane_m of the region's plane). In a region of at
//    least region_min_area_m2 whose labelled area holds a class that fits the region's geometry
//    (as above) with at least region_min_share of the labelled area, that class fills the
//    region's unlabelled and contradicting vertices, and, when it is wall, floor or ceiling,
//    the vertices of classes that cannot lie in such a plane (objects and furniture: all but
//    the stuff classes and picture). An unlabelled region facing up at floor height is floor;
//    one facing down at ceiling height is ceiling (the lowest and highest large horizontal
//    surfaces).
//  - evidence that fits: a vertex still unlabelled or contradicting after the regions, where the
//    normal or height rules rule out some classes, gets the class its voxel's fused evidence
//    (SurfaceLabelEvidence) shows once those classes are impossible: the posterior conditioned on
//    the geometry, decided by the same thresholds as every label. A horizontal counter that the
//    network calls wall about as often as cabinet becomes cabinet, not unlabelled.
//  - segments: the mesh is cut into smooth segments where its normal turns (Felzenszwalb-
//    Huttenlocher over vertex edges weighted 1 - n_u.n_v, K = segment_k, as ScanNet segments its
//    meshes for labelling, without its joining of segments under 20 vertices,
//    which carried labels across objects). In a segment whose labelled area is at least
//    segment_min_labelled of its area and whose largest class holds region_min_share of that,
//    the class labels the vertices still unlabelled, unless it is wall, floor or ceiling: those
//    are decided by the planar regions (a counter front the network half calls wall would
//    otherwise become a wall). Parts of things the network saw too rarely or too uncertainly for
//    the per-voxel thresholds take the class of the surface they belong to; a segment boundary
//    (an edge, a corner, a change of curvature) stops it, as labels in a person's annotation do.
//    The segments are cut before the likely rule and shared with it.
//  - likely (before the segments' fill): a vertex still unlabelled whose voxel was labelled takes
//    the class c its evidence makes most probable, weighted by the map's own class frequencies
//    (the share of the labelled area, plus 1e-3 for a class the map shows nowhere):
//    argmax p(c | evidence) * prior(c) over the classes the network named there, when it leads
//    every other class and holds likely_probability of the sum (0: the most probable). Wall,
//    floor and ceiling are allowed only where every triangle around the vertex fits them. In a
//    smooth segment whose labelled vertices show some classes, only those. A surface seen in few
//    semantic frames, or from far, is named by its best evidence instead of left blank; a border
//    vertex whose voxel also saw the neighbouring object keeps to its segment's classes.
//  - other (after the segments): a vertex whose wall, floor or ceiling label its surface
//    contradicts, that no rule relabelled and that lies off the planes (region_plane_m) of the
//    regions decided wall, floor or ceiling, is `other`: an object the network does not name, in
//    front of the structure (the network calls a shelf's clutter wall). At a junction of two
//    structural planes it stays unlabelled.
//  - fringes (last): what is still unlabelled within fringe_m along the mesh of labelled surface
//    of its own smooth segment takes, ring by ring outward, the class with the most labelled
//    neighbour area in that segment among those its surface fits (wall, floor, ceiling only
//    where every triangle around the vertex fits them, as in the likely rule); a class reaches
//    no farther than fringe_m from where it was decided. The per-voxel thresholds leave seams a
//    few voxels wide along a surface's labelled parts. Across a crease the rule does not reach:
//    there it mostly carried an object's class onto the floor or wall at its foot (semap demo
//    mIoU 0.922 against 0.942 within segments).
#include <cstddef>

#include "semap/core/gravity.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/tsdf/tsdf_config.hpp"
#include "tsdf/voxel_label.hpp"

namespace semap {

/// What the rules changed (vertex counts).
struct LabelPriorStats {
  size_t contradicting = 0;  ///< labels the normal or height rules rejected
  size_t filled = 0;         ///< vertices given their region's class (from unlabelled or contradicting)
  size_t replaced = 0;       ///< object labels in a wall/floor/ceiling plane given its class
  size_t refitted = 0;       ///< vertices given the class their evidence shows among the fitting ones
  size_t segment_filled = 0; ///< unlabelled vertices given their smooth segment's class
  size_t likely_filled = 0;  ///< unlabelled vertices given their likely class (the likely rule)
  size_t other_filled = 0;   ///< structural labels ruled out, nothing fitting: `other`
  size_t fringe_filled = 0;  ///< unlabelled vertices near labelled ones given their neighbours' class
  size_t regions = 0;        ///< regions that decided a class
  double region_area_m2 = 0.0;  ///< their area
};

/// Applies the rules of the file comment that `config` switches on to mesh.vertices.labels.
/// `evidence` (one entry per vertex, or empty) enables the last rule. A mesh without labels is
/// left alone. Thread safety: touches only `mesh`.
LabelPriorStats apply_label_priors(TriangleMesh& mesh, const GravityEstimate& gravity, const TsdfConfig& config,
                                   const SurfaceLabelEvidence& evidence = {});

}  // namespace semap
