#include "eval/nearest_neighbors.hpp"

#include <tbb/parallel_for.h>

#include <cmath>
#include <nanoflann.hpp>

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
}  // namespace

struct NearestNeighborIndex::Impl {
  CloudAdaptor adaptor;
  std::unique_ptr<KdTree> tree;
};

NearestNeighborIndex::NearestNeighborIndex(const std::vector<Eigen::Vector3f>& points)
    : impl_(std::make_unique<Impl>()) {
  impl_->adaptor.points = &points;
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
    hit.index = index;
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
