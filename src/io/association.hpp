#pragma once
// Timestamp association as in the TUM benchmark's associate.py: greedy over all candidate
// pairs sorted by |a - b| (+ offset), each timestamp used at most once, max difference.
#include <cstddef>
#include <utility>
#include <vector>

namespace semap {

/// Returns index pairs (i into a, j into b), sorted by i.
std::vector<std::pair<size_t, size_t>> associate_timestamps(const std::vector<double>& a,
                                                            const std::vector<double>& b,
                                                            double max_difference = 0.02,
                                                            double offset = 0.0);

}  // namespace semap
