#include "tracking/registration.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

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

std::vector<std::pair<int, int>> match_features(const FrameFeatures& query, const FrameFeatures& train,
                                                double ratio, int max_hamming) {
  std::vector<std::pair<int, int>> pairs;
  if (query.descriptors.rows < 2 || train.descriptors.rows < 2) return pairs;
  cv::BFMatcher matcher(cv::NORM_HAMMING, false);
  std::vector<std::vector<cv::DMatch>> forward;
  matcher.knnMatch(query.descriptors, train.descriptors, forward, 2);
  std::vector<cv::DMatch> backward;
  matcher.match(train.descriptors, query.descriptors, backward);
  std::vector<int> back_best(train.descriptors.rows, -1);
  for (const auto& m : backward) back_best[m.queryIdx] = m.trainIdx;
  for (const auto& knn : forward) {
    if (knn.empty()) continue;
    const cv::DMatch& m = knn[0];
    if (m.distance > max_hamming) continue;
    if (knn.size() > 1 && m.distance > ratio * knn[1].distance) continue;
    if (back_best[m.trainIdx] != m.queryIdx) continue;  // cross-check
    pairs.emplace_back(m.queryIdx, m.trainIdx);
  }
  return pairs;
}

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

cv::Mat vertices_from_depth(const cv::Mat& depth, const PinholeIntrinsics& k, double min_depth, double max_depth) {
  cv::Mat v(depth.size(), CV_32FC3);
  const float fx_inv = float(1.0 / k.fx), fy_inv = float(1.0 / k.fy);
  const float cx = float(k.cx), cy = float(k.cy);
  cv::parallel_for_(cv::Range(0, depth.rows), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const float* d = depth.ptr<float>(y);
      cv::Vec3f* out = v.ptr<cv::Vec3f>(y);
      for (int x = 0; x < depth.cols; ++x) {
        const float z = d[x];
        if (z >= min_depth && z <= max_depth) out[x] = cv::Vec3f((x - cx) * z * fx_inv, (y - cy) * z * fy_inv, z);
        else out[x] = cv::Vec3f(kNaN, kNaN, kNaN);
      }
    }
  });
  return v;
}

cv::Mat normals_from_vertices(const cv::Mat& v) {
  cv::Mat n(v.size(), CV_32FC3, cv::Scalar::all(kNaN));
  cv::parallel_for_(cv::Range(1, std::max(1, v.rows - 1)), [&](const cv::Range& range) {
    for (int y = range.start; y < range.end; ++y) {
      const cv::Vec3f* up = v.ptr<cv::Vec3f>(y - 1);
      const cv::Vec3f* mid = v.ptr<cv::Vec3f>(y);
      const cv::Vec3f* down = v.ptr<cv::Vec3f>(y + 1);
      cv::Vec3f* out = n.ptr<cv::Vec3f>(y);
      for (int x = 1; x < v.cols - 1; ++x) {
        const cv::Vec3f& c = mid[x];
        if (std::isnan(c[2])) continue;
        const cv::Vec3f dx = mid[x + 1] - mid[x - 1];
        const cv::Vec3f dy = down[x] - up[x];
        if (std::isnan(dx[2]) || std::isnan(dy[2])) continue;
        // Depth discontinuities give unreliable normals.
        const float limit = 0.05f * c[2];
        if (std::abs(dx[2]) > 2 * limit || std::abs(dy[2]) > 2 * limit) continue;
        cv::Vec3f nn = dy.cross(dx);
        const float len = float(cv::norm(nn));
        if (!(len > 0)) continue;
        nn /= len;
        if (nn.dot(c) > 0) nn = -nn;  // face the camera
        out[x] = nn;
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

std::vector<DepthLevel> build_depth_pyramid(const cv::Mat& depth, const PinholeIntrinsics& intrinsics, int levels,
                                            double min_depth, double max_depth, bool with_normals,
                                            const cv::Mat& gray) {
  std::vector<DepthLevel> pyramid;
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
    if (l > 0) {
      d = downsample_depth(d);
      if (!intensity.empty()) cv::resize(intensity, intensity, d.size(), 0, 0, cv::INTER_AREA);
      k = k.scaled(0.5);
      k.width = d.cols;
      k.height = d.rows;
    }
    DepthLevel level;
    level.intrinsics = k;
    level.vertices = vertices_from_depth(d, k, min_depth, max_depth);
    if (with_normals) level.normals = normals_from_vertices(level.vertices);
    if (!intensity.empty()) {
      level.intensity = intensity.clone();
      // Central differences (kernel [-0.5 0 0.5]): derivative per pixel.
      const cv::Mat kx = (cv::Mat_<float>(1, 3) << -0.5f, 0.0f, 0.5f);
      cv::filter2D(level.intensity, level.grad_x, CV_32F, kx, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
      cv::filter2D(level.intensity, level.grad_y, CV_32F, kx.t(), cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
    }
    pyramid.push_back(std::move(level));
  }
  return pyramid;
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

/// Bilinear sample of a CV_32FC1 image at (x, y); false outside the interpolation domain.
inline bool bilinear(const cv::Mat& img, float x, float y, float& out) {
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= img.cols || y0 + 1 >= img.rows) return false;
  const float ax = x - x0, ay = y - y0;
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(y0 + 1);
  out = (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x0 + 1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x0 + 1]);
  return true;
}

/// photo_bias: brightness offset of the target against the source (auto exposure), subtracted
/// from every intensity residual.
Accumulator accumulate(const DepthLevel& src, const DepthLevel& tgt, const Pose& t, int stride, double max_dist,
                       double min_normal_cos, double huber, const IcpParams& params, double photo_bias = 0.0) {
  const bool photometric = params.photometric_weight > 0 && !src.intensity.empty() && !tgt.intensity.empty();
  const float photo_max_dz = float(params.photometric_max_depth_difference);
  const double photo_huber = params.photometric_huber;
  constexpr int kStripes = 8;  // fixed stripes: summation order (and result) independent of thread count
  std::vector<Accumulator> parts(kStripes);
  const Eigen::Matrix3f r = t.linear().cast<float>();
  const Eigen::Vector3f tr = t.translation().cast<float>();
  const PinholeIntrinsics& k = tgt.intrinsics;
  const float max_sq = float(max_dist * max_dist);
  const int rows = src.vertices.rows;
  cv::parallel_for_(cv::Range(0, kStripes), [&](const cv::Range& range) {
    for (int s = range.start; s < range.end; ++s) {
      Accumulator& acc = parts[s];
      Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 6> hp = Eigen::Matrix<double, 6, 6>::Zero();
      const int y_begin = rows * s / kStripes, y_end = rows * (s + 1) / kStripes;
      for (int y = y_begin; y < y_end; ++y) {
        if (y % stride) continue;
        const cv::Vec3f* sv = src.vertices.ptr<cv::Vec3f>(y);
        // Normal gate against the target normal only from the source normal where the source
        // has smooth normals; Kinect normals from 1-pixel differences are too noisy at level 0.
        const cv::Vec3f* sn = (src.normals.empty() || src.vertices.cols >= 640) ? nullptr : src.normals.ptr<cv::Vec3f>(y);
        for (int x = 0; x < src.vertices.cols; x += stride) {
          const cv::Vec3f& v = sv[x];
          if (std::isnan(v[2])) continue;
          ++acc.valid;
          const Eigen::Vector3f p = r * Eigen::Vector3f(v[0], v[1], v[2]) + tr;
          if (p.z() <= 0) continue;
          const float uf = float(k.fx) * p.x() / p.z() + float(k.cx);
          const float vf = float(k.fy) * p.y() / p.z() + float(k.cy);
          const int u = int(std::lround(uf));
          const int w = int(std::lround(vf));
          if (u < 0 || w < 0 || u >= tgt.vertices.cols || w >= tgt.vertices.rows) continue;
          const cv::Vec3f& qv = tgt.vertices.at<cv::Vec3f>(w, u);
          if (photometric && !std::isnan(qv[2]) && std::abs(qv[2] - p.z()) < photo_max_dz) {
            // Photometric residual r = I_t(pi(p)) - I_s(x); dr/dp = grad I_t * dpi/dp.
            float it, gx, gy;
            if (bilinear(tgt.intensity, uf, vf, it) && bilinear(tgt.grad_x, uf, vf, gx) &&
                bilinear(tgt.grad_y, uf, vf, gy)) {
              const double res = double(it) - double(src.intensity.at<float>(y, x)) - photo_bias;
              const double iz = 1.0 / p.z();
              const double dfx = gx * k.fx * iz, dfy = gy * k.fy * iz;
              const Eigen::Vector3d gp(dfx, dfy, -(dfx * p.x() + dfy * p.y()) * iz);
              Eigen::Matrix<double, 6, 1> j;
              j.head<3>() = p.cast<double>().cross(gp);
              j.tail<3>() = gp;
              const double a = std::abs(res);
              const double weight = a <= photo_huber ? 1.0 : photo_huber / a;
              hp.selfadjointView<Eigen::Upper>().rankUpdate(j, weight);
              acc.g_photo += weight * res * j;
              acc.photo_weighted_sum += weight * res;
              acc.photo_weight_sum += weight;
              ++acc.photo_matched;
            }
          }
          const cv::Vec3f& nv = tgt.normals.at<cv::Vec3f>(w, u);
          if (std::isnan(qv[2]) || std::isnan(nv[2])) continue;
          const Eigen::Vector3f q(qv[0], qv[1], qv[2]), n(nv[0], nv[1], nv[2]);
          const Eigen::Vector3f diff = p - q;
          if (diff.squaredNorm() > max_sq) continue;
          // Normal gate: the source normal when available, else the viewing geometry is not
          // checked (noisy Kinect normals reject too many good pairs).
          if (sn) {
            const cv::Vec3f& snv = sn[x];
            if (!std::isnan(snv[2]) && (r * Eigen::Vector3f(snv[0], snv[1], snv[2])).dot(n) < min_normal_cos) continue;
          }
          const double res = n.dot(diff);
          Eigen::Matrix<double, 6, 1> j;
          j.head<3>() = p.cross(n).cast<double>();
          j.tail<3>() = n.cast<double>();
          const double a = std::abs(res);
          const double weight = a <= huber ? 1.0 : huber / a;
          h.selfadjointView<Eigen::Upper>().rankUpdate(j, weight);
          acc.g += weight * res * j;
          acc.sq_sum += res * res;
          ++acc.matched;
        }
      }
      acc.h = h.selfadjointView<Eigen::Upper>();
      acc.h_photo = hp.selfadjointView<Eigen::Upper>();
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
  for (int l = levels - 1; l >= 0 && !failed; --l) {
    const int iterations = params.iterations.empty() ? 0
                           : params.iterations[std::min<size_t>(l, params.iterations.size() - 1)];
    const int stride = std::max(1, params.stride >> l);
    const double max_dist = params.max_distance * std::pow(2.0, l);
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
      if (last_update < params.convergence_update) break;
    }
  }
  result.T_target_source = t;
  if (levels > 0) {
    const Accumulator final_acc = accumulate(source[0], target[0], t, params.stride, params.max_distance, min_cos,
                                             params.huber_delta, params, photo_bias);
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
