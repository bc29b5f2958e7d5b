#include "segmentation/nms.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace semap {

double box_iou(const cv::Rect2f& a, const cv::Rect2f& b) {
  const float x1 = std::max(a.x, b.x), y1 = std::max(a.y, b.y);
  const float x2 = std::min(a.x + a.width, b.x + b.width), y2 = std::min(a.y + a.height, b.y + b.height);
  const double inter = std::max(0.f, x2 - x1) * double(std::max(0.f, y2 - y1));
  const double uni = double(a.width) * a.height + double(b.width) * b.height - inter;
  return uni > 0 ? inter / uni : 0.0;
}

std::vector<NmsResult> hard_nms(const std::vector<ScoredBox>& boxes, double iou_threshold, bool class_agnostic,
                                int max_keep) {
  std::vector<int> order(boxes.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return boxes[a].score > boxes[b].score; });
  std::vector<NmsResult> kept;
  std::vector<bool> removed(boxes.size(), false);
  for (size_t i = 0; i < order.size() && static_cast<int>(kept.size()) < max_keep; ++i) {
    const int a = order[i];
    if (removed[a]) continue;
    kept.push_back({a, boxes[a].score});
    for (size_t j = i + 1; j < order.size(); ++j) {
      const int b = order[j];
      if (removed[b] || (!class_agnostic && boxes[a].class_id != boxes[b].class_id)) continue;
      if (box_iou(boxes[a].box, boxes[b].box) > iou_threshold) removed[b] = true;
    }
  }
  return kept;
}

std::vector<NmsResult> soft_nms(const std::vector<ScoredBox>& boxes, double sigma, double score_floor,
                                bool class_agnostic, int max_keep) {
  std::vector<float> score(boxes.size());
  std::vector<int> alive;
  for (size_t i = 0; i < boxes.size(); ++i) {
    score[i] = boxes[i].score;
    if (score[i] >= score_floor) alive.push_back(static_cast<int>(i));
  }
  std::vector<NmsResult> kept;
  while (!alive.empty() && static_cast<int>(kept.size()) < max_keep) {
    // Pick the best remaining (ties: lower index, for determinism).
    size_t best = 0;
    for (size_t k = 1; k < alive.size(); ++k)
      if (score[alive[k]] > score[alive[best]] || (score[alive[k]] == score[alive[best]] && alive[k] < alive[best]))
        best = k;
    const int m = alive[best];
    kept.push_back({m, score[m]});
    alive.erase(alive.begin() + static_cast<std::ptrdiff_t>(best));
    std::vector<int> next;
    next.reserve(alive.size());
    for (int i : alive) {
      if (class_agnostic || boxes[i].class_id == boxes[m].class_id) {
        const double iou = box_iou(boxes[m].box, boxes[i].box);
        score[i] = static_cast<float>(score[i] * std::exp(-iou * iou / sigma));
      }
      if (score[i] >= score_floor) next.push_back(i);
    }
    alive.swap(next);
  }
  return kept;
}

}  // namespace semap
