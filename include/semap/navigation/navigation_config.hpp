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
  double near_distance_m = 1.0;    ///< `near`: centroid distance at most this
  double min_place_area_m2 = 0.5;  ///< free regions smaller than this are no place

  void visit(ParamVisitor& v) {
    v.param("min_height_m", min_height_m, "m",
            "lower edge of the robot's height band above the floor: surfaces below it are floor (free when "
            "nothing is in the band), surfaces from it up to max_height_m are obstacles",
            {0.0, 10.0});
    v.param("max_height_m", max_height_m, "m", "upper edge of the robot's height band (its height)", positive(100.0));
    v.param("resolution_m", resolution_m, "m", "occupancy grid and distance field cell edge", {0.005, 1.0});
    v.param("on_tolerance_m", on_tolerance_m, "m",
            "scene graph `on`: the object's bottom lies within this of the supporting top surface", non_negative(1.0));
    v.param("near_distance_m", near_distance_m, "m", "scene graph `near`: object centroids at most this apart",
            non_negative(100.0));
    v.param("min_place_area_m2", min_place_area_m2, "m^2", "scene graph places: free regions of at least this area",
            non_negative(1e6));
  }
  void validate() const {
    check_param_ranges(*this, "navigation");
    require_param(max_height_m > min_height_m, "navigation.max_height_m", "must be > min_height_m");
  }
};

}  // namespace semap
