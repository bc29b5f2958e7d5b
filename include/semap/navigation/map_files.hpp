#pragma once
// The occupancy grid and its distance field as files a robot stack opens as they are (issue 39):
//
//   map.pgm         ROS map_server image (binary P5, 8 bit): 0 occupied (black), 254 free,
//                   205 unknown; the first image row is the grid's highest y (map_server's
//                   lower-left origin convention).
//   map.yaml        map_server description: image, resolution (m/cell), origin [x, y, yaw] (m,
//                   rad: the lower-left pixel's corner in the gravity frame G), negate 0,
//                   occupied_thresh 0.65, free_thresh 0.196, mode trinary; plus semap keys that
//                   map_server ignores: frame, T_W_G (4x4 row-major, world from G), height band,
//                   labels_image and label_palette (class id, name, rgb of map_labels.png).
//   map_labels.png  RGB: the palette colour of each cell's top-most surface class (black: none).
//   esdf.npy        float32 (NumPy .npy, C order, rows like map.pgm): distance (m) from each
//                   cell centre to the nearest occupied cell (inf: no obstacle at all).
//   esdf.yaml       the same resolution and origin, image: esdf.npy.
// Every file is written atomically (write_file_atomic) into `dir`.
#include <filesystem>
#include <string>

#include "semap/navigation/occupancy_grid.hpp"

namespace semap {

/// map_server pixel values.
inline constexpr uint8_t kPgmOccupied = 0, kPgmFree = 254, kPgmUnknown = 205;

/// The YAML text of map.yaml for `grid` (image file name given).
std::string map_yaml(const OccupancyGrid& grid, const std::string& image);
/// Binary PGM bytes of the grid (see the file comment).
std::string map_pgm(const OccupancyGrid& grid);
/// NumPy .npy (format 1.0, '<f4', C order) bytes of a rows x cols float image.
std::string npy_float32(const std::vector<float>& row_major, int rows, int cols);

/// Writes map.pgm, map.yaml, map_labels.png, esdf.npy and esdf.yaml into `dir`. Throws
/// semap::Error naming the file that cannot be written.
void write_navigation_maps(const OccupancyGrid& grid, const std::filesystem::path& dir);

}  // namespace semap
