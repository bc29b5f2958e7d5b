#pragma once
// Parameters of the robot-facing maps (issue 39): the 2D occupancy grid, its distance field
// and the scene graph's relations. Heights are in the gravity frame (core/gravity.hpp: z up,
// z = 0 on the floor plane).
#include "semap/core/params.hpp"

namespace semap {

struct NavigationConfig {
  double min_height_m = 0.10;  ///< surfaces above this are obstacles; below it they are floor
  double max_height_m = 1.20;  ///< surfaces above this (ceiling, shelves over the robot) are ignored
  double resolution_m = 0.05;  ///< grid cell edge
  double on_tolerance_m = 0.06;    ///< `on`: |object bottom - support top| at most this
  double floor_support_max_gap_m = 0.25;  ///< `on` the floor: unsupported bottom at most this high
  double near_distance_m = 1.0;    ///< `near`: centroid distance at most this
  double min_place_area_m2 = 0.5;  ///< free regions smaller than this are no place
  double place_passage_width_m = 0.9;   ///< passages narrower than this (doors) separate places
  double vertical_tolerance_deg = 15.0;  ///< walls: normal within this of horizontal; ceiling: of vertical
  double wall_plane_tolerance_m = 0.08;  ///< wall triangles within this of their plane
  double wall_min_area_m2 = 0.4;         ///< smaller vertical planes are no wall
  double wall_min_top_m = 1.4;           ///< an unlabelled wall reaches this high (furniture stays below)
  double ceiling_min_height_m = 1.8;     ///< ceiling candidates lie at least this high
  double esdf_max_distance_m = 2.0;      ///< 3D distance field: farther reads as this ("at least")
  double esdf_max_memory_mb = 512.0;     ///< 3D distance field: build memory limit (cells coarsen to fit)

  void visit(ParamVisitor& v) {
    v.param("min_height_m", min_height_m, "m",
            "lower edge of the robot's height band above the floor: surfaces below it are floor (free when "
            "nothing is in the band), surfaces from it up to max_height_m are obstacles",
            {0.0, 10.0});
    v.param("max_height_m", max_height_m, "m", "upper edge of the robot's height band (its height)", positive(100.0));
    v.param("resolution_m", resolution_m, "m", "occupancy grid and distance field cell edge", {0.005, 1.0});
    v.param("on_tolerance_m", on_tolerance_m, "m",
            "scene graph `on`: the object's bottom lies within this of the supporting top surface", non_negative(1.0));
    v.param("floor_support_max_gap_m", floor_support_max_gap_m, "m",
            "scene graph `on` the floor: an object no other object supports rests on the floor when its bottom lies "
            "at most this above it (legs hidden under a table); higher ones (wall-mounted) rest on nothing",
            non_negative(10.0));
    v.param("near_distance_m", near_distance_m, "m", "scene graph `near`: object centroids at most this apart",
            non_negative(100.0));
    v.param("min_place_area_m2", min_place_area_m2, "m^2", "scene graph places: free regions of at least this area",
            non_negative(1e6));
    v.param("place_passage_width_m", place_passage_width_m, "m",
            "scene graph places: free-space passages narrower than this (doors) separate places (rooms); cells "
            "under objects count as floor for this split, so furniture does not cut a room; 0: one place per "
            "connected free region",
            non_negative(100.0));
    v.param("vertical_tolerance_deg", vertical_tolerance_deg, "deg",
            "structural surfaces: wall triangles have normals within this of horizontal, ceiling triangles within "
            "this of vertical",
            {1.0, 45.0});
    v.param("wall_plane_tolerance_m", wall_plane_tolerance_m, "m",
            "walls: triangles within this of the fitted plane (depth noise and drift make a wall a few cm thick in "
            "the mesh)",
            {0.005, 1.0});
    v.param("wall_min_area_m2", wall_min_area_m2, "m^2", "walls: observed area of at least this", positive(1e6));
    v.param("wall_min_top_m", wall_min_top_m, "m",
            "walls: a plane not mostly labelled wall is a wall only when its top (98th height percentile) reaches at "
            "least this above the floor; lower vertical surfaces (furniture sides, counters) are no wall",
            non_negative(100.0));
    v.param("ceiling_min_height_m", ceiling_min_height_m, "m",
            "ceiling: downward-facing horizontal surfaces at least this high above the floor", positive(100.0));
    v.param("esdf_max_distance_m", esdf_max_distance_m, "m",
            "3D distance queries (navigation/esdf.hpp): distances beyond this read as this (at least that far); "
            "is_free with a larger radius answers false",
            {0.05, 100.0});
    v.param("esdf_max_memory_mb", esdf_max_memory_mb, "MiB",
            "3D distance field: its build uses at most this (13 B per cell over the map's bounding box); larger "
            "maps get cells of 2, 3, ... voxels, up to 16",
            {1.0, 1e6});
  }
  void validate() const {
    check_param_ranges(*this, "navigation");
    require_param(max_height_m > min_height_m, "navigation.max_height_m", "must be > min_height_m");
  }
};

}  // namespace semap
