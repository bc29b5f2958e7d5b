#pragma once
// Exact nearest-neighbour queries over a point set (nanoflann k-d tree), used by the
// evaluation metrics.
#include <Eigen/Core>
#include <limits>
#include <memory>
#include <vector>

namespace semap::eval_detail {

class NearestNeighborIndex {
 public:
  /// Keeps a reference to `points`: they must outlive the index. Repeated points are indexed
  /// once (a copy of the distinct ones, only when there are repeats); a hit names the lowest
  /// index holding its point. O(N log N). Queries are thread-safe (const).
  explicit NearestNeighborIndex(const std::vector<Eigen::Vector3f>& points);
  ~NearestNeighborIndex();
  NearestNeighborIndex(const NearestNeighborIndex&) = delete;
  NearestNeighborIndex& operator=(const NearestNeighborIndex&) = delete;

  struct Hit {
    size_t index = 0;
    float distance = std::numeric_limits<float>::infinity();  ///< inf when the set is empty
  };
  Hit nearest(const Eigen::Vector3f& query) const;
  /// nearest() for every query, in parallel (TBB).
  std::vector<Hit> nearest_all(const std::vector<Eigen::Vector3f>& queries) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace semap::eval_detail
