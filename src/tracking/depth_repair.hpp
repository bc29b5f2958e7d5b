#pragma once
// Joint median filter depth repair (METHODS.md A1).
#include <opencv2/core.hpp>

#include "semap/tracking/tracking_config.hpp"  // DepthRepairParams

namespace semap {

/// Fills every invalid (0 / non-finite) pixel of `depth` (CV_32FC1, metres) with the median of
/// the valid depths in its (2r+1)^2 window whose grey value (from `rgb`, CV_8UC3 BGR or CV_8UC1,
/// same size) is within t_gray of the centre's. Valid pixels are never changed. Row-parallel.
/// Throws semap::Error on type/size mismatch.
cv::Mat repair_depth(const cv::Mat& depth, const cv::Mat& rgb, const DepthRepairParams& params);

}  // namespace semap
