// The occupancy grid as a picture for report.html (issue 39 "the report shows the grid as a
// picture"). Reads the grid the run published (navigation/occupancy_grid.hpp), the same cells
// map.pgm and map_labels.png hold, and draws the camera path over it.
#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pipeline/report.hpp"

namespace semap {
namespace {

constexpr int kMaxCellPx = 12;  ///< a small grid is drawn with cells at most this big

cv::Vec3b cell_colour(const OccupancyGrid& grid, size_t i) {
  switch (grid.state[i]) {
    case CellState::kFree: return {255, 255, 255};
    case CellState::kUnknown: return {205, 205, 205};  // map.pgm's unknown grey
    case CellState::kOccupied: break;
  }
  const ClassId label = i < grid.top_label.size() ? grid.top_label[i] : 0;
  if (label == 0) return {0, 0, 0};
  const Rgb8 c = class_colour(label);
  return {c.b, c.g, c.r};
}

/// Classes of the occupied cells, most cells first.
std::vector<ClassId> occupied_classes(const OccupancyGrid& grid) {
  std::map<ClassId, size_t> cells;
  for (size_t i = 0; i < grid.state.size() && i < grid.top_label.size(); ++i)
    if (grid.state[i] == CellState::kOccupied && grid.top_label[i] != 0) ++cells[grid.top_label[i]];
  std::vector<std::pair<size_t, ClassId>> order;
  for (const auto& [c, n] : cells) order.emplace_back(n, c);
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<ClassId> out;
  for (const auto& [n, c] : order) out.push_back(c);
  return out;
}

/// The camera path in grid cells (x right, y down from the grid's highest row, fractional).
std::vector<cv::Point2d> path_in_cells(const OccupancyGrid& grid, const Trajectory& trajectory) {
  const Pose T_G_W = grid.T_W_G.inverse();
  std::vector<cv::Point2d> path;
  for (const auto& p : trajectory) {
    const Eigen::Vector3d p_G = T_G_W * p.T_world_camera.translation();
    const Eigen::Vector2d cell = (p_G.head<2>() - grid.origin_G) / grid.resolution_m;
    path.emplace_back(cell.x(), grid.height - cell.y());
  }
  return path;
}

/// Cells added around the grid so that the whole path shows (the camera may move where no
/// floor or obstacle was mapped): left, top, right, bottom.
cv::Vec4i margin_for(const std::vector<cv::Point2d>& path, int width, int height) {
  constexpr int kPad = 2;
  cv::Vec4i m(0, 0, 0, 0);
  for (const cv::Point2d& p : path) {
    m[0] = std::max(m[0], static_cast<int>(std::ceil(-p.x)) + kPad);
    m[1] = std::max(m[1], static_cast<int>(std::ceil(-p.y)) + kPad);
    m[2] = std::max(m[2], static_cast<int>(std::ceil(p.x - width)) + kPad);
    m[3] = std::max(m[3], static_cast<int>(std::ceil(p.y - height)) + kPad);
  }
  return m;
}

void draw_path(cv::Mat& image, const std::vector<cv::Point2d>& path_cells, cv::Point2d offset_cells, int cell_px) {
  if (path_cells.empty()) return;
  std::vector<cv::Point> path;
  for (const cv::Point2d& p : path_cells) path.emplace_back(cv::Point((p + offset_cells) * cell_px));
  const cv::Scalar blue(200, 80, 20);  // BGR
  cv::polylines(image, path, false, cv::Scalar(255, 255, 255), 4, cv::LINE_AA);
  cv::polylines(image, path, false, blue, 2, cv::LINE_AA);
  cv::circle(image, path.front(), 5, cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA);
}

}  // namespace

GridPicture render_grid_picture(const OccupancyGrid& grid, const Trajectory& trajectory, int max_side_px) {
  GridPicture picture;
  if (grid.width <= 0 || grid.height <= 0 || grid.state.size() != static_cast<size_t>(grid.width) * grid.height)
    return picture;
  const std::vector<cv::Point2d> path = path_in_cells(grid, trajectory);
  const cv::Vec4i margin = margin_for(path, grid.width, grid.height);
  const int width = grid.width + margin[0] + margin[2], height = grid.height + margin[1] + margin[3];
  const int cell_px = std::clamp(max_side_px / std::max(width, height), 1, kMaxCellPx);
  cv::Mat cells(height, width, CV_8UC3, cv::Scalar(205, 205, 205));  // outside the grid: unknown
  for (int iy = 0; iy < grid.height; ++iy)
    for (int ix = 0; ix < grid.width; ++ix)  // row 0: the highest y
      cells.at<cv::Vec3b>(margin[1] + grid.height - 1 - iy, margin[0] + ix) = cell_colour(grid, grid.index(ix, iy));
  cv::Mat image;
  cv::resize(cells, image, {}, cell_px, cell_px, cv::INTER_NEAREST);
  if (margin != cv::Vec4i(0, 0, 0, 0))  // where map.pgm ends
    cv::rectangle(image, cv::Rect(margin[0] * cell_px, margin[1] * cell_px, grid.width * cell_px, grid.height * cell_px),
                  cv::Scalar(120, 120, 120), 1);
  draw_path(image, path, cv::Point2d(margin[0], margin[1]), cell_px);
  std::vector<uint8_t> png;
  cv::imencode(".png", image, png);
  picture.png.assign(png.begin(), png.end());
  picture.classes = occupied_classes(grid);
  picture.resolution_m = grid.resolution_m;
  picture.width_cells = grid.width;
  picture.height_cells = grid.height;
  picture.free_cells = grid.count(CellState::kFree);
  picture.occupied_cells = grid.count(CellState::kOccupied);
  picture.unknown_cells = grid.count(CellState::kUnknown);
  return picture;
}

}  // namespace semap
