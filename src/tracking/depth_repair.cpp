#include "tracking/depth_repair.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.hpp"

namespace semap {

cv::Mat repair_depth(const cv::Mat& depth, const cv::Mat& rgb, const DepthRepairParams& params) {
  if (depth.type() != CV_32FC1) throw Error("repair_depth", "depth must be CV_32FC1");
  if (rgb.size() != depth.size()) throw Error("repair_depth", "rgb and depth sizes differ");
  if (params.radius < 1) throw Error("repair_depth", "radius must be >= 1");
  cv::Mat gray;
  if (rgb.type() == CV_8UC3) cv::cvtColor(rgb, gray, cv::COLOR_BGR2GRAY);
  else if (rgb.type() == CV_8UC1) gray = rgb;
  else throw Error("repair_depth", "rgb must be CV_8UC3 or CV_8UC1");

  cv::Mat out = depth.clone();
  const int r = params.radius;
  const int rows = depth.rows, cols = depth.cols;
  const int t_gray = static_cast<int>(std::lround(params.gray_threshold));
  // METHODS.md A1: only invalid centres, neighbours must be valid and of similar grey value.
  cv::parallel_for_(cv::Range(0, rows), [&](const cv::Range& range) {
    std::vector<float> window;
    window.reserve((2 * r + 1) * (2 * r + 1));
    for (int y = range.start; y < range.end; ++y) {
      const float* drow = depth.ptr<float>(y);
      float* orow = out.ptr<float>(y);
      const uint8_t* grow = gray.ptr<uint8_t>(y);
      for (int x = 0; x < cols; ++x) {
        const float d = drow[x];
        if (d > 0.0f && std::isfinite(d)) continue;
        orow[x] = 0.0f;  // non-finite invalid pixels become 0
        const int g0 = grow[x];
        window.clear();
        const int y0 = std::max(0, y - r), y1 = std::min(rows - 1, y + r);
        const int x0 = std::max(0, x - r), x1 = std::min(cols - 1, x + r);
        for (int yy = y0; yy <= y1; ++yy) {
          const float* dn = depth.ptr<float>(yy);
          const uint8_t* gn = gray.ptr<uint8_t>(yy);
          for (int xx = x0; xx <= x1; ++xx) {
            const float dv = dn[xx];
            if (!(dv > 0.0f) || !std::isfinite(dv)) continue;
            if (std::abs(int(gn[xx]) - g0) > t_gray) continue;
            window.push_back(dv);
          }
        }
        if (window.empty() || static_cast<int>(window.size()) < params.min_support) continue;
        auto mid = window.begin() + window.size() / 2;
        std::nth_element(window.begin(), mid, window.end());
        orow[x] = *mid;
      }
    }
  });
  return out;
}

}  // namespace semap
