#pragma once
// Voxel types of the TSDF (METHODS.md B3) and the quantisers of its optional layers (A6).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "semap/core/labels.hpp"

namespace semap {

// ---- IEEE 754 binary16 (hand-rolled: no F16C instructions needed, round to nearest even) ----

inline uint16_t float_to_half(float value) {
  uint32_t x;
  std::memcpy(&x, &value, 4);
  const uint32_t sign = (x >> 16) & 0x8000u;
  uint32_t mantissa = x & 0x7fffffu;
  const int32_t exponent = static_cast<int32_t>((x >> 23) & 0xffu);
  if (exponent == 0xff) return static_cast<uint16_t>(sign | 0x7c00u | (mantissa ? 0x200u : 0u));
  const int32_t e = exponent - 127 + 15;
  if (e >= 0x1f) return static_cast<uint16_t>(sign | 0x7c00u);  // overflow -> inf
  if (e <= 0) {                                                  // subnormal half or zero
    if (e < -10) return static_cast<uint16_t>(sign);
    mantissa |= 0x800000u;
    const int shift = 14 - e;
    uint32_t h = mantissa >> shift;
    const uint32_t rest = mantissa & ((1u << shift) - 1u), halfway = 1u << (shift - 1);
    if (rest > halfway || (rest == halfway && (h & 1u))) ++h;
    return static_cast<uint16_t>(sign | h);
  }
  uint32_t h = sign | (static_cast<uint32_t>(e) << 10) | (mantissa >> 13);
  const uint32_t rest = mantissa & 0x1fffu;
  if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;  // a carry into the exponent is correct
  return static_cast<uint16_t>(h);
}

inline float half_to_float(uint16_t h) {
  const uint32_t sign = static_cast<uint32_t>(h & 0x8000u) << 16;
  const uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
  uint32_t x;
  if (exponent == 0) {
    const float f = static_cast<float>(mantissa) * (1.0f / 16777216.0f);  // m * 2^-24
    return sign ? -f : f;
  }
  if (exponent == 31) x = sign | 0x7f800000u | (mantissa << 13);
  else x = sign | ((exponent + 112u) << 23) | (mantissa << 13);
  float f;
  std::memcpy(&f, &x, 4);
  return f;
}

/// The same conversions by the compiler's _Float16: F16C instructions where the calling
/// function is built for them (the integrator's AVX2 path), library code elsewhere. Compilers
/// without _Float16 on this target (clang 14 on x86: the fuzz and sanitizer builds) use the
/// conversions above, which give the same bits (test_tsdf_core).
#ifdef __FLT16_MAX__
[[gnu::always_inline]] inline uint16_t native_float_to_half(float value) {
  const _Float16 h = static_cast<_Float16>(value);
  uint16_t bits;
  std::memcpy(&bits, &h, 2);
  return bits;
}
[[gnu::always_inline]] inline float native_half_to_float(uint16_t bits) {
  _Float16 h;
  std::memcpy(&h, &bits, 2);
  return static_cast<float>(h);
}
#else
[[gnu::always_inline]] inline uint16_t native_float_to_half(float value) { return float_to_half(value); }
[[gnu::always_inline]] inline float native_half_to_float(uint16_t bits) { return half_to_float(bits); }
#endif

// ---- core voxel (METHODS B3) ----

/// 4 bytes: fp16 signed distance (metres), u8 log-quantised weight (WeightQuantizer), u8 label.
struct TsdfVoxel {
  uint16_t sdf_half = 0;
  uint8_t weight_q = 0;  ///< 0 = never observed
  ClassId label = 0;     ///< compact label (B6 rule: weighted majority vote, see VoteQuantizer)

  float sdf() const { return half_to_float(sdf_half); }
  void set_sdf(float d) { sdf_half = float_to_half(d); }
  bool operator==(const TsdfVoxel&) const = default;
};
static_assert(sizeof(TsdfVoxel) == 4, "METHODS B3: one voxel = 4 bytes");

/// u8 weight on a log scale: W(q) = unit * (exp(q * L / 255) - 1), L = ln(1 + max / unit).
/// Relative step ~ L / 255 (4.5 % with the defaults), so weights from 1/z^2 at 5 m (0.04) to
/// grouped sums of hundreds keep their ratios. An increment smaller than half a step rounds away:
/// the weight then stops growing and the sdf keeps a running average (a soft W_max).
class WeightQuantizer {
 public:
  WeightQuantizer(double unit = 0.01, double max = 1000.0) : unit_(unit), max_(max) {
    scale_ = std::log1p(max / unit) / 255.0;
    for (int q = 0; q < 256; ++q) table_[q] = static_cast<float>(unit * std::expm1(q * scale_));
    table_[255] = static_cast<float>(max);
    // upper_[q]: the smallest weight that rounds to q + 1, i.e. round(log1p(w / unit) / scale)
    // without a logarithm per voxel update (it was 5 % of a TUM run's time).
    for (int q = 0; q < 255; ++q) upper_[q] = unit * std::expm1((q + 0.5) * scale_);
    upper_[255] = std::numeric_limits<double>::infinity();  // a power-of-two table for first_above
  }
  float decode(uint8_t q) const { return table_[q]; }
  uint8_t encode(float weight) const {
    if (!(weight > 0)) return 0;
    if (weight >= max_) return 255;
    return static_cast<uint8_t>(std::max(first_above(0, weight), 1));  // observed stays > 0
  }
  /// encode(weight), found by scanning upward from `from`: a voxel's new weight W + w (B6) is
  /// never below its old code, and once W is large it moves by 0-2 codes, where the scan ends
  /// after a comparison or two instead of the 8 unpredictable branches of the binary search.
  /// Any `from` gives encode's result (a weight below decode(from) takes the full search).
  uint8_t encode_from(float weight, uint8_t from) const {
    if (!(weight > 0)) return 0;
    if (weight >= max_) return 255;
    const double w = weight;
    if (from > 1 && w < upper_[from - 1]) return encode(weight);
    constexpr int kScanSteps = 4;  // then a binary search over the rest (first observations jump far)
    int q = from;
    for (const int last = std::min(q + kScanSteps, 255); q < last; ++q)
      if (upper_[q] > w) return static_cast<uint8_t>(std::max(q, 1));
    return static_cast<uint8_t>(first_above(q, weight));
  }
  double unit() const { return unit_; }
  double max() const { return max_; }

 private:
  /// The first q >= from with upper_[q] > w (upper_bound over upper_[from..255], 255 at most:
  /// upper_[255] is +inf), by binary lifting with selects: the same index as std::upper_bound
  /// without its data-dependent branches (a grouped ray's weight jumps far: the scan above
  /// fails and the search's 8 branches mispredicted).
  int first_above(int from, double w) const {
    int q = from - 1;  // upper_[q] <= w holds for q < from (the caller scanned them), or q = -1
    for (int step = 128; step >= 1; step >>= 1) {
      const int probe = q + step;
      q = (probe <= 255 && upper_[static_cast<size_t>(probe)] <= w) ? probe : q;
    }
    return q + 1;
  }

  double unit_, max_, scale_;
  std::array<float, 256> table_{};
  std::array<double, 256> upper_{};
};

// ---- Bayesian label layer (METHODS A6) ----

/// Up to kMaxTopK (class, probability) pairs describing one observation or one voxel's
/// distribution; the mass not listed, `rest_each`, is spread evenly over the other classes.
constexpr int kMaxTopK = 8;
constexpr int kNumRealClasses = kNumClasses - 1;  ///< ids 1..kNumClasses-1 (0 = unlabelled)

struct ClassDistribution {
  int count = 0;
  std::array<ClassId, kMaxTopK> classes{};
  std::array<float, kMaxTopK> probabilities{};
  float rest_each = 1.0f / kNumRealClasses;  ///< probability of every class not listed

  /// Likelihood of observing `label` with confidence c (METHODS A6 with a label-only segmenter):
  /// c if the true class is `label`, (1 - c) / m for every other true class. m = the number of
  /// classes a segmenter's errors spread over (its confusable classes); m = kNumRealClasses - 1
  /// is the uniform-error model. One observation multiplies the odds of `label` against any other
  /// class by r = c m / (1 - c): m small = errors concentrated = one frame is weak evidence.
  static ClassDistribution from_label(ClassId label, float confidence, int confusion_classes = kNumRealClasses - 1);
  /// The k most probable classes of a full per-class vector (index = class id, index 0 ignored).
  static ClassDistribution from_probabilities(const float* probs, int num_channels, int k);
};

/// Per voxel: k (class, q) byte pairs, q = round(-ln(p) / step) with p = min_probability at
/// q = 255; class 0 marks an empty slot. Sorted by probability, most probable first.
class BayesLayerCodec {
 public:
  BayesLayerCodec(int k = 4, double min_probability = 1e-3) : k_(k), min_p_(min_probability) {
    step_ = -std::log(min_probability) / 255.0;
    for (int q = 0; q < 256; ++q) table_[q] = static_cast<float>(std::exp(-q * step_));
    // lower_[q]: p above it rounds to q or less (q = round(-ln p / step)); decreasing in q.
    // A search replaces a logarithm per class per labelled voxel update.
    for (int q = 0; q < 255; ++q) lower_[q] = std::exp(-(q + 0.5) * step_);
    build_encode_buckets();
  }
  int k() const { return k_; }
  int bytes_per_voxel() const { return 2 * k_; }
  float decode(uint8_t q) const { return table_[q]; }
  uint8_t encode(float p) const {
    if (!(p > min_p_)) return 255;
    const double pd = p;
    // The float's top 16 bits (sign, exponent, 7 mantissa bits) pick a bucket of p values
    // narrower than one code step; the scan from its first code takes 1-2 comparisons
    // instead of a binary search's 8 (same first q with lower_[q] < p, see encode_search).
    uint32_t bits;
    std::memcpy(&bits, &p, 4);
    const uint32_t b = (bits >> 16) - bucket_base_;
    if (b >= bucket_start_.size()) return encode_search(pd);
    int q = bucket_start_[b];
    while (q < 255 && lower_[q] >= pd) ++q;
    return static_cast<uint8_t>(q);
  }
  /// encode by binary search (the reference of encode's buckets): the first q whose bound is below p (lower_ is decreasing; a tie rounds up, as lround does).
  uint8_t encode_search(double pd) const {
    const auto it = std::lower_bound(lower_.begin(), lower_.end(), pd, [](double bound, double x) { return bound >= x; });
    return static_cast<uint8_t>(it - lower_.begin());
  }
  /// Reads a voxel's stored distribution (empty voxel = uniform prior).
  ClassDistribution read(const uint8_t* voxel) const;
  /// Recursive Bayes (A6): posterior ∝ observation × prior over ALL classes (the unlisted mass
  /// of both is exact through rest_each), normalised, the top k kept and quantised.
  void update(uint8_t* voxel, const ClassDistribution& observation) const;
  /// Most probable class of a voxel (0 when never labelled).
  static ClassId argmax(const uint8_t* voxel) { return voxel[0]; }
  /// Posterior odds of the most probable class against the runner-up (a listed class or, when
  /// none is listed, any unlisted one); 0 when never labelled. With the label-only likelihood
  /// (ClassDistribution::from_label) every frame's vote multiplies these odds by r = c m/(1-c).
  float top_odds(const uint8_t* voxel) const {
    if (voxel[0] == 0) return 0.0f;
    const ClassDistribution d = read(voxel);
    const float second = d.count > 1 ? std::max(d.probabilities[1], d.rest_each) : d.rest_each;
    return second > 0 ? d.probabilities[0] / second : std::numeric_limits<float>::infinity();
  }
  /// Largest odds the floor lets a voxel reach (every other class at min_probability).
  double max_odds() const { return (1.0 - (kNumRealClasses - 1) * min_p_) / min_p_; }
  double min_probability() const { return min_p_; }

 private:
  /// bucket_start_[b]: the code of the largest float of bucket b (top 16 bits bucket_base_ + b),
  /// for the positive floats from min_probability to 2 (a posterior is at most ~1).
  void build_encode_buckets() {
    const float lo = static_cast<float>(min_p_), hi = 2.0f;
    uint32_t lo_bits, hi_bits;
    std::memcpy(&lo_bits, &lo, 4);
    std::memcpy(&hi_bits, &hi, 4);
    bucket_base_ = lo_bits >> 16;
    const uint32_t n = (hi_bits >> 16) - bucket_base_;
    if (!(min_p_ > 0) || n > (1u << 16)) return;  // no buckets: every encode searches
    bucket_start_.resize(n);
    for (uint32_t b = 0; b < n; ++b) {
      const uint32_t top_bits = ((bucket_base_ + b + 1) << 16) - 1;
      float top;
      std::memcpy(&top, &top_bits, 4);
      bucket_start_[b] = encode_search(top);
    }
  }

  int k_;
  double min_p_, step_;
  std::array<float, 256> table_{};
  std::array<double, 255> lower_{};
  uint32_t bucket_base_ = 0;
  std::vector<uint8_t> bucket_start_;
};

/// Compact label rule (METHODS B6 leaves it open): a Boyer-Moore majority vote with one vote
/// per voxel per frame (frames, not rays, vote: a close-up frame must not outvote many others).
/// The voxel keeps its label byte plus a 1-byte vote counter C (saturating at 255). Same label:
/// C += 1. Different label: C -= 1, and at C = 0 the next differing label replaces the stored
/// one. A label observed in more than half of the frames that saw the voxel ends up stored.
inline void compact_label_vote(ClassId& label, uint8_t& votes, ClassId observed) {
  if (observed == 0) return;
  if (votes == 0) {
    label = observed;
    votes = 1;
  } else if (label == observed) {
    if (votes < 255) ++votes;
  } else {
    --votes;
  }
}

}  // namespace semap
