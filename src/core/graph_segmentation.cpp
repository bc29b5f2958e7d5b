#include "core/graph_segmentation.hpp"

#include <algorithm>
#include <numeric>

namespace semap {

namespace {

struct DisjointSets {
  std::vector<int> parent, size;
  std::vector<float> internal;  // Int(C): largest weight in the component's spanning tree
  explicit DisjointSets(int n) : parent(n), size(n, 1), internal(n, 0.f) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  }
  void unite(int a, int b, float w) {
    if (size[a] < size[b]) std::swap(a, b);
    parent[b] = a;
    size[a] += size[b];
    internal[a] = std::max({internal[a], internal[b], w});
  }
};

}  // namespace

std::vector<int> felzenszwalb_cluster(int num_nodes, std::vector<WeightedEdge> edges, float k) {
  std::stable_sort(edges.begin(), edges.end(),
                   [](const WeightedEdge& x, const WeightedEdge& y) { return x.weight < y.weight; });
  DisjointSets sets(num_nodes);
  for (const auto& e : edges) {
    const int a = sets.find(e.a), b = sets.find(e.b);
    if (a == b) continue;
    const float threshold = std::min(sets.internal[a] + k / static_cast<float>(sets.size[a]),
                                     sets.internal[b] + k / static_cast<float>(sets.size[b]));
    if (e.weight <= threshold) sets.unite(a, b, e.weight);
  }
  std::vector<int> component(num_nodes, -1), remap(num_nodes, -1);
  int next = 0;
  for (int i = 0; i < num_nodes; ++i) {
    const int root = sets.find(i);
    if (remap[root] < 0) remap[root] = next++;
    component[i] = remap[root];
  }
  return component;
}

}  // namespace semap
