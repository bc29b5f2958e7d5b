#include "semap/synth/segmentation_noise.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <numeric>
#include <vector>

#include "semap/core/error.hpp"
#include "semap/core/labels.hpp"
#include "synth/random.hpp"

namespace semap {
namespace {

using synth_detail::hash_combine;
using synth_detail::hash_unit;

// Classes a flickering region turns into: the object classes of the synthetic world (a
// confusable set, like a real detector's errors) and the structural classes for stuff.
constexpr Label kObjectConfusions[] = {Label::kTable, Label::kChair, Label::kSofa, Label::kBookcase,
                                       Label::kCabinet, Label::kMonitor, Label::kCup, Label::kBottle,
                                       Label::kBox, Label::kPlant, Label::kLamp};
constexpr Label kStuffConfusions[] = {Label::kWall, Label::kFloor, Label::kCeiling, Label::kDoor};

template <size_t N>
ClassId wrong_class(ClassId truth, uint64_t h, const Label (&set)[N]) {
  // Uniform over the set without the true class.
  ClassId choices[N];
  size_t n = 0;
  for (Label l : set)
    if (id(l) != truth) choices[n++] = id(l);
  return choices[static_cast<size_t>(hash_unit(h) * n) % n];
}

enum Tag : uint64_t { kMiss = 1, kFlicker, kFlickerClass, kBorder, kBorderRadius, kBorderKind, kMerge, kStuff, kPixel, kSplit, kSplitAxis };

double unit(uint64_t seed, uint64_t tag, uint64_t a, uint64_t b = 0) {
  return hash_unit(hash_combine(hash_combine(hash_combine(seed, tag), a), b));
}

struct InstanceInfo {
  bool present = false;
  ClassId cls = 0;
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
};

int find_root(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Over-segmentation: the far half of a split instance's box (along its longer side, or the
// other one at random) becomes a new instance of the same class, with an id no instance uses.
void split_instances(cv::Mat& instances, const std::vector<int>& roots, const std::vector<char>& missed,
                     const std::vector<InstanceInfo>& info, std::vector<int>& parent, uint64_t seed, double rate) {
  int next_id = 1;
  for (size_t i = 1; i < info.size(); ++i)
    if (info[i].present) next_id = static_cast<int>(i) + 1;
  for (int r : roots) {
    if (missed[r] || unit(seed, kSplit, r) >= rate || next_id > 65535) continue;
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    for (size_t i = 1; i < info.size(); ++i)
      if (info[i].present && find_root(parent, static_cast<int>(i)) == r)
        x0 = std::min(x0, info[i].x0), y0 = std::min(y0, info[i].y0), x1 = std::max(x1, info[i].x1), y1 = std::max(y1, info[i].y1);
    const bool longer_is_x = x1 - x0 >= y1 - y0;
    const bool split_x = unit(seed, kSplitAxis, r) < 0.75 ? longer_is_x : !longer_is_x;
    const cv::Rect far_half = split_x ? cv::Rect((x0 + x1) / 2 + 1, y0, x1 - (x0 + x1) / 2, y1 - y0 + 1)
                                      : cv::Rect(x0, (y0 + y1) / 2 + 1, x1 - x0 + 1, y1 - (y0 + y1) / 2);
    if (far_half.area() <= 0) continue;
    cv::Mat half = instances(far_half);
    half.setTo(next_id++, half == r);
  }
}

}  // namespace

void SegmentationNoiseParams::visit(ParamVisitor& v) {
  v.param("flicker_rate", flicker_rate, "", "fraction of regions (instances, stuff classes) per frame with a wrong class", fraction());
  v.param("pixel_flicker_rate", pixel_flicker_rate, "", "fraction of labelled pixels per frame with a wrong class", fraction());
  v.param("miss_rate", miss_rate, "", "fraction of instances whose mask is dropped per frame", fraction());
  v.param("merge_rate", merge_rate, "", "probability that two touching instances are merged per frame", fraction());
  v.param("split_rate", split_rate, "", "fraction of instances per frame whose mask is split in two (over-segmentation)", fraction());
  v.param("border_rate", border_rate, "", "fraction of instances with eroded/dilated borders per frame", fraction());
  v.param("border_px", border_px, "px", "maximum erosion/dilation radius", {0, 50});
  v.param("noisy_stuff", noisy_stuff, "", "flicker also applies to wall/floor/ceiling/door regions");
}

void SegmentationNoiseParams::validate() const { check_param_ranges(*this, "simulated_segmentation"); }

std::pair<cv::Mat, cv::Mat> apply_segmentation_noise(const cv::Mat& labels_in, const cv::Mat& instances_in,
                                                     uint64_t seed, const SegmentationNoiseParams& p) {
  if (labels_in.type() != CV_8UC1) throw Error("segmentation noise", "labels must be CV_8UC1");
  if (instances_in.type() != CV_16UC1) throw Error("segmentation noise", "instances must be CV_16UC1");
  if (labels_in.size() != instances_in.size()) throw Error("segmentation noise", "labels and instances differ in size");
  const int rows = labels_in.rows, cols = labels_in.cols;
  cv::Mat labels = labels_in.clone(), instances = instances_in.clone();

  // 1. Instances present, their class (first pixel) and bounding box; touching pairs.
  std::vector<InstanceInfo> info(65536);
  std::vector<int> present;
  std::vector<std::pair<int, int>> touching;
  for (int v = 0; v < rows; ++v) {
    const uint16_t* in = instances_in.ptr<uint16_t>(v);
    const uint16_t* below = v + 1 < rows ? instances_in.ptr<uint16_t>(v + 1) : nullptr;
    const uint8_t* lab = labels_in.ptr<uint8_t>(v);
    for (int u = 0; u < cols; ++u) {
      const int i = in[u];
      if (i == 0) continue;
      InstanceInfo& s = info[i];
      if (!s.present) {
        s.present = true;
        s.cls = lab[u];
        present.push_back(i);
      }
      s.x0 = std::min(s.x0, u), s.x1 = std::max(s.x1, u), s.y0 = std::min(s.y0, v), s.y1 = std::max(s.y1, v);
      if (u + 1 < cols && in[u + 1] != 0 && in[u + 1] != i) touching.emplace_back(std::min(i, +in[u + 1]), std::max(i, +in[u + 1]));
      if (below && below[u] != 0 && below[u] != i) touching.emplace_back(std::min(i, +below[u]), std::max(i, +below[u]));
    }
  }
  std::sort(present.begin(), present.end());
  std::sort(touching.begin(), touching.end());
  touching.erase(std::unique(touching.begin(), touching.end()), touching.end());

  // 2. Merged neighbours: union-find, the smaller id survives.
  std::vector<int> parent(65536);
  for (int i : present) parent[i] = i;
  if (p.merge_rate > 0)
    for (const auto& [a, b] : touching)
      if (unit(seed, kMerge, a, b) < p.merge_rate) {
        const int ra = find_root(parent, a), rb = find_root(parent, b);
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
      }

  // 3. Per-root decisions: missed, class (flicker), border change.
  std::vector<uint16_t> out_id(65536, 0);
  std::vector<ClassId> out_cls(65536, 0);
  std::vector<int> roots;
  for (int i : present) {
    const int r = find_root(parent, i);
    if (r == i) roots.push_back(r);
  }
  std::vector<char> missed(65536, 0);
  for (int r : roots) {
    missed[r] = unit(seed, kMiss, r) < p.miss_rate;
    ClassId c = info[r].cls;
    if (unit(seed, kFlicker, r) < p.flicker_rate)
      c = wrong_class(c, hash_combine(hash_combine(seed, kFlickerClass), r), kObjectConfusions);
    out_cls[r] = c;
  }
  for (int i : present) {
    const int r = find_root(parent, i);
    out_id[i] = missed[r] ? 0 : static_cast<uint16_t>(r);
    out_cls[i] = missed[r] ? 0 : out_cls[r];
  }
  // Stuff regions (instance 0): one region per class.
  ClassId stuff_map[256];
  for (int c = 0; c < 256; ++c) {
    stuff_map[c] = static_cast<ClassId>(c);
    if (c > 0 && p.noisy_stuff && unit(seed, kStuff, c) < p.flicker_rate)
      stuff_map[c] = wrong_class(static_cast<ClassId>(c), hash_combine(hash_combine(seed, kStuff + 100), c), kStuffConfusions);
  }
  for (int v = 0; v < rows; ++v) {
    uint16_t* in = instances.ptr<uint16_t>(v);
    uint8_t* lab = labels.ptr<uint8_t>(v);
    for (int u = 0; u < cols; ++u) {
      if (in[u] == 0) {
        lab[u] = stuff_map[lab[u]];
      } else {
        const int i = in[u];
        lab[u] = out_cls[i];
        in[u] = out_id[i];
      }
    }
  }

  if (p.split_rate > 0) split_instances(instances, roots, missed, info, parent, seed, p.split_rate);

  // 4. Eroded / dilated borders of surviving roots (ascending id: deterministic overwrite order).
  if (p.border_rate > 0 && p.border_px > 0) {
    for (int r : roots) {
      if (missed[r] || unit(seed, kBorder, r) >= p.border_rate) continue;
      const int radius = 1 + std::min(p.border_px - 1, static_cast<int>(unit(seed, kBorderRadius, r) * p.border_px));
      const bool dilate = unit(seed, kBorderKind, r) < 0.5;
      int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
      for (int i : present)
        if (find_root(parent, i) == r)
          x0 = std::min(x0, info[i].x0), y0 = std::min(y0, info[i].y0), x1 = std::max(x1, info[i].x1),
          y1 = std::max(y1, info[i].y1);
      const cv::Rect roi = cv::Rect(x0 - radius - 1, y0 - radius - 1, x1 - x0 + 2 * radius + 3, y1 - y0 + 2 * radius + 3) &
                           cv::Rect(0, 0, cols, rows);
      cv::Mat inst_roi = instances(roi), lab_roi = labels(roi);
      const cv::Mat mask = inst_roi == r;
      const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
      cv::Mat changed;
      if (dilate) {
        cv::Mat grown;
        cv::dilate(mask, grown, kernel);
        changed = grown & ~mask;
        inst_roi.setTo(r, changed);
        lab_roi.setTo(out_cls[r], changed);
      } else {
        cv::Mat shrunk;
        cv::erode(mask, shrunk, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
        changed = mask & ~shrunk;
        inst_roi.setTo(0, changed);
        lab_roi.setTo(0, changed);
      }
    }
  }

  // 5. Single-pixel flicker.
  if (p.pixel_flicker_rate > 0) {
    for (int v = 0; v < rows; ++v) {
      uint8_t* lab = labels.ptr<uint8_t>(v);
      const uint16_t* in = instances.ptr<uint16_t>(v);
      for (int u = 0; u < cols; ++u) {
        if (lab[u] == 0) continue;
        const uint64_t idx = static_cast<uint64_t>(v) * cols + u;
        if (unit(seed, kPixel, idx) < p.pixel_flicker_rate)
          lab[u] = in[u] ? wrong_class(lab[u], hash_combine(seed ^ 0x9e37, idx), kObjectConfusions)
                         : wrong_class(lab[u], hash_combine(seed ^ 0x9e37, idx), kStuffConfusions);
      }
    }
  }
  return {labels, instances};
}

}  // namespace semap
