#include "io/association.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace semap {

// Same result as TUM's associate.py: all pairs with |a - (b + offset)| < max_difference,
// taken greedily by increasing difference, each timestamp used once. Candidates come from a
// window over sorted b instead of all n*m pairs.
std::vector<std::pair<size_t, size_t>> associate_timestamps(const std::vector<double>& a,
                                                            const std::vector<double>& b,
                                                            double max_difference, double offset) {
  std::vector<size_t> b_order(b.size());
  std::iota(b_order.begin(), b_order.end(), 0);
  std::sort(b_order.begin(), b_order.end(), [&](size_t x, size_t y) { return b[x] < b[y]; });
  std::vector<double> b_sorted(b.size());
  for (size_t k = 0; k < b.size(); ++k) b_sorted[k] = b[b_order[k]] + offset;

  std::vector<std::tuple<double, double, double, size_t, size_t>> candidates;  // diff, a, b, i, j
  for (size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i])) continue;
    auto it = std::lower_bound(b_sorted.begin(), b_sorted.end(), a[i] - max_difference);
    for (; it != b_sorted.end() && *it <= a[i] + max_difference; ++it) {
      const double diff = std::abs(a[i] - *it);
      const size_t j = b_order[it - b_sorted.begin()];
      if (diff < max_difference) candidates.emplace_back(diff, a[i], b[j], i, j);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<char> a_used(a.size(), 0), b_used(b.size(), 0);
  std::vector<std::pair<size_t, size_t>> matches;
  for (const auto& [diff, ta, tb, i, j] : candidates) {
    if (a_used[i] || b_used[j]) continue;
    a_used[i] = b_used[j] = 1;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

}  // namespace semap
