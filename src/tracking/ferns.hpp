#pragma once
// Random-ferns keyframe database (METHODS.md A3, Glocker et al.).
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "semap/tracking/tracking_config.hpp"  // FernParams

namespace semap {

/// The m fern codes of one image.
using FernCode = std::vector<uint16_t>;

class FernDatabase {
 public:
  explicit FernDatabase(const FernParams& params);

  /// Encodes an RGB-D frame: downsample to width x height, then per fern n tests
  /// I(x, c) >= theta on channel c in {R, G, B, D} (depth in metres, 0 when invalid).
  FernCode encode(const cv::Mat& rgb, const cv::Mat& depth) const;
  /// Adds keyframe `id` (ids must be added in increasing order) to the code table.
  void add(int id, const FernCode& code);
  /// Similarity (fraction of ferns with equal code, in [0, 1]) of `code` to every stored
  /// keyframe, by walking the table rows of its codes. Indexed like ids().
  std::vector<double> similarities(const FernCode& code) const;
  /// Best similarity over all stored keyframes (0 when empty).
  double max_similarity(const FernCode& code) const;
  const std::vector<int>& ids() const { return ids_; }
  size_t size() const { return ids_.size(); }
  const FernParams& params() const { return params_; }

 private:
  struct Test {
    int x, y, channel;  ///< channel 0..2 = B, G, R (OpenCV order), 3 = depth
    float threshold;
  };
  FernParams params_;
  std::vector<Test> tests_;                           ///< fern_count * fern_tests
  std::vector<std::vector<std::vector<int>>> table_;  ///< [fern][code] -> positions in ids_
  std::vector<int> ids_;
};

}  // namespace semap
