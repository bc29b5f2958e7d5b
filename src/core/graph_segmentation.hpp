#pragma once
// Felzenszwalb-Huttenlocher graph segmentation ("Efficient graph-based image segmentation", 2004;
// METHODS.md C2.5): used on supervoxel graphs (objects, C2.5) and on mesh vertices (the label
// rules' smooth segments, tsdf/label_priors). Pure: no state, safe from any thread.
#include <vector>

namespace semap {

struct WeightedEdge {
  int a = 0, b = 0;
  float weight = 0.f;
};

/// Merges along increasing weight while w <= min(Int(C1) + k/|C1|, Int(C2) + k/|C2|) (Int: the
/// largest weight of a component's spanning tree). Returns a component id (0..C-1) per node,
/// numbered in node order. (The paper's joining of small components is left out: it ignores the
/// weights; tsdf/label_priors measured it carrying labels across objects.)
std::vector<int> felzenszwalb_cluster(int num_nodes, std::vector<WeightedEdge> edges, float k);

}  // namespace semap
