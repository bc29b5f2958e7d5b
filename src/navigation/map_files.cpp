#include "semap/navigation/map_files.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>

#include "core/paths.hpp"
#include "semap/core/error.hpp"

namespace semap {
namespace {

/// Grid row of image row `row` (images put the highest y first).
int grid_row(const OccupancyGrid& grid, int row) { return grid.height - 1 - row; }

std::string yaml_number(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

std::string yaml_common(const OccupancyGrid& grid, const std::string& image) {
  std::ostringstream y;
  y << "image: " << image << "\n"
    << "resolution: " << yaml_number(grid.resolution_m) << "\n"
    << "origin: [" << yaml_number(grid.origin_G.x()) << ", " << yaml_number(grid.origin_G.y()) << ", 0.0]\n";
  return y.str();
}

std::string yaml_frame(const OccupancyGrid& grid) {
  std::ostringstream y;
  y << "# semap keys (map_server ignores them). frame: the gravity frame G (z up, z = 0 on the floor);\n"
    << "# T_W_G: world (the run's trajectory frame) from G, 4x4 row-major.\n"
    << "frame: gravity\n"
    << "T_W_G: [";
  const Eigen::Matrix4d m = grid.T_W_G.matrix();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) y << (r || c ? ", " : "") << yaml_number(m(r, c));
  y << "]\n"
    << "min_height_m: " << yaml_number(grid.min_height_m) << "\n"
    << "max_height_m: " << yaml_number(grid.max_height_m) << "\n";
  return y.str();
}

std::string png_bytes(const cv::Mat& image, const std::string& name) {
  std::vector<uint8_t> buffer;
  if (!cv::imencode(".png", image, buffer)) throw Error(name, "cannot encode the PNG image");
  return std::string(buffer.begin(), buffer.end());
}

}  // namespace

std::string map_yaml(const OccupancyGrid& grid, const std::string& image) {
  std::ostringstream y;
  y << yaml_common(grid, image) << "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n"
    << yaml_frame(grid) << "labels_image: map_labels.png\n"
    << "# label_palette: class id, name and RGB colour of the map_labels.png pixels (black: no surface)\n"
    << "label_palette:\n";
  std::set<ClassId> classes(grid.top_label.begin(), grid.top_label.end());
  for (ClassId c : classes) {
    const Rgb8 rgb = class_colour(c);
    y << "  - {id: " << int(c) << ", name: " << class_name(c) << ", rgb: [" << int(rgb.r) << ", " << int(rgb.g) << ", "
      << int(rgb.b) << "]}\n";
  }
  return y.str();
}

std::string map_pgm(const OccupancyGrid& grid) {
  std::string out = "P5\n" + std::to_string(grid.width) + " " + std::to_string(grid.height) + "\n255\n";
  for (int row = 0; row < grid.height; ++row)
    for (int ix = 0; ix < grid.width; ++ix) {
      const CellState s = grid.state[grid.index(ix, grid_row(grid, row))];
      out.push_back(static_cast<char>(s == CellState::kOccupied ? kPgmOccupied
                                      : s == CellState::kFree   ? kPgmFree
                                                                : kPgmUnknown));
    }
  return out;
}

std::string npy_float32(const std::vector<float>& row_major, int rows, int cols) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(rows) + ", " +
                       std::to_string(cols) + "), }";
  // Magic (6) + version (2) + length (2) + header + '\n', padded with spaces to a multiple of 64.
  const size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  std::string out("\x93NUMPY\x01\x00", 8);
  out.push_back(static_cast<char>(header.size() & 0xff));
  out.push_back(static_cast<char>(header.size() >> 8));
  out += header;
  static_assert(std::endian::native == std::endian::little, "npy writer assumes little endian");
  const size_t at = out.size();
  out.resize(at + row_major.size() * sizeof(float));
  std::memcpy(out.data() + at, row_major.data(), row_major.size() * sizeof(float));
  return out;
}

void write_navigation_maps(const OccupancyGrid& grid, const std::filesystem::path& dir) {
  write_file_atomic(dir / "map.pgm", map_pgm(grid));
  write_file_atomic(dir / "map.yaml", map_yaml(grid, "map.pgm"));
  cv::Mat labels(std::max(grid.height, 1), std::max(grid.width, 1), CV_8UC3, cv::Scalar(0, 0, 0));
  for (int row = 0; row < grid.height; ++row)
    for (int ix = 0; ix < grid.width; ++ix) {
      const ClassId c = grid.top_label[grid.index(ix, grid_row(grid, row))];
      if (c == 0) continue;
      const Rgb8 rgb = class_colour(c);
      labels.at<cv::Vec3b>(row, ix) = {rgb.b, rgb.g, rgb.r};  // OpenCV writes BGR
    }
  write_file_atomic(dir / "map_labels.png", png_bytes(labels, (dir / "map_labels.png").string()));
  // The distance field, rows flipped like the images.
  const std::vector<float> distance = distance_to_obstacles_m(grid);
  std::vector<float> rows(distance.size());
  for (int row = 0; row < grid.height; ++row)
    for (int ix = 0; ix < grid.width; ++ix)
      rows[static_cast<size_t>(row) * grid.width + ix] = distance[grid.index(ix, grid_row(grid, row))];
  write_file_atomic(dir / "esdf.npy", npy_float32(rows, grid.height, grid.width));
  write_file_atomic(dir / "esdf.yaml", yaml_common(grid, "esdf.npy") +
                                           "# distance (m, float32) from each cell centre to the nearest occupied "
                                           "cell of map.pgm; rows like map.pgm\nunit: m\n" +
                                           yaml_frame(grid));
}

}  // namespace semap
