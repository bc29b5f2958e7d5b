#include "tracking/registration.hpp"

#include "tracking/parallel.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace semap {

Pose fit_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst, bool* ok) {
  if (ok) *ok = false;
  const size_t n = std::min(src.size(), dst.size());
  if (n < 3) return Pose::Identity();
  Eigen::Vector3d cs = Eigen::Vector3d::Zero(), cd = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    cs += src[i];
    cd += dst[i];
  }
  cs /= double(n);
  cd /= double(n);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i) h += (src[i] - cs) * (dst[i] - cd).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d sv = svd.singularValues();
  // Collinear / coincident samples leave the rotation about the line undetermined.
  if (!(sv(1) > 1e-9 * std::max(1.0, sv(0)))) return Pose::Identity();
  const Eigen::Matrix3d u = svd.matrixU(), v = svd.matrixV();
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (v * u.transpose()).determinant() < 0 ? -1.0 : 1.0;  // no reflections
  Pose t = Pose::Identity();
  t.linear() = v * d * u.transpose();
  t.translation() = cd - t.linear() * cs;
  if (ok) *ok = t.matrix().allFinite();
  return t;
}

namespace {
std::vector<int> count_inliers(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                               const Pose& t, double max_dist, double* rmse) {
  std::vector<int> inliers;
  const double max_sq = max_dist * max_dist;
  double sum = 0.0;
  for (size_t i = 0; i < src.size(); ++i) {
    const double e = (t * src[i] - dst[i]).squaredNorm();
    if (e < max_sq) {
      inliers.push_back(int(i));
      sum += e;
    }
  }
  if (rmse) *rmse = inliers.empty() ? 0.0 : std::sqrt(sum / inliers.size());
  return inliers;
}
}  // namespace

RansacResult ransac_rigid(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                          const RansacParams& params) {
  RansacResult best;
  const int n = int(std::min(src.size(), dst.size()));
  if (n < 3) return best;
  std::mt19937 rng(params.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  const double max_sq = params.inlier_distance * params.inlier_distance;
  int best_votes = 0;
  Pose best_t = Pose::Identity();
  std::vector<Eigen::Vector3d> s3(3), d3(3);
  for (int it = 0; it < params.iterations; ++it) {
    int a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || a == c || b == c) continue;
    // Rigid transforms preserve distances: cheap pre-check rejects most wrong samples.
    const int idx[3] = {a, b, c};
    bool consistent = true;
    for (int i = 0; i < 3 && consistent; ++i) {
      const int p = idx[i], q = idx[(i + 1) % 3];
      const double ds = (src[p] - src[q]).norm(), dd = (dst[p] - dst[q]).norm();
      consistent = std::abs(ds - dd) < 2.0 * params.inlier_distance;
    }
    if (!consistent) continue;
    for (int i = 0; i < 3; ++i) {
      s3[i] = src[idx[i]];
      d3[i] = dst[idx[i]];
    }
    bool ok = false;
    const Pose t = fit_rigid(s3, d3, &ok);
    if (!ok) continue;
    int votes = 0;
    for (int i = 0; i < n; ++i) votes += (t * src[i] - dst[i]).squaredNorm() < max_sq;
    if (votes >= params.min_inliers) best.hypotheses.emplace_back(votes, t);
    if (votes > best_votes) {
      best_votes = votes;
      best_t = t;
    }
  }
  if (best_votes < 3) return best;
  // Refit on all inliers (twice: the refit can gain a few more votes).
  Pose t = best_t;
  std::vector<int> inliers = count_inliers(src, dst, t, params.inlier_distance, nullptr);
  for (int round = 0; round < 2; ++round) {
    std::vector<Eigen::Vector3d> s, d;
    for (int i : inliers) {
      s.push_back(src[i]);
      d.push_back(dst[i]);
    }
    bool ok = false;
    const Pose refit = fit_rigid(s, d, &ok);
    if (!ok) break;
    std::vector<int> again = count_inliers(src, dst, refit, params.inlier_distance, nullptr);
    if (again.size() < inliers.size()) break;
    t = refit;
    inliers = std::move(again);
  }
  best.T = t;
  best.best_votes = best_votes;
  best.inliers = count_inliers(src, dst, t, params.inlier_distance, &best.inlier_rmse);
  best.ok = int(best.inliers.size()) >= params.min_inliers;
  return best;
}

FrameFeatures extract_features(cv::ORB& orb, const cv::Mat& gray, const cv::Mat& depth,
                               const PinholeIntrinsics& intrinsics, double min_depth, double max_depth) {
  FrameFeatures out;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb.detectAndCompute(gray, cv::noArray(), keypoints, descriptors);
  out.descriptors.create(0, descriptors.cols, descriptors.type());
  std::vector<int> keep;
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const int u = int(std::lround(keypoints[i].pt.x)), v = int(std::lround(keypoints[i].pt.y));
    if (u < 0 || v < 0 || u >= depth.cols || v >= depth.rows) continue;
    const float z = depth.at<float>(v, u);
    if (!(z >= min_depth && z <= max_depth)) continue;
    keep.push_back(int(i));
    out.keypoints.push_back(keypoints[i]);
    out.points.push_back(intrinsics.backproject(keypoints[i].pt.x, keypoints[i].pt.y, z));
  }
  if (!keep.empty()) {
    out.descriptors.create(int(keep.size()), descriptors.cols, descriptors.type());
    for (size_t r = 0; r < keep.size(); ++r) descriptors.row(keep[r]).copyTo(out.descriptors.row(int(r)));
  }
  return out;
}

namespace {
/// Hamming distance of two descriptors of `bytes` bytes (8-byte words, then the tail).
template <bool kPopcnt>  // separate instantiation for the popcnt-targeted caller
inline int hamming(const uint8_t* a, const uint8_t* b, int words, int bytes) {
  int d = 0;
  for (int w = 0; w < words; ++w) {
    uint64_t x, y;
    std::memcpy(&x, a + 8 * w, 8);
    std::memcpy(&y, b + 8 * w, 8);
    d += __builtin_popcountll(x ^ y);
  }
  for (int i = 8 * words; i < bytes; ++i) d += __builtin_popcount(unsigned(a[i] ^ b[i]));
  return d;
}

/// One pass over the query x train distance matrix: best and second best train per query row,
/// best query per train column (ties: the lower index, as cv::BFMatcher).
template <bool kPopcnt>  // separate instantiation for the popcnt-targeted caller
void hamming_scan(const cv::Mat& q, const cv::Mat& t, std::vector<int>& best_t, std::vector<int>& d1,
                  std::vector<int>& d2, std::vector<int>& best_q, std::vector<int>& col_d) {
  const int bytes = q.cols, words = bytes / 8;
  for (int i = 0; i < q.rows; ++i) {
    const uint8_t* a = q.ptr<uint8_t>(i);
    int b1 = std::numeric_limits<int>::max(), b2 = b1, bi = -1;
    for (int j = 0; j < t.rows; ++j) {
      const int d = hamming<kPopcnt>(a, t.ptr<uint8_t>(j), words, bytes);
      if (d < b1) {
        b2 = b1;
        b1 = d;
        bi = j;
      } else if (d < b2) {
        b2 = d;
      }
      if (d < col_d[j]) {
        col_d[j] = d;
        best_q[j] = i;
      }
    }
    best_t[i] = bi;
    d1[i] = b1;
    d2[i] = b2;
  }
}
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
__attribute__((target("popcnt"), flatten)) void hamming_scan_popcnt(const cv::Mat& q, const cv::Mat& t, std::vector<int>& best_t,
                                                           std::vector<int>& d1, std::vector<int>& d2,
                                                           std::vector<int>& best_q, std::vector<int>& col_d) {
  hamming_scan<true>(q, t, best_t, d1, d2, best_q, col_d);
}
bool cpu_has_popcnt() {
  static const bool has = __builtin_cpu_supports("popcnt");
  return has;
}
#else
void hamming_scan_popcnt(const cv::Mat& q, const cv::Mat& t, std::vector<int>& best_t, std::vector<int>& d1,
                         std::vector<int>& d2, std::vector<int>& best_q, std::vector<int>& col_d) {
  hamming_scan<false>(q, t, best_t, d1, d2, best_q, col_d);
}
bool cpu_has_popcnt() { return true; }
#endif
}  // namespace

std::vector<std::pair<int, int>> match_features(const FrameFeatures& query, const FrameFeatures& train,
                                                double ratio, int max_hamming) {
  std::vector<std::pair<int, int>> pairs;
  if (query.descriptors.rows < 2 || train.descriptors.rows < 2) return pairs;
  CV_Assert(query.descriptors.type() == CV_8U && train.descriptors.type() == CV_8U &&
            query.descriptors.cols == train.descriptors.cols && query.descriptors.isContinuous() &&
            train.descriptors.isContinuous());
  // Forward 2-NN (ratio test) and backward 1-NN (cross-check) from one scan of the distance
  // matrix instead of two matcher passes (METHODS.md A2 step 1).
  const int nq = query.descriptors.rows, nt = train.descriptors.rows;
  std::vector<int> best_t(nq), d1(nq), d2(nq), best_q(nt, -1), col_d(nt, std::numeric_limits<int>::max());
  if (cpu_has_popcnt()) hamming_scan_popcnt(query.descriptors, train.descriptors, best_t, d1, d2, best_q, col_d);
  else hamming_scan<false>(query.descriptors, train.descriptors, best_t, d1, d2, best_q, col_d);
  for (int i = 0; i < nq; ++i) {
    if (best_t[i] < 0 || d1[i] > max_hamming) continue;
    if (double(d1[i]) > ratio * double(d2[i])) continue;
    if (best_q[best_t[i]] != i) continue;  // cross-check
    pairs.emplace_back(i, best_t[i]);
  }
  return pairs;
}

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

cv::Mat vertices_from_depth(const cv::Mat& depth, const PinholeIntrinsics& k, double min_depth, double max_depth) {
  cv::Mat v(depth.size(), CV_32FC3);
  const float fx_inv = float(1.0 / k.fx), fy_inv = float(1.0 / k.fy);
  const float cx = float(k.cx), cy = float(k.cy);
  tracking_detail::parallel_rows(cv::Range(0, depth.rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const float* d = depth.ptr<float>(y);
      float* out = v.ptr<float>(y);
      const float ry = (y - cy) * fy_inv;
      for (int x = 0; x < depth.cols; ++x, out += 3) {
        const float z = d[x];
        if (z >= min_depth && z <= max_depth) {
          out[0] = (x - cx) * z * fx_inv;
          out[1] = ry * z;
          out[2] = z;
        } else {
          out[0] = out[1] = out[2] = kNaN;
        }
      }
    }
  });
  return v;
}

cv::Mat normals_from_vertices(const cv::Mat& v) {
  cv::Mat n(v.size(), CV_32FC3);
  const int rows = v.rows, cols = v.cols;
  tracking_detail::parallel_rows(cv::Range(0, rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      float* out = n.ptr<float>(y);
      std::fill(out, out + 3 * cols, kNaN);
      if (y == 0 || y == rows - 1) continue;
      const float* up = v.ptr<float>(y - 1);
      const float* mid = v.ptr<float>(y);
      const float* down = v.ptr<float>(y + 1);
      for (int x = 1; x < cols - 1; ++x) {
        const float* c = mid + 3 * x;
        if (std::isnan(c[2])) continue;
        const float* l = mid + 3 * (x - 1);
        const float* r = mid + 3 * (x + 1);
        const float* u = up + 3 * x;
        const float* d = down + 3 * x;
        const float dx0 = r[0] - l[0], dx1 = r[1] - l[1], dx2 = r[2] - l[2];
        const float dy0 = d[0] - u[0], dy1 = d[1] - u[1], dy2 = d[2] - u[2];
        if (std::isnan(dx2) || std::isnan(dy2)) continue;
        // Depth discontinuities give unreliable normals.
        const float limit = 0.05f * c[2];
        if (std::abs(dx2) > 2 * limit || std::abs(dy2) > 2 * limit) continue;
        float n0 = dy1 * dx2 - dy2 * dx1, n1 = dy2 * dx0 - dy0 * dx2, n2 = dy0 * dx1 - dy1 * dx0;  // dy x dx
        const float len = std::sqrt(n0 * n0 + n1 * n1 + n2 * n2);
        if (!(len > 0)) continue;
        float inv = 1.0f / len;
        if (n0 * c[0] + n1 * c[1] + n2 * c[2] > 0) inv = -inv;  // face the camera
        float* o = out + 3 * x;
        o[0] = n0 * inv;
        o[1] = n1 * inv;
        o[2] = n2 * inv;
      }
    }
  });
  return n;
}

cv::Mat downsample_depth(const cv::Mat& depth) {
  cv::Mat out(depth.rows / 2, depth.cols / 2, CV_32FC1);
  for (int y = 0; y < out.rows; ++y) {
    const float* r0 = depth.ptr<float>(2 * y);
    const float* r1 = depth.ptr<float>(2 * y + 1);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x) {
      const float v[4] = {r0[2 * x], r0[2 * x + 1], r1[2 * x], r1[2 * x + 1]};
      float ref = 0, sum = 0;
      int count = 0;
      for (float d : v) {
        if (!(d > 0)) continue;
        if (count == 0) ref = d;
        if (std::abs(d - ref) > 0.03f * ref) continue;  // do not average across edges
        sum += d;
        ++count;
      }
      o[x] = count ? sum / count : 0.0f;
    }
  }
  return out;
}
}  // namespace

namespace {
/// (I, dI/dx, dI/dy) with central differences, replicated border (derivative per pixel).
cv::Mat intensity_with_gradients(const cv::Mat& intensity) {
  const int rows = intensity.rows, cols = intensity.cols;
  cv::Mat out(intensity.size(), CV_32FC3);
  for (int y = 0; y < rows; ++y) {
    const float* up = intensity.ptr<float>(std::max(0, y - 1));
    const float* mid = intensity.ptr<float>(y);
    const float* down = intensity.ptr<float>(std::min(rows - 1, y + 1));
    float* o = out.ptr<float>(y);
    for (int x = 0; x < cols; ++x, o += 3) {
      const int xl = x > 0 ? x - 1 : 0, xr = x + 1 < cols ? x + 1 : cols - 1;
      o[0] = mid[x];
      o[1] = 0.5f * (mid[xr] - mid[xl]);
      o[2] = 0.5f * (down[x] - up[x]);
    }
  }
  return out;
}
}  // namespace

std::vector<DepthLevel> build_depth_pyramid(const cv::Mat& depth, const PinholeIntrinsics& intrinsics, int levels,
                                            double min_depth, double max_depth, bool with_normals,
                                            const cv::Mat& gray, bool source_only) {
  std::vector<DepthLevel> pyramid;
  pyramid.reserve(levels);
  cv::Mat d = depth;
  cv::Mat intensity;
  if (!gray.empty()) {
    gray.convertTo(intensity, CV_32F, 1.0 / 255.0);
    if (intensity.size() != depth.size()) cv::resize(intensity, intensity, depth.size(), 0, 0, cv::INTER_AREA);
    cv::GaussianBlur(intensity, intensity, cv::Size(5, 5), 1.0);
  }
  PinholeIntrinsics k = intrinsics;
  k.width = depth.cols;
  k.height = depth.rows;
  for (int l = 0; l < levels; ++l) {
    DepthLevel level;
    if (l > 0) {
      d = downsample_depth(d);
      if (!intensity.empty()) cv::resize(intensity, level.intensity, d.size(), 0, 0, cv::INTER_AREA);
      k = k.scaled(0.5);
      k.width = d.cols;
      k.height = d.rows;
    } else {
      level.intensity = intensity;
    }
    level.intrinsics = k;
    level.vertices = vertices_from_depth(d, k, min_depth, max_depth);
    if (with_normals && (!source_only || icp_uses_source_normals(level))) level.normals = normals_from_vertices(level.vertices);
    if (!level.intensity.empty() && !source_only) level.intensity_gradients = intensity_with_gradients(level.intensity);
    intensity = level.intensity;
    pyramid.push_back(std::move(level));
  }
  return pyramid;
}

void complete_target_pyramid(std::vector<DepthLevel>& pyramid, bool with_normals) {
  for (auto& level : pyramid) {
    if (with_normals && level.normals.empty()) level.normals = normals_from_vertices(level.vertices);
    if (!level.intensity.empty() && level.intensity_gradients.empty())
      level.intensity_gradients = intensity_with_gradients(level.intensity);
  }
}

Pose twist_exp(const Vector6d& xi) {
  Pose t = Pose::Identity();
  const Eigen::Vector3d w = xi.head<3>();
  const double angle = w.norm();
  if (angle > 1e-12) t.linear() = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  t.translation() = xi.tail<3>();
  return t;
}

namespace {
struct Accumulator {
  Matrix6d h = Matrix6d::Zero();  ///< geometric part
  Vector6d g = Vector6d::Zero();
  Matrix6d h_photo = Matrix6d::Zero();  ///< photometric part (unscaled by its weight)
  Vector6d g_photo = Vector6d::Zero();
  double sq_sum = 0.0;  ///< unweighted squared point-to-plane residuals
  int matched = 0;
  int photo_matched = 0;
  double photo_weighted_sum = 0.0;  ///< sum of Huber weight * intensity residual
  double photo_weight_sum = 0.0;    ///< sum of Huber weights
  int valid = 0;
};

/// Weighted sums of v v^T for v = (J, r, 1): J^T W J, J^T W r, sum w r^2, sum w r, sum w.
/// Float per image row (8x8, vectorises), flushed into double per row: ~5x fewer instructions
/// than a scalar double rank-1 update per point.
struct RowSums {
  alignas(32) float m[8][8];
  RowSums() { clear(); }
  void clear() { std::fill(&m[0][0], &m[0][0] + 64, 0.0f); }
  inline void add(const float v[8], float w) {
#if defined(__SSE2__)
    const __m128 lo = _mm_loadu_ps(v), hi = _mm_loadu_ps(v + 4);
    for (int a = 0; a < 8; ++a) {  // rows 4..7: only the upper half (columns 4..7) is read
      const __m128 wa = _mm_set1_ps(w * v[a]);
      if (a < 4) _mm_store_ps(m[a], _mm_add_ps(_mm_load_ps(m[a]), _mm_mul_ps(wa, lo)));
      _mm_store_ps(m[a] + 4, _mm_add_ps(_mm_load_ps(m[a] + 4), _mm_mul_ps(wa, hi)));
    }
#else
    for (int a = 0; a < 8; ++a) {
      const float wa = w * v[a];
      for (int b = 0; b < 8; ++b) m[a][b] += wa * v[b];
    }
#endif
  }
};
struct NormalEquations {
  Matrix6d h = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  double weighted_residual_sum = 0.0, weight_sum = 0.0;
  void flush(RowSums& row) {
    for (int a = 0; a < 6; ++a) {
      for (int b = a; b < 6; ++b) h(a, b) += row.m[a][b];  // upper triangle
      g(a) += row.m[a][6];
    }
    for (int a = 0; a < 6; ++a)
      for (int b = 0; b < a; ++b) h(a, b) = h(b, a);
    weighted_residual_sum += row.m[6][7];
    weight_sum += row.m[7][7];
    row.clear();
  }
};

/// Bilinear sample of the packed (I, gx, gy) image at (x, y); false outside the interpolation
/// domain.
inline bool bilinear3(const cv::Mat& img, float x, float y, float out[3]) {
  if (!(x >= 0.0f && y >= 0.0f)) return false;
  const int x0 = int(x), y0 = int(y);
  if (x0 + 1 >= img.cols || y0 + 1 >= img.rows) return false;
  const float ax = x - x0, ay = y - y0;
  const float w00 = (1 - ax) * (1 - ay), w01 = ax * (1 - ay), w10 = (1 - ax) * ay, w11 = ax * ay;
  const float* r0 = img.ptr<float>(y0) + 3 * x0;
  const float* r1 = img.ptr<float>(y0 + 1) + 3 * x0;
  for (int c = 0; c < 3; ++c) out[c] = w00 * r0[c] + w01 * r0[3 + c] + w10 * r1[c] + w11 * r1[3 + c];
  return true;
}

/// photo_bias: brightness offset of the target against the source (auto exposure), subtracted
/// from every intensity residual.
Accumulator accumulate(const DepthLevel& src, const DepthLevel& tgt, const Pose& t, int stride, double max_dist,
                       double min_normal_cos, double huber, const IcpParams& params, double photo_bias = 0.0) {
  const bool photometric = params.photometric_weight > 0 && !src.intensity.empty() && !tgt.intensity.empty();
  if (photometric) CV_Assert(!tgt.intensity_gradients.empty());  // target pyramid must be complete
  const float photo_max_dz = float(params.photometric_max_depth_difference);
  const float photo_huber = float(params.photometric_huber);
  const float photo_bias_f = float(photo_bias);
  const float huber_f = float(huber);
  constexpr int kStripes = 8;  // fixed stripes: summation order (and result) independent of thread count
  std::vector<Accumulator> parts(kStripes);
  const Eigen::Matrix3f r = t.linear().cast<float>();
  const Eigen::Vector3f tr = t.translation().cast<float>();
  const PinholeIntrinsics& k = tgt.intrinsics;
  const float fx = float(k.fx), fy = float(k.fy), cx = float(k.cx), cy = float(k.cy);
  const float max_sq = float(max_dist * max_dist);
  const int rows = src.vertices.rows, cols = src.vertices.cols;
  const int tcols = tgt.vertices.cols, trows = tgt.vertices.rows;
  // Normal gate against the target normal only from the source normal where the source has
  // smooth normals; Kinect normals from 1-pixel differences are too noisy at level 0.
  const bool gate = !src.normals.empty() && icp_uses_source_normals(src);
  tracking_detail::parallel_rows(cv::Range(0, kStripes), [&](const cv::Range& range) {
    for (int s = range.start; s < range.end; ++s) {
      Accumulator& acc = parts[s];
      NormalEquations geo, photo;
      RowSums geo_row, photo_row;
      const int y_begin = rows * s / kStripes, y_end = rows * (s + 1) / kStripes;
      for (int y = (y_begin + stride - 1) / stride * stride; y < y_end; y += stride) {
        const cv::Vec3f* sv = src.vertices.ptr<cv::Vec3f>(y);
        const cv::Vec3f* sn = gate ? src.normals.ptr<cv::Vec3f>(y) : nullptr;
        const float* si = photometric ? src.intensity.ptr<float>(y) : nullptr;
        for (int x = 0; x < cols; x += stride) {
          const cv::Vec3f& v = sv[x];
          if (std::isnan(v[2])) continue;
          ++acc.valid;
          const Eigen::Vector3f p = r * Eigen::Vector3f(v[0], v[1], v[2]) + tr;
          if (!(p.z() > 0)) continue;
          const float iz = 1.0f / p.z();
          const float uf = fx * p.x() * iz + cx;
          const float vf = fy * p.y() * iz + cy;
          if (!(uf > -0.5f && vf > -0.5f)) continue;  // also rejects NaN
          const int u = int(uf + 0.5f), w = int(vf + 0.5f);  // nearest pixel
          if (u >= tcols || w >= trows) continue;
          const cv::Vec3f& qv = tgt.vertices.ptr<cv::Vec3f>(w)[u];
          if (std::isnan(qv[2])) continue;
          if (photometric && std::abs(qv[2] - p.z()) < photo_max_dz) {
            // Photometric residual r = I_t(pi(p)) - I_s(x); dr/dp = grad I_t * dpi/dp.
            float ig[3];
            if (bilinear3(tgt.intensity_gradients, uf, vf, ig)) {
              const float res = ig[0] - si[x] - photo_bias_f;
              const float dfx = ig[1] * fx * iz, dfy = ig[2] * fy * iz;
              const float gz = -(dfx * p.x() + dfy * p.y()) * iz;
              const float px = p.x(), py = p.y(), pz = p.z();
              const float j[8] = {py * gz - pz * dfy, pz * dfx - px * gz, px * dfy - py * dfx, dfx, dfy, gz, res, 1.0f};
              const float a = std::abs(res);
              photo_row.add(j, a <= photo_huber ? 1.0f : photo_huber / a);
              ++acc.photo_matched;
            }
          }
          const cv::Vec3f& nv = tgt.normals.ptr<cv::Vec3f>(w)[u];
          if (std::isnan(nv[2])) continue;
          const Eigen::Vector3f q(qv[0], qv[1], qv[2]), n(nv[0], nv[1], nv[2]);
          const Eigen::Vector3f diff = p - q;
          if (diff.squaredNorm() > max_sq) continue;
          // Normal gate: the source normal when available, else the viewing geometry is not
          // checked (noisy Kinect normals reject too many good pairs).
          if (sn) {
            const cv::Vec3f& snv = sn[x];
            if (!std::isnan(snv[2]) && (r * Eigen::Vector3f(snv[0], snv[1], snv[2])).dot(n) < min_normal_cos) continue;
          }
          const float res = n.dot(diff);
          const Eigen::Vector3f pxn = p.cross(n);
          const float j[8] = {pxn.x(), pxn.y(), pxn.z(), n.x(), n.y(), n.z(), res, 1.0f};
          const float a = std::abs(res);
          geo_row.add(j, a <= huber_f ? 1.0f : huber_f / a);
          acc.sq_sum += double(res) * res;
          ++acc.matched;
        }
        geo.flush(geo_row);
        if (photometric) photo.flush(photo_row);
      }
      acc.h = geo.h;
      acc.g = geo.g;
      acc.h_photo = photo.h;
      acc.g_photo = photo.g;
      acc.photo_weighted_sum = photo.weighted_residual_sum;
      acc.photo_weight_sum = photo.weight_sum;
    }
  });
  Accumulator total;
  for (const auto& p : parts) {
    total.h += p.h;
    total.g += p.g;
    total.h_photo += p.h_photo;
    total.g_photo += p.g_photo;
    total.photo_matched += p.photo_matched;
    total.photo_weighted_sum += p.photo_weighted_sum;
    total.photo_weight_sum += p.photo_weight_sum;
    total.sq_sum += p.sq_sum;
    total.matched += p.matched;
    total.valid += p.valid;
  }
  return total;
}
}  // namespace

IcpResult icp_point_to_plane(const std::vector<DepthLevel>& source, const std::vector<DepthLevel>& target,
                             const Pose& initial_T_target_source, const IcpParams& params) {
  IcpResult result;
  Pose t = initial_T_target_source;
  const int levels = int(std::min(source.size(), target.size()));
  const double min_cos = std::cos(params.max_normal_angle_deg * M_PI / 180.0);
  double last_update = 0.0;
  double photo_bias = 0.0;
  bool failed = levels == 0;
  Accumulator last_fine;          // last level-0 system, for the final statistics
  bool fine_converged = false;    // level 0 ended on a negligible update
  for (int l = levels - 1; l >= 0 && !failed; --l) {
    const int iterations = params.iterations_at(l);
    const int stride = l == 0 ? std::max(1, params.stride) : std::max({1, params.min_stride, params.stride >> l});
    const double max_dist = params.max_distance * std::pow(2.0, l);
    // Coarser pixels resolve the pose more coarsely: the stop threshold grows per level.
    const double stop_update = params.convergence_update * std::pow(params.convergence_level_scale, l);
    for (int it = 0; it < iterations; ++it) {
      const Accumulator acc =
          accumulate(source[l], target[l], t, stride, max_dist, min_cos, params.huber_delta, params, photo_bias);
      // Brightness offset (auto exposure) re-estimated by alternation: robust mean residual.
      if (params.photometric_bias && acc.photo_weight_sum > 0) photo_bias += acc.photo_weighted_sum / acc.photo_weight_sum;
      if (acc.matched < 30) {
        failed = true;
        break;
      }
      // Joint cost: geometric + weighted photometric (both Huber-weighted Gauss-Newton).
      Matrix6d h = acc.h + params.photometric_weight * acc.h_photo;
      const Vector6d g = acc.g + params.photometric_weight * acc.g_photo;
      // Tiny damping keeps degenerate directions (planar scenes) from exploding.
      h.diagonal().array() += 1e-6 * h.diagonal().maxCoeff();
      const Vector6d xi = h.ldlt().solve(-g);
      if (!xi.allFinite()) {
        failed = true;
        break;
      }
      t = orthonormalized(twist_exp(xi) * t);
      last_update = xi.norm();
      ++result.iterations_run;
      if (last_update < stop_update) {
        if (l == 0) {
          last_fine = acc;
          fine_converged = true;
        }
        break;
      }
    }
  }
  result.T_target_source = t;
  if (levels > 0) {
    // Converged at level 0: the last system was built at a pose within convergence_update of
    // the result, reuse it instead of one more pass (METHODS.md A2 step 4).
    const Accumulator final_acc = fine_converged && !failed
                                      ? last_fine
                                      : accumulate(source[0], target[0], t, std::max(1, params.stride),
                                                   params.max_distance, min_cos, params.huber_delta, params, photo_bias);
    result.matched = final_acc.matched;
    result.photometric_matched = final_acc.photo_matched;
    result.overlap = final_acc.valid ? double(final_acc.matched) / final_acc.valid : 0.0;
    result.rmse = final_acc.matched ? std::sqrt(final_acc.sq_sum / final_acc.matched) : 0.0;
    result.hessian = final_acc.h;
    if (final_acc.matched < 30) failed = true;
  }
  result.converged = !failed && last_update < params.converged_update;
  return result;
}

}  // namespace semap
