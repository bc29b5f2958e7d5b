// Unit tests of the TSDF building blocks: voxel layout, half floats, weight quantisation,
// B5 grouping, the compact label vote and the A6 Bayesian update, the block hash table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <unordered_map>

#include "tsdf/integrator.hpp"
#include "semap/tsdf/tsdf_map.hpp"
#include "semap/tsdf/voxel.hpp"

namespace semap {
namespace {

TEST(TsdfVoxel, IsFourBytes) {
  static_assert(sizeof(TsdfVoxel) == 4);
  EXPECT_EQ(sizeof(TsdfVoxel), 4u);
}

TEST(HalfFloat, RoundTripsEveryHalf) {
  for (uint32_t h = 0; h < 65536; ++h) {
    const uint16_t bits = static_cast<uint16_t>(h);
    const float f = half_to_float(bits);
    if (std::isnan(f)) {
      EXPECT_TRUE(std::isnan(half_to_float(float_to_half(f))));
      continue;
    }
    EXPECT_EQ(float_to_half(f), bits) << h;
  }
}

// The integrator's AVX2 path converts with F16C (native_*): both must give the hand-rolled
// values, for every half and for floats across the whole range (every 4099th bit pattern).
TEST(HalfFloat, NativeConversionsEqualHandRolled) {
  int mismatches = 0;
  for (uint32_t h = 0; h < 65536; ++h) {
    const float a = half_to_float(static_cast<uint16_t>(h)), b = native_half_to_float(static_cast<uint16_t>(h));
    mismatches += !(std::isnan(a) ? std::isnan(b) : std::memcmp(&a, &b, 4) == 0);
  }
  for (uint64_t bits = 0; bits < (1ULL << 32); bits += 4099) {
    float f;
    const uint32_t b32 = static_cast<uint32_t>(bits);
    std::memcpy(&f, &b32, 4);
    if (!std::isnan(f)) mismatches += float_to_half(f) != native_float_to_half(f);
  }
  EXPECT_EQ(mismatches, 0);
}

TEST(HalfFloat, AccurateToHalfAnUlp) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> dist(-0.5f, 0.5f);
  for (int i = 0; i < 200000; ++i) {
    const float f = dist(rng);
    const float back = half_to_float(float_to_half(f));
    // binary16 has 11 significant bits: relative error <= 2^-11 for normal numbers.
    EXPECT_LE(std::fabs(back - f), std::max(std::fabs(f) * 0x1p-11f, 0x1p-25f)) << f;
#if defined(__FLT16_MAX__)
    EXPECT_EQ(back, static_cast<float>(static_cast<_Float16>(f))) << f;
#endif
  }
  EXPECT_TRUE(std::isinf(half_to_float(float_to_half(1e6f))));
}

TEST(WeightQuantizer, MonotoneLogScale) {
  const WeightQuantizer q(0.01, 1000.0);
  EXPECT_EQ(q.encode(0.0f), 0);
  EXPECT_EQ(q.decode(0), 0.0f);
  EXPECT_FLOAT_EQ(q.decode(255), 1000.0f);
  for (int i = 1; i < 256; ++i) EXPECT_GT(q.decode(i), q.decode(i - 1));
  for (float w : {0.02f, 0.1f, 1.0f, 7.0f, 55.0f, 300.0f}) {
    EXPECT_NEAR(q.decode(q.encode(w)), w, 0.03f * w) << w;  // < half a 4.5 % step
  }
  EXPECT_EQ(q.encode(1e9f), 255);
  EXPECT_GE(q.encode(1e-9f), 1);  // observed stays observed
}

// BayesLayerCodec::encode starts from a bucket of the float's top bits; over the floats from
// the floor to 2 (every 97th bit pattern) it must give the binary search's code.
TEST(Quantizers, BucketedBayesEncodeEqualsSearch) {
  for (const double min_p : {1e-5, 1e-3, 0.05}) {
    const BayesLayerCodec codec(4, min_p);
    int mismatches = 0;
    const float lo = static_cast<float>(min_p) * 0.5f, hi = 2.5f;
    uint32_t bits, end;
    std::memcpy(&bits, &lo, 4);
    std::memcpy(&end, &hi, 4);
    for (; bits < end; bits += 97) {
      float p;
      std::memcpy(&p, &bits, 4);
      const uint8_t expected = p > static_cast<float>(min_p) ? codec.encode_search(p) : 255;
      mismatches += codec.encode(p) != expected;
    }
    EXPECT_EQ(mismatches, 0) << "min_probability " << min_p;
  }
}

// The quantisers find codes by a table search (no logarithm per voxel update); the codes must
// be those of the closed forms round(log1p(w / unit) / L) and round(-ln p / step).
TEST(Quantizers, TableSearchEqualsClosedForm) {
  const WeightQuantizer wq(0.01, 1000.0);
  const double L = std::log1p(1000.0 / 0.01) / 255.0;
  const BayesLayerCodec codec(4, 1e-5);
  const double step = -std::log(1e-5) / 255.0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> log_w(std::log(1e-4), std::log(999.0)), log_p(std::log(1.1e-5), 0.0);
  int mismatches = 0;
  for (int i = 0; i < 200000; ++i) {
    const float w = static_cast<float>(std::exp(log_w(rng)));
    const long qw = std::clamp(std::lround(std::log1p(double(w) / 0.01) / L), 1L, 255L);
    mismatches += wq.encode(w) != qw;
    const float p = static_cast<float>(std::exp(log_p(rng)));
    const long qp = std::clamp(std::lround(-std::log(double(p)) / step), 0L, 255L);
    mismatches += codec.encode(p) != qp;
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_EQ(codec.encode(1.0f), 0);
  EXPECT_EQ(codec.encode(1e-6f), 255);
}

// The integrator's upward scan from the old code must give encode's code for any start code,
// for weights above, at and below decode(start), including the ends of the scale.
TEST(WeightQuantizer, EncodeFromEqualsEncode) {
  const WeightQuantizer wq(0.01, 1000.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> log_w(std::log(1e-5), std::log(2000.0));
  std::uniform_int_distribution<int> code(0, 255);
  int mismatches = 0;
  for (int i = 0; i < 500000; ++i) {
    const float w = static_cast<float>(std::exp(log_w(rng)));
    const uint8_t from = static_cast<uint8_t>(i % 2 ? code(rng) : wq.encode(w * 0.8f));  // random / a realistic old code
    mismatches += wq.encode_from(w, from) != wq.encode(w);
  }
  for (int q = 0; q < 256; ++q)
    for (int from = 0; from < 256; ++from) {
      const float w = wq.decode(static_cast<uint8_t>(q));
      mismatches += wq.encode_from(w, static_cast<uint8_t>(from)) != wq.encode(w);
      mismatches += wq.encode_from(std::nextafter(w, 0.0f), static_cast<uint8_t>(from)) != wq.encode(std::nextafter(w, 0.0f));
    }
  for (float w : {0.0f, -1.0f, std::nanf(""), 1e-9f, 1000.0f, 1e9f})
    for (int from : {0, 1, 2, 128, 254, 255}) mismatches += wq.encode_from(w, static_cast<uint8_t>(from)) != wq.encode(w);
  EXPECT_EQ(mismatches, 0);
}

TEST(SemanticGrouping, PicksWeightedMajorityLabelAndItsMean) {
  // 3 chair points of weight 1 against 2 table points of weight 2: table wins (4 > 3).
  std::vector<LabelledPoint> pts = {
      {{0.0f, 0.0f, 1.0f}, 1.0f, id(Label::kChair)}, {{0.01f, 0.0f, 1.0f}, 1.0f, id(Label::kChair)},
      {{0.02f, 0.0f, 1.0f}, 1.0f, id(Label::kChair)}, {{0.0f, 0.01f, 1.0f}, 2.0f, id(Label::kTable)},
      {{0.0f, 0.02f, 1.0f}, 2.0f, id(Label::kTable)}};
  PointGroup g = group_points(pts);
  EXPECT_EQ(g.label, id(Label::kTable));
  EXPECT_FLOAT_EQ(g.label_weight, 4.0f);
  EXPECT_FLOAT_EQ(g.total_weight, 7.0f);
  EXPECT_NEAR(g.point.y(), 0.015f, 1e-6f);  // mean of the table points only
  EXPECT_NEAR(g.point.x(), 0.0f, 1e-6f);
  // More points but less weight loses.
  pts.push_back({{0.0f, 0.0f, 1.0f}, 0.5f, id(Label::kChair)});
  EXPECT_EQ(group_points(pts).label, id(Label::kTable));  // chair 3.5 < table 4
  pts.push_back({{0.0f, 0.0f, 1.0f}, 1.0f, id(Label::kChair)});
  EXPECT_EQ(group_points(pts).label, id(Label::kChair));  // chair 4.5 > table 4
}

TEST(CompactLabel, MajorityVoteOvertakes) {
  ClassId label = 0;
  uint8_t votes = 0;
  compact_label_vote(label, votes, id(Label::kChair));
  compact_label_vote(label, votes, id(Label::kChair));
  EXPECT_EQ(label, id(Label::kChair));
  compact_label_vote(label, votes, id(Label::kTable));
  EXPECT_EQ(label, id(Label::kChair));  // 2 - 1 left
  compact_label_vote(label, votes, id(Label::kTable));
  compact_label_vote(label, votes, id(Label::kTable));
  EXPECT_EQ(label, id(Label::kTable));  // overtaken
  compact_label_vote(label, votes, 0);
  EXPECT_EQ(label, id(Label::kTable));  // unlabelled pixels never vote
  // 20 % flicker to random labels never displaces an 80 % majority.
  std::mt19937 rng(5);
  label = 0;
  votes = 0;
  int wrong = 0;
  for (int i = 0; i < 500; ++i) {
    const bool flicker = rng() % 5 == 0;
    compact_label_vote(label, votes, flicker ? static_cast<ClassId>(1 + rng() % 38) : id(Label::kSofa));
    if (i > 20) wrong += label != id(Label::kSofa);
  }
  EXPECT_EQ(wrong, 0);
}

TEST(BayesLayer, TwoObservationsMultiplyAndRenormalise) {
  const BayesLayerCodec codec(4, 1e-4);
  std::vector<uint8_t> voxel(8, 0);
  for (int i = 0; i < 4; ++i) voxel[2 * i + 1] = 255;
  // Uniform prior, observation P(chair) = 0.6: posterior = 0.6.
  codec.update(voxel.data(), ClassDistribution::from_label(id(Label::kChair), 0.6f));
  ClassDistribution d = codec.read(voxel.data());
  ASSERT_GE(d.count, 1);
  EXPECT_EQ(d.classes[0], id(Label::kChair));
  EXPECT_NEAR(d.probabilities[0], 0.6f, 0.6f * 0.03f);
  // Second observation P(chair) = 0.6 again: 0.36 / (0.36 + 37 * (0.4/37)^2) = 0.36 / 0.3643.
  codec.update(voxel.data(), ClassDistribution::from_label(id(Label::kChair), 0.6f));
  d = codec.read(voxel.data());
  const double expected = 0.36 / (0.36 + 37 * std::pow(0.4 / 37, 2));
  EXPECT_NEAR(d.probabilities[0], expected, expected * 0.03);
  // A full probability vector: table 0.7, chair 0.3 against chair prior ~0.99.
  std::vector<float> probs(kNumClasses, 0.0f);
  probs[id(Label::kTable)] = 0.7f;
  probs[id(Label::kChair)] = 0.3f;
  codec.update(voxel.data(), ClassDistribution::from_probabilities(probs.data(), kNumClasses, 4));
  d = codec.read(voxel.data());
  EXPECT_EQ(d.classes[0], id(Label::kChair));
  EXPECT_EQ(d.classes[1], id(Label::kTable));
  double sum = 0;
  for (int i = 0; i < d.count; ++i) sum += d.probabilities[i];
  EXPECT_LE(sum, 1.03);
}

TEST(BayesLayer, EvidenceRuleCountsFramesNotSaturatedProbabilities) {
  // Defaults: c = 0.7, m = 4 confusable classes -> one label-only frame multiplies the odds of its
  // label by r = 0.7 * 4 / 0.3 = 9.33; the mesh shows the argmax at a lead of three frames
  // (odds >= r^2.5, midway between two and three frames' odds).
  const TsdfConfig cfg;
  const BayesLayerCodec codec(cfg.bayes_top_k, cfg.bayes_min_probability);
  const double r = cfg.bayes_frame_odds();
  EXPECT_NEAR(r, 0.7 * 4 / 0.3, 1e-9);
  const double needed = std::pow(r, cfg.mesh_min_label_frames - 0.5);
  ASSERT_LT(needed, 0.9 * codec.max_odds());  // the floor can represent the rule's odds
  auto observe = [&](std::vector<uint8_t>& voxel, Label l) {
    codec.update(voxel.data(), ClassDistribution::from_label(id(l), static_cast<float>(cfg.bayes_default_confidence),
                                                             cfg.bayes_confusion_classes));
  };
  auto fresh = [&] {
    std::vector<uint8_t> v(static_cast<size_t>(codec.bytes_per_voxel()), 0);
    for (int i = 0; i < codec.k(); ++i) v[2 * i + 1] = 255;
    return v;
  };
  auto shown = [&](const std::vector<uint8_t>& v) { return codec.top_odds(v.data()) >= needed; };
  // Odds grow by r per agreeing frame (quantisation: 3 % per stored probability).
  std::vector<uint8_t> voxel = fresh();
  observe(voxel, Label::kWall);
  EXPECT_NEAR(codec.top_odds(voxel.data()), r, r * 0.06);
  observe(voxel, Label::kWall);
  // Stored probabilities are rounded to half a code step (relative); the odds against the unlisted
  // classes, p / ((1 - p) / (N - 1)), amplify an error in p by 1 / (1 - p), twice over two frames.
  const double half_step = std::log(1.0 / cfg.bayes_min_probability) / 255 / 2;
  const double p2 = r * r / (r * r + (kNumRealClasses - 1));  // the label's posterior after two frames
  EXPECT_NEAR(codec.top_odds(voxel.data()), r * r, r * r * 2 * half_step / (1 - p2));
  EXPECT_FALSE(shown(voxel));  // two frames: not enough
  observe(voxel, Label::kWall);
  EXPECT_TRUE(shown(voxel));
  // The stray-class pattern of 20 % region flicker on a rarely seen patch: 4 x ceiling, 2 x wall,
  // 2 x floor. Ceiling is the argmax (and above 0.9), but leads by only two frames: not shown.
  voxel = fresh();
  for (Label l : {Label::kCeiling, Label::kWall, Label::kCeiling, Label::kFloor, Label::kCeiling, Label::kWall,
                  Label::kFloor, Label::kCeiling})
    observe(voxel, l);
  EXPECT_EQ(BayesLayerCodec::argmax(voxel.data()), id(Label::kCeiling));
  EXPECT_FALSE(shown(voxel));
  // A well-seen wall keeps its evidence through the same flicker: 20 frames, 4 of them ceiling.
  voxel = fresh();
  for (int i = 0; i < 20; ++i) observe(voxel, i % 5 == 2 ? Label::kCeiling : Label::kWall);
  EXPECT_EQ(BayesLayerCodec::argmax(voxel.data()), id(Label::kWall));
  EXPECT_TRUE(shown(voxel));
}

TEST(BayesLayer, TopKKeepsTheMostProbable) {
  const BayesLayerCodec codec(2, 1e-3);
  std::vector<uint8_t> voxel(4, 0);
  voxel[1] = voxel[3] = 255;
  std::vector<float> probs(kNumClasses, 0.0f);
  probs[3] = 0.5f;
  probs[5] = 0.3f;
  probs[7] = 0.2f;
  const ClassDistribution obs = ClassDistribution::from_probabilities(probs.data(), kNumClasses, 8);
  EXPECT_EQ(obs.count, 3);
  codec.update(voxel.data(), obs);
  EXPECT_EQ(voxel[0], 3);
  EXPECT_EQ(voxel[2], 5);
  // Floor keeps the update recoverable: repeated class 7 observations take over.
  probs.assign(kNumClasses, 0.0f);
  probs[7] = 0.9f;
  probs[3] = 0.1f;
  for (int i = 0; i < 5; ++i) codec.update(voxel.data(), ClassDistribution::from_probabilities(probs.data(), kNumClasses, 8));
  EXPECT_EQ(BayesLayerCodec::argmax(voxel.data()), 7);
}

TEST(BlockHashTable, MatchesUnorderedMapUnderInsertErase) {
  BlockHashTable table;
  std::unordered_map<BlockIndex, int32_t, BlockHash> ref;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> coord(-40, 40);
  for (int i = 0; i < 20000; ++i) {
    const BlockIndex b(coord(rng), coord(rng), coord(rng) / 8);
    if (rng() % 3 == 0) {
      table.erase(b);
      ref.erase(b);
    } else if (!ref.count(b)) {
      table.insert(b, i);
      ref[b] = i;
    }
  }
  EXPECT_EQ(table.size(), ref.size());
  for (const auto& [k, v] : ref) EXPECT_EQ(table.find(k), v);
  for (int i = 0; i < 2000; ++i) {
    const BlockIndex b(coord(rng), coord(rng), coord(rng) / 8);
    EXPECT_EQ(table.find(b), ref.count(b) ? ref[b] : -1);
  }
}

TEST(TsdfMap, RemoveKeepsLookupsConsistent) {
  TsdfConfig cfg;
  TsdfMap map(cfg);
  for (int i = 0; i < 100; ++i) map.allocate_block(BlockIndex(i, -i, i % 7));
  EXPECT_EQ(map.num_blocks(), 100u);
  EXPECT_EQ(map.bytes_per_voxel(), 4u + 1u + 8u + 3u);  // core 4 + vote 1 + Bayesian top-4 (2 bytes each) + RGB 3, the defaults
  size_t far = 0;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3f c = (Eigen::Vector3f(i, -i, i % 7) * 0.16f).array() + 0.08f;
    far += c.norm() > 5.0f;
  }
  ASSERT_GT(far, 0u);
  EXPECT_EQ(map.remove_blocks_beyond(Eigen::Vector3f::Zero(), 5.0f), far);
  EXPECT_EQ(map.num_blocks(), 100 - far);
  for (const auto& b : map.blocks()) EXPECT_EQ(map.find_block(b->index), b.get());
  EXPECT_EQ(map.take_removed_blocks().size(), far);
}

}  // namespace
}  // namespace semap
