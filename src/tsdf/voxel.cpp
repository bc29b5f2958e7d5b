#include "semap/tsdf/voxel.hpp"

namespace semap {

ClassDistribution ClassDistribution::from_label(ClassId label, float confidence, int confusion_classes) {
  ClassDistribution d;
  d.count = 1;
  d.classes[0] = label;
  d.probabilities[0] = confidence;
  // A likelihood over the true class (not normalised): the Bayes update normalises the posterior.
  // Capped at c: an observation never argues against its own label (r >= 1).
  d.rest_each = std::min(confidence, (1.0f - confidence) / static_cast<float>(std::clamp(confusion_classes, 1, kNumRealClasses - 1)));
  return d;
}

ClassDistribution ClassDistribution::from_probabilities(const float* probs, int num_channels, int k) {
  ClassDistribution d;
  k = std::min(k, kMaxTopK);
  float total = 0.0f;
  for (int c = 1; c < num_channels && c < kNumClasses; ++c) {
    const float p = std::max(probs[c], 0.0f);
    total += p;
    if (p <= 0) continue;
    // Insertion into the sorted top-k (ties: lower class id first, deterministic).
    int pos = d.count;
    while (pos > 0 && d.probabilities[pos - 1] < p) --pos;
    if (pos >= k) continue;
    const int last = std::min(d.count, k - 1);
    for (int i = last; i > pos; --i) {
      d.classes[i] = d.classes[i - 1];
      d.probabilities[i] = d.probabilities[i - 1];
    }
    d.classes[pos] = static_cast<ClassId>(c);
    d.probabilities[pos] = p;
    d.count = std::min(d.count + 1, k);
  }
  if (!(total > 0)) return ClassDistribution{};  // no information: uniform
  float listed = 0.0f;
  for (int i = 0; i < d.count; ++i) {
    d.probabilities[i] /= total;
    listed += d.probabilities[i];
  }
  const int others = kNumRealClasses - d.count;
  d.rest_each = others > 0 ? std::max(0.0f, 1.0f - listed) / static_cast<float>(others) : 0.0f;
  return d;
}

ClassDistribution BayesLayerCodec::read(const uint8_t* voxel) const {
  ClassDistribution d;
  float listed = 0.0f;
  for (int i = 0; i < k_; ++i) {
    if (voxel[2 * i] == 0) break;
    d.classes[d.count] = voxel[2 * i];
    d.probabilities[d.count] = decode(voxel[2 * i + 1]);
    listed += d.probabilities[d.count];
    ++d.count;
  }
  if (d.count == 0) return d;  // uniform prior
  const int others = kNumRealClasses - d.count;
  // Unlisted mass, floored so that no class becomes impossible (Bayes stays recoverable).
  d.rest_each = others > 0 ? std::max(std::max(0.0f, 1.0f - listed) / others, static_cast<float>(min_p_)) : 0.0f;
  return d;
}

void BayesLayerCodec::update(uint8_t* voxel, const ClassDistribution& observation) const {
  const ClassDistribution prior = read(voxel);
  // Candidates: classes listed by the prior or the observation.
  std::array<ClassId, 2 * kMaxTopK> classes{};
  std::array<float, 2 * kMaxTopK> posterior{};
  int n = 0;
  auto likelihood = [&](ClassId c) {
    for (int i = 0; i < observation.count; ++i)
      if (observation.classes[i] == c) return observation.probabilities[i];
    return observation.rest_each;
  };
  for (int i = 0; i < prior.count; ++i) {
    classes[n] = prior.classes[i];
    posterior[n] = prior.probabilities[i] * likelihood(prior.classes[i]);
    ++n;
  }
  for (int i = 0; i < observation.count; ++i) {
    bool present = false;
    for (int j = 0; j < prior.count; ++j) present |= prior.classes[j] == observation.classes[i];
    if (present) continue;
    classes[n] = observation.classes[i];
    posterior[n] = prior.rest_each * observation.probabilities[i];
    ++n;
  }
  // Mass of all classes that are not candidates: each has prior rest_each, likelihood rest_each.
  const float rest_mass = static_cast<float>(kNumRealClasses - n) * prior.rest_each * observation.rest_each;
  float z = rest_mass;
  for (int i = 0; i < n; ++i) z += posterior[i];
  if (!(z > 0)) return;
  // Sort candidates by posterior (ties by class id) and keep the top k.
  // Insertion sort: n <= 2 kMaxTopK, mostly already in order (the prior's order), where it does
  // a comparison per candidate; the order is total (distinct classes), so any sort gives it.
  std::array<int, 2 * kMaxTopK> order{};
  auto before = [&](int a, int b) {
    return posterior[a] != posterior[b] ? posterior[a] > posterior[b] : classes[a] < classes[b];
  };
  for (int i = 0; i < n; ++i) {
    int j = i;
    for (; j > 0 && before(i, order[j - 1]); --j) order[j] = order[j - 1];
    order[j] = i;
  }
  const float inv_z = 1.0f / z;
  for (int i = 0; i < k_; ++i) {
    if (i < n) {
      voxel[2 * i] = classes[order[i]];
      voxel[2 * i + 1] = encode(posterior[order[i]] * inv_z);
    } else {
      voxel[2 * i] = 0;
      voxel[2 * i + 1] = 255;
    }
  }
}

}  // namespace semap
