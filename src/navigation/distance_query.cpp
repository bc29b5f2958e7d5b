#include "semap/navigation/distance_query.hpp"

#include <cmath>

namespace semap {

bool DistanceQuery::is_free(const Eigen::Vector3d& p_W, double radius_m) const {
  if (!(radius_m >= 0.0) || radius_m > max_distance_m()) return false;
  const double d = distance_m(p_W);
  return !std::isnan(d) && d >= radius_m;
}

}  // namespace semap
