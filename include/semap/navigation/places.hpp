#pragma once
// Places of an occupancy grid (issue 39): the free space cut into rooms at narrow passages.
//
// Room space: the free cells plus the occupied cells whose top surface is an object's (a class
// that is not stuff; furniture stands inside a room and must not cut it). With
// place_passage_width_m = w > 0, a distance transform of the open space (room space and unknown
// cells: unobserved floor, e.g. the middle of a room a camera circled looking out, must not
// narrow a room) gives each cell its clearance (distance to the nearest closed cell: a wall, an
// obstacle that is no object); the cells with clearance > w / 2 are the room cores, and a core
// with clearance >= w somewhere (a room at least 2 w across) seeds a place with its room-space
// cells. Every room-space cell joins the seed
// reached first by a breadth-first growth over the room space (8-neighbourhood: a geodesic
// Voronoi split at the doors). Connected room space that no seed reaches is one place. A place
// with under min_place_area_m2 of free cells is dropped and the growth repeated without its
// seed. w = 0: one place per connected region of room space. One room gives one place.
//
// Passages: two places whose room-space cells touch (8-neighbourhood) share a passage, the door
// the growth split them at. Its width is twice the largest clearance (distance to the nearest
// closed cell, as above) among the cells along their border: where the border crosses the
// door, the middle of the door, half the door's width from either jamb. Its centre is that
// cell pair's midpoint.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semap/navigation/navigation_config.hpp"
#include "semap/navigation/occupancy_grid.hpp"

namespace semap {

struct PlaceNode {
  std::string id;  ///< "place_<k>"
  double area_m2 = 0.0;  ///< its free cells' area
  Eigen::Vector2d centroid_G = Eigen::Vector2d::Zero();  ///< mean of its free cells' centres
  size_t cells = 0;  ///< its free cells
  nlohmann::json evidence = nlohmann::json::object();  ///< how it was found (clearance, seeding)
};

/// A passage between places a < b (indices into PlaceMap::places); see the file comment.
struct PlacePassage {
  int a = -1, b = -1;
  double width_m = 0.0;
  Eigen::Vector2d centre_G = Eigen::Vector2d::Zero();
  size_t border_cells = 0;  ///< cells of either place with a neighbour in the other
};

struct PlaceMap {
  std::vector<PlaceNode> places;
  std::vector<PlacePassage> passages;  ///< ordered by (a, b)
  std::vector<int> place_of_cell;  ///< grid layout; index into places, -1: none
};

/// See the file comment. Parallel-safe; O(cells) per growth (a few growths at most).
PlaceMap segment_places(const OccupancyGrid& grid, const NavigationConfig& config);

}  // namespace semap
