#include "semap/core/point_cloud.hpp"

namespace semap {

void PointCloud::reserve(size_t n) {
  points.reserve(n);
  if (has_normals()) normals.reserve(n);
  if (has_colours()) colours.reserve(n);
  if (has_labels()) labels.reserve(n);
  if (has_instances()) instances.reserve(n);
}

void PointCloud::clear() {
  points.clear();
  normals.clear();
  colours.clear();
  labels.clear();
  instances.clear();
}

void PointCloud::push_back_from(const PointCloud& other, size_t i) {
  const bool first = empty();
  points.push_back(other.points[i]);
  if (other.has_normals() && (first || has_normals())) normals.push_back(other.normals[i]);
  if (other.has_colours() && (first || has_colours())) colours.push_back(other.colours[i]);
  if (other.has_labels() && (first || has_labels())) labels.push_back(other.labels[i]);
  if (other.has_instances() && (first || has_instances())) instances.push_back(other.instances[i]);
}

bool PointCloud::consistent() const {
  const size_t n = points.size();
  auto ok = [n](size_t m) { return m == 0 || m == n; };
  return ok(normals.size()) && ok(colours.size()) && ok(labels.size()) && ok(instances.size());
}

}  // namespace semap
