#include "tracking/depth_repair.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "semap/core/error.hpp"
#include "tracking/parallel.hpp"

namespace semap {

cv::Mat repair_depth(const cv::Mat& depth, const cv::Mat& rgb, const DepthRepairParams& params) {
  if (depth.type() != CV_32FC1) throw Error("repair_depth", "depth must be CV_32FC1");
  if (rgb.size() != depth.size()) throw Error("repair_depth", "rgb and depth sizes differ");
  if (params.radius < 1) throw Error("repair_depth", "radius must be >= 1");
  cv::Mat gray;
  if (rgb.type() == CV_8UC3) cv::cvtColor(rgb, gray, cv::COLOR_BGR2GRAY);
  else if (rgb.type() == CV_8UC1) gray = rgb;
  else throw Error("repair_depth", "rgb must be CV_8UC3 or CV_8UC1");

  const int r = params.radius;
  const int rows = depth.rows, cols = depth.cols;
  const int t_gray = static_cast<int>(std::lround(params.gray_threshold));
  const int min_support = std::max(1, params.min_support);
  // Clean copy: every invalid pixel (0, negative, NaN, inf) becomes 0, so the window test below
  // is a single comparison; it is also the output (valid pixels never change).
  cv::Mat out(depth.size(), CV_32FC1);
  cv::Mat invalid(depth.size(), CV_8UC1);
  for (int y = 0; y < rows; ++y) {
    const float* d = depth.ptr<float>(y);
    float* o = out.ptr<float>(y);
    uint8_t* m = invalid.ptr<uint8_t>(y);
    for (int x = 0; x < cols; ++x) {
      const bool ok = d[x] > 0.0f && d[x] < std::numeric_limits<float>::infinity();
      o[x] = ok ? d[x] : 0.0f;
      m[x] = !ok;
    }
  }
  const cv::Mat clean = out.clone();
  // Valid pixels per column over the window's rows (<= 2r+1 <= 31): a centre whose window holds
  // fewer than min_support valid pixels (hole interiors) is skipped after 2r+1 additions.
  cv::Mat column_valid(depth.size(), CV_8UC1);
  tracking_detail::parallel_rows(cv::Range(0, rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const int y0 = std::max(0, y - r), y1 = std::min(rows - 1, y + r);
      uint8_t* __restrict c = column_valid.ptr<uint8_t>(y);
      std::fill(c, c + cols, uint8_t(y1 - y0 + 1));
      for (int yy = y0; yy <= y1; ++yy) {
        const uint8_t* __restrict m = invalid.ptr<uint8_t>(yy);
        for (int x = 0; x < cols; ++x) c[x] = uint8_t(c[x] - m[x]);  // vectorises
      }
    }
  });
  // METHODS.md A1: only invalid centres, neighbours must be valid and of similar grey value.
  tracking_detail::parallel_rows(cv::Range(0, rows), [&](const cv::Range& range) {
    std::vector<float> window((2 * r + 1) * (2 * r + 1));
    for (int y = range.start; y < range.end; ++y) {
      const uint8_t* mrow = invalid.ptr<uint8_t>(y);
      const uint8_t* crow = column_valid.ptr<uint8_t>(y);
      float* orow = out.ptr<float>(y);
      const uint8_t* grow = gray.ptr<uint8_t>(y);
      const int y0 = std::max(0, y - r), y1 = std::min(rows - 1, y + r);
      for (int x = 0; x < cols; ++x) {
        if (!mrow[x]) continue;
        const int g0 = grow[x];
        const int x0 = std::max(0, x - r), x1 = std::min(cols - 1, x + r);
        int support = 0;
        for (int xx = x0; xx <= x1; ++xx) support += crow[xx];
        if (support < min_support) continue;
        int n = 0;
        for (int yy = y0; yy <= y1; ++yy) {
          const float* dn = clean.ptr<float>(yy);
          const uint8_t* gn = gray.ptr<uint8_t>(yy);
          for (int xx = x0; xx <= x1; ++xx) {
            const float dv = dn[xx];
            window[n] = dv;  // branch-free: kept when valid and of similar grey
            n += int(dv > 0.0f) & int(std::abs(int(gn[xx]) - g0) <= t_gray);
          }
        }
        if (n < min_support) continue;
        const auto mid = window.begin() + n / 2;
        std::nth_element(window.begin(), mid, window.begin() + n);
        orow[x] = *mid;
      }
    }
  });
  return out;
}

}  // namespace semap
