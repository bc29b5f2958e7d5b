#include "semap/navigation/places.hpp"

#include <algorithm>
#include <deque>
#include <map>
#include <set>
#include <opencv2/imgproc.hpp>

namespace semap {
namespace {

constexpr int kMaxGrowths = 16;  // each repeat drops at least one seed

/// Room space (see places.hpp): free cells and cells under an object's top surface.
cv::Mat room_space(const OccupancyGrid& grid) {
  cv::Mat room(grid.height, grid.width, CV_8UC1, cv::Scalar(0));
  for (int iy = 0; iy < grid.height; ++iy)
    for (int ix = 0; ix < grid.width; ++ix) {
      const size_t i = grid.index(ix, iy);
      const ClassId top = grid.top_label[i];
      const bool object_top = top != 0 && !is_stuff(top);
      room.at<uint8_t>(iy, ix) =
          grid.state[i] == CellState::kFree || (grid.state[i] == CellState::kOccupied && object_top) ? 1 : 0;
    }
  return room;
}

/// Labels 1..n-1 of the 8-connected components of `mask` (0: background); returns n.
int components(const cv::Mat& mask, cv::Mat& labels) { return cv::connectedComponents(mask, labels, 8, CV_32S); }

/// Multi-source breadth-first growth over `room` from the seed cells (seed_of_cell >= 0).
std::vector<int> grow(const cv::Mat& room, std::vector<int> seed_of_cell) {
  const int w = room.cols, h = room.rows;
  std::deque<int> queue;
  for (int i = 0; i < w * h; ++i)
    if (seed_of_cell[i] >= 0) queue.push_back(i);
  while (!queue.empty()) {
    const int i = queue.front();
    queue.pop_front();
    const int x = i % w, y = i / w;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;
        if (nx < 0 || ny < 0 || nx >= w || ny >= h || !room.at<uint8_t>(ny, nx)) continue;
        const int j = ny * w + nx;
        if (seed_of_cell[j] >= 0) continue;
        seed_of_cell[j] = seed_of_cell[i];
        queue.push_back(j);
      }
  }
  return seed_of_cell;
}

/// Open space: room space and unknown cells. Unobserved floor (the middle of a room a camera
/// circled, looking out) must not narrow a room; walls and unlabelled obstacles do.
cv::Mat open_space(const OccupancyGrid& grid, const cv::Mat& room) {
  cv::Mat open = room.clone();
  for (size_t i = 0; i < grid.state.size(); ++i)
    if (grid.state[i] == CellState::kUnknown) open.data[i] = 1;
  return open;
}

/// Seeds: core components (clearance in open space > w / 2) holding a cell with clearance >= w;
/// a seed is its room-space cells (none: no seed) and its largest clearance (m).
struct Seed {
  std::vector<int> cells;
  double clearance_m = 0.0;
};
/// Metres from each open cell's centre to the nearest closed cell's (a wall, an obstacle that
/// is no object).
cv::Mat clearance_map_m(const cv::Mat& open, double resolution_m) {
  cv::Mat clearance;
  cv::distanceTransform(open, clearance, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  return clearance * resolution_m;
}

std::vector<Seed> room_seeds(const cv::Mat& room, const cv::Mat& clearance, double passage_m) {
  const cv::Mat core = clearance > 0.5 * passage_m;
  cv::Mat labels;
  const int n = components(core, labels);
  std::vector<Seed> seeds(n);
  for (int y = 0; y < room.rows; ++y)
    for (int x = 0; x < room.cols; ++x) {
      const int k = labels.at<int>(y, x);
      if (k == 0) continue;
      seeds[k].clearance_m = std::max<double>(seeds[k].clearance_m, clearance.at<float>(y, x));
      if (room.at<uint8_t>(y, x)) seeds[k].cells.push_back(y * room.cols + x);
    }
  std::erase_if(seeds, [&](const Seed& s) { return s.cells.empty() || s.clearance_m < passage_m; });
  return seeds;
}

/// Passages between places whose cells touch (see places.hpp).
std::vector<PlacePassage> find_passages(const OccupancyGrid& grid, const std::vector<int>& place_of_cell,
                                        const cv::Mat& clearance) {
  struct Border {
    std::set<int> cells;
    float best_clearance_m = -1.f;
    Eigen::Vector2d centre_G = Eigen::Vector2d::Zero();
  };
  std::map<std::pair<int, int>, Border> borders;
  for (int y = 0; y < grid.height; ++y)
    for (int x = 0; x < grid.width; ++x) {
      const int i = static_cast<int>(grid.index(x, y)), p = place_of_cell[i];
      if (p < 0) continue;
      for (int dy = 0; dy <= 1; ++dy)  // each neighbour pair once: right, below-left, below, below-right
        for (int dx = -1; dx <= 1; ++dx) {
          if (dy == 0 && dx <= 0) continue;
          const int nx = x + dx, ny = y + dy;
          if (nx < 0 || ny >= grid.height || nx >= grid.width) continue;
          const int j = static_cast<int>(grid.index(nx, ny)), q = place_of_cell[j];
          if (q < 0 || q == p) continue;
          Border& b = borders[{std::min(p, q), std::max(p, q)}];
          b.cells.insert(i), b.cells.insert(j);
          const float c = std::min(clearance.at<float>(y, x), clearance.at<float>(ny, nx));
          if (c > b.best_clearance_m)
            b.best_clearance_m = c, b.centre_G = 0.5 * (grid.cell_centre(x, y) + grid.cell_centre(nx, ny));
        }
    }
  std::vector<PlacePassage> passages;
  for (const auto& [pair, b] : borders)
    passages.push_back({pair.first, pair.second, 2.0 * b.best_clearance_m, b.centre_G, b.cells.size()});
  return passages;
}

}  // namespace

PlaceMap segment_places(const OccupancyGrid& grid, const NavigationConfig& config) {
  PlaceMap out;
  if (grid.width == 0 || grid.height == 0) return out;
  const size_t n = grid.state.size();
  const cv::Mat room = room_space(grid);
  const cv::Mat clearance = clearance_map_m(open_space(grid, room), grid.resolution_m);
  std::vector<Seed> seeds;
  if (config.place_passage_width_m > 0) seeds = room_seeds(room, clearance, config.place_passage_width_m);
  const double cell_m2 = grid.resolution_m * grid.resolution_m;
  for (int growth = 0; growth < kMaxGrowths; ++growth) {
    // Seeds first, then one region per connected room space that no seed reaches.
    std::vector<int> region(n, -1);
    for (size_t s = 0; s < seeds.size(); ++s)
      for (int c : seeds[s].cells) region[c] = static_cast<int>(s);
    region = grow(room, region);
    cv::Mat unreached = room.clone();
    for (size_t i = 0; i < n; ++i)
      if (region[i] >= 0) unreached.data[i] = 0;
    cv::Mat labels;
    const int extra = components(unreached, labels);
    const int* label = labels.ptr<int>();  // continuous, grid layout
    for (size_t i = 0; i < n; ++i)
      if (label[i] > 0) region[i] = static_cast<int>(seeds.size()) + label[i] - 1;
    // Free area per region; drop a small seeded region and grow again without it.
    const size_t regions = seeds.size() + static_cast<size_t>(std::max(extra - 1, 0));
    std::vector<size_t> free_cells(regions, 0);
    for (size_t i = 0; i < n; ++i)
      if (region[i] >= 0 && grid.state[i] == CellState::kFree) ++free_cells[region[i]];
    const auto small = [&](size_t r) { return free_cells[r] * cell_m2 < config.min_place_area_m2; };
    size_t kept_seeds = 0;
    std::vector<Seed> next;
    for (size_t s = 0; s < seeds.size(); ++s)
      if (!small(s)) next.push_back(std::move(seeds[s])), ++kept_seeds;
    if (kept_seeds < seeds.size() && growth + 1 < kMaxGrowths) {
      seeds = std::move(next);
      continue;
    }
    // Final: number the kept regions as places.
    std::vector<int> place_of_region(regions, -1);
    for (size_t r = 0; r < regions; ++r) {
      if (small(r)) continue;
      place_of_region[r] = static_cast<int>(out.places.size());
      PlaceNode p;
      p.id = "place_" + std::to_string(out.places.size());
      p.cells = free_cells[r];
      p.area_m2 = free_cells[r] * cell_m2;
      p.evidence = r < seeds.size() ? nlohmann::json{{"split", "narrow_passage"},
                                                     {"passage_width_m", config.place_passage_width_m},
                                                     {"max_clearance_m", seeds[r].clearance_m}}
                                    : nlohmann::json{{"split", "connected_region"}};
      out.places.push_back(std::move(p));
    }
    out.place_of_cell.assign(n, -1);
    std::vector<Eigen::Vector2d> sum(out.places.size(), Eigen::Vector2d::Zero());
    for (int iy = 0; iy < grid.height; ++iy)
      for (int ix = 0; ix < grid.width; ++ix) {
        const size_t i = grid.index(ix, iy);
        const int p = region[i] >= 0 ? place_of_region[region[i]] : -1;
        out.place_of_cell[i] = p;
        if (p >= 0 && grid.state[i] == CellState::kFree) sum[p] += grid.cell_centre(ix, iy);
      }
    for (size_t p = 0; p < out.places.size(); ++p) out.places[p].centroid_G = sum[p] / static_cast<double>(out.places[p].cells);
    out.passages = find_passages(grid, out.place_of_cell, clearance);
    break;
  }
  return out;
}

}  // namespace semap
