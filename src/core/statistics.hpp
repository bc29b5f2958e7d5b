#pragma once
// Small statistics shared by the stages and the metrics.
#include <algorithm>
#include <vector>

namespace semap {

/// Median (mean of the two middle values for an even count); 0 for an empty set.
template <class T>
double median_of(std::vector<T> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + mid, values.end());
  double m = values[mid];
  if (values.size() % 2 == 0) m = 0.5 * (m + *std::max_element(values.begin(), values.begin() + mid));
  return m;
}

}  // namespace semap
