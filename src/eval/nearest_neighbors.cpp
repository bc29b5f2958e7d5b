#include "eval/nearest_neighbors.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <nanoflann.hpp>
#include <numeric>

namespace semap::eval_detail {

namespace {
struct CloudAdaptor {
  const std::vector<Eigen::Vector3f>* points;
  size_t kdtree_get_point_count() const { return points->size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return (*points)[i][static_cast<int>(dim)]; }
  template <class Bbox>
  bool kdtree_get_bbox(Bbox&) const { return false; }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CloudAdaptor>,
                                                   CloudAdaptor, 3, size_t>;

/// Bit pattern of a point: a total order (NaN included) under which equal coordinates compare equal.
std::array<uint32_t, 3> bits_of(const Eigen::Vector3f& p) {
  return {std::bit_cast<uint32_t>(p.x()), std::bit_cast<uint32_t>(p.y()), std::bit_cast<uint32_t>(p.z())};
}
}  // namespace

struct NearestNeighborIndex::Impl {
  std::vector<Eigen::Vector3f> unique_points;  ///< the input without repeats, when it has any
  std::vector<size_t> original_index;          ///< unique point -> lowest input index (empty: identity)
  CloudAdaptor adaptor;
  std::unique_ptr<KdTree> tree;
};

// The tree holds each distinct point once: nanoflann visits every leaf whose distance ties the
// best one, so N copies of one point made each query O(N) and a search O(N^2) (issue 44, class 7:
// 1M identical vertices took minutes). Deduplication is a sort, O(N log N).
NearestNeighborIndex::NearestNeighborIndex(const std::vector<Eigen::Vector3f>& points)
    : impl_(std::make_unique<Impl>()) {
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return bits_of(points[a]) < bits_of(points[b]); });
  for (size_t k = 0; k < order.size(); ++k)
    if (k == 0 || bits_of(points[order[k]]) != bits_of(points[order[k - 1]]))
      impl_->original_index.push_back(order[k]);  // stable sort: the first of equal points
  if (impl_->original_index.size() == points.size()) {
    std::vector<size_t>().swap(impl_->original_index);  // no repeats: the tree indexes `points` itself
    impl_->adaptor.points = &points;
  } else {
    impl_->unique_points.reserve(impl_->original_index.size());
    for (size_t i : impl_->original_index) impl_->unique_points.push_back(points[i]);
    impl_->adaptor.points = &impl_->unique_points;
  }
  if (!points.empty())
    impl_->tree = std::make_unique<KdTree>(3, impl_->adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
}

NearestNeighborIndex::~NearestNeighborIndex() = default;

NearestNeighborIndex::Hit NearestNeighborIndex::nearest(const Eigen::Vector3f& query) const {
  Hit hit;
  if (!impl_->tree) return hit;
  size_t index = 0;
  float distance_sq = 0.0f;
  if (impl_->tree->knnSearch(query.data(), 1, &index, &distance_sq) == 1) {
    hit.index = impl_->original_index.empty() ? index : impl_->original_index[index];
    hit.distance = std::sqrt(distance_sq);
  }
  return hit;
}

std::vector<NearestNeighborIndex::Hit> NearestNeighborIndex::nearest_all(
    const std::vector<Eigen::Vector3f>& queries) const {
  std::vector<Hit> hits(queries.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, queries.size(), 4096), [&](const auto& range) {
    for (size_t i = range.begin(); i < range.end(); ++i) hits[i] = nearest(queries[i]);
  });
  return hits;
}

}  // namespace semap::eval_detail
