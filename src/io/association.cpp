#include "io/association.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <tuple>

namespace semap {

// Same result as TUM's associate.py: all pairs with |a - (b + offset)| < max_difference,
// taken greedily by increasing difference (ties by a, b, i, j), each timestamp used once.
//
// Not by listing every pair within max_difference: dense timestamps (1M poses 1 us apart) made
// that list billions long (issue 44, class 2: 2-3.7 GB). In one sorted list of both sides, the
// closest remaining a-b pair is always adjacent (any element between them is nearer to one of
// the two when timestamps within one side are distinct), so a heap of adjacent pairs over a
// linked list, updated as matched elements leave it, gives the same greedy order in O(n log n)
// time and O(n) memory.
std::vector<std::pair<size_t, size_t>> associate_timestamps(const std::vector<double>& a,
                                                            const std::vector<double>& b,
                                                            double max_difference, double offset) {
  struct Element {
    double time;   ///< a[i] or b[j] + offset
    bool from_b;
    size_t index;  ///< i or j
  };
  std::vector<Element> merged;
  merged.reserve(a.size() + b.size());
  for (size_t i = 0; i < a.size(); ++i)
    if (std::isfinite(a[i])) merged.push_back({a[i], false, i});
  for (size_t j = 0; j < b.size(); ++j)
    if (std::isfinite(b[j] + offset)) merged.push_back({b[j] + offset, true, j});
  std::stable_sort(merged.begin(), merged.end(), [](const Element& x, const Element& y) { return x.time < y.time; });

  const size_t n = merged.size();
  constexpr size_t kNone = static_cast<size_t>(-1);
  std::vector<size_t> prev(n), next(n);
  for (size_t k = 0; k < n; ++k) {
    prev[k] = k == 0 ? kNone : k - 1;
    next[k] = k + 1 == n ? kNone : k + 1;
  }
  // (diff, a time, b time, i, j, position of the a element, position of the b element)
  using Candidate = std::tuple<double, double, double, size_t, size_t, size_t, size_t>;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<>> heap;
  auto push_if_pair = [&](size_t x, size_t y) {
    if (x == kNone || y == kNone || merged[x].from_b == merged[y].from_b) return;
    const size_t pa = merged[x].from_b ? y : x, pb = merged[x].from_b ? x : y;
    const double diff = std::abs(merged[pa].time - merged[pb].time);
    if (!(diff < max_difference)) return;
    heap.emplace(diff, a[merged[pa].index], b[merged[pb].index], merged[pa].index, merged[pb].index, pa, pb);
  };
  for (size_t k = 0; k + 1 < n; ++k) push_if_pair(k, k + 1);

  std::vector<char> used(n, 0);
  std::vector<std::pair<size_t, size_t>> matches;
  auto unlink = [&](size_t k) {
    if (prev[k] != kNone) next[prev[k]] = next[k];
    if (next[k] != kNone) prev[next[k]] = prev[k];
  };
  while (!heap.empty()) {
    const auto [diff, ta, tb, i, j, pa, pb] = heap.top();
    heap.pop();
    if (used[pa] || used[pb]) continue;  // elements leave the list only when matched
    used[pa] = used[pb] = 1;
    matches.emplace_back(i, j);
    const size_t left = prev[std::min(pa, pb)], right = next[std::max(pa, pb)];
    unlink(pa);
    unlink(pb);
    push_if_pair(left, right);  // the two neighbours are now adjacent
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

}  // namespace semap
