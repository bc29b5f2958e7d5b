#include "tracking/keyframe_database.hpp"

#include <algorithm>

#include "semap/core/error.hpp"

namespace semap {

namespace {
FernParams fern_params(const TrackingConfig& c) {
  FernParams p = c.ferns;
  p.min_depth = c.min_depth;
  p.max_depth = c.max_depth;
  p.seed = uint32_t(c.seed);
  return p;
}
/// RANSAC seed of a registration against keyframe `id` (relocalisation, map merging).
uint32_t keyframe_seed(const TrackingConfig& c, int id) { return uint32_t(c.seed) + 104729u * uint32_t(id + 1); }
}  // namespace

KeyframeDatabase::KeyframeDatabase(const TrackingConfig& config, const Odometry& odometry)
    : cfg_(config), odometry_(odometry), ferns_(fern_params(config)) {}

void KeyframeDatabase::add(std::shared_ptr<const Keyframe> keyframe) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (keyframe->id != int(keyframes_.size())) throw Error("KeyframeDatabase::add", "keyframe ids must be added in order");
  ferns_.add(keyframe->id, keyframe->code);
  keyframes_.push_back(std::move(keyframe));
}

std::shared_ptr<const Keyframe> KeyframeDatabase::get(int id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_.at(size_t(id));
}

std::vector<std::shared_ptr<const Keyframe>> KeyframeDatabase::all() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_;
}

size_t KeyframeDatabase::size() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return keyframes_.size();
}

double KeyframeDatabase::max_similarity(const FernCode& code) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return ferns_.max_similarity(code);
}

std::vector<std::shared_ptr<const Keyframe>> KeyframeDatabase::most_similar_locked(const FernCode& code, int count) const {
  std::vector<std::pair<double, std::shared_ptr<const Keyframe>>> by_fern;
  const auto sims = ferns_.similarities(code);
  for (size_t i = 0; i < sims.size(); ++i) by_fern.emplace_back(sims[i], keyframes_[ferns_.ids()[i]]);
  std::stable_sort(by_fern.begin(), by_fern.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::shared_ptr<const Keyframe>> out;
  for (int i = 0; i < int(by_fern.size()) && i < count; ++i) out.push_back(by_fern[i].second);
  return out;
}

std::vector<std::shared_ptr<const Keyframe>> KeyframeDatabase::most_similar(const FernCode& code, int count) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return most_similar_locked(code, count);
}

std::vector<std::shared_ptr<const Keyframe>> KeyframeDatabase::loop_candidates(const Keyframe& kf) const {
  std::vector<std::pair<double, std::shared_ptr<const Keyframe>>> candidates;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto sims = ferns_.similarities(kf.code);
    const auto& ids = ferns_.ids();
    for (size_t i = 0; i < ids.size(); ++i) {
      const int other = ids[i];
      if (kf.id - other < cfg_.loop_min_keyframe_gap || sims[i] < cfg_.loop_min_similarity) continue;
      candidates.emplace_back(sims[i], keyframes_[other]);
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  if (int(candidates.size()) > cfg_.loop_candidates) candidates.resize(size_t(cfg_.loop_candidates));
  std::vector<std::shared_ptr<const Keyframe>> out;
  for (auto& [sim, other] : candidates) out.push_back(std::move(other));
  return out;
}

/// Wide-baseline registration judged with no prior: feature support and enough overlap.
bool KeyframeDatabase::accepted_as_relocalisation(const OdometryResult& reg) const {
  return reg.accepted && reg.icp.overlap >= cfg_.relocalisation_min_overlap;
}

std::optional<KeyframeRegistration> KeyframeDatabase::relocalise(const FrameFeatures& features,
                                                                 const std::vector<DepthLevel>& frame_pyramid,
                                                                 const FernCode& code, int reference,
                                                                 const std::vector<DepthLevel>& reference_pyramid) const {
  if (int(features.points.size()) < cfg_.ransac.trusted_inliers) return std::nullopt;  // blank / textureless frame
  std::vector<std::shared_ptr<const Keyframe>> candidates;
  {
    auto add = [&](const std::shared_ptr<const Keyframe>& kf) {
      if (std::find(candidates.begin(), candidates.end(), kf) == candidates.end()) candidates.push_back(kf);
    };
    std::lock_guard<std::mutex> lock(mutex_);
    const auto similar = most_similar_locked(code, cfg_.relocalisation_candidates);
    if (reference >= 0) add(keyframes_[size_t(reference)]);
    for (const auto& kf : similar) add(kf);
    for (int i = 0; i < cfg_.relocalisation_recent && i < int(keyframes_.size()); ++i)
      add(keyframes_[keyframes_.size() - 1 - size_t(i)]);
  }
  for (const auto& kf : candidates) {
    auto kf_pyramid = kf->id == reference ? reference_pyramid : odometry_.pyramid(kf->depth, kf->gray);
    OdometryResult reg = odometry_.register_to(features, frame_pyramid, kf->features, kf_pyramid, nullptr,
                                               keyframe_seed(cfg_, kf->id), RegistrationEffort::wide);
    if (accepted_as_relocalisation(reg)) return KeyframeRegistration{kf, std::move(reg), std::move(kf_pyramid)};
  }
  return std::nullopt;
}

std::optional<KeyframeRegistration> KeyframeDatabase::match(const Keyframe& other) const {
  if (int(other.features.points.size()) < cfg_.ransac.trusted_inliers) return std::nullopt;  // textureless view
  const auto other_pyramid = odometry_.pyramid(other.depth, other.gray, true);
  for (const auto& kf : most_similar(other.code, cfg_.relocalisation_candidates)) {
    auto kf_pyramid = odometry_.pyramid(kf->depth, kf->gray);
    OdometryResult reg = odometry_.register_to(other.features, other_pyramid, kf->features, kf_pyramid, nullptr,
                                               keyframe_seed(cfg_, kf->id), RegistrationEffort::wide);
    if (accepted_as_relocalisation(reg)) return KeyframeRegistration{kf, std::move(reg), std::move(kf_pyramid)};
  }
  return std::nullopt;
}

void KeyframeDatabase::remember_target(int id, const std::vector<DepthLevel>& pyramid) {
  if (cfg_.local_edge_keyframes <= 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  recent_targets_[id] = {++target_uses_, std::make_shared<const std::vector<DepthLevel>>(pyramid)};  // shares the pixels
  while (int(recent_targets_.size()) > cfg_.local_edge_keyframes + 1) {
    auto oldest = recent_targets_.begin();
    for (auto it = recent_targets_.begin(); it != recent_targets_.end(); ++it)
      if (it->second.last_use < oldest->second.last_use) oldest = it;
    recent_targets_.erase(oldest);
  }
}

std::shared_ptr<const std::vector<DepthLevel>> KeyframeDatabase::recent_target(int id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = recent_targets_.find(id);
  return it == recent_targets_.end() ? nullptr : it->second.pyramid;
}

std::map<int, std::shared_ptr<const std::vector<DepthLevel>>> KeyframeDatabase::recent_targets() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::map<int, std::shared_ptr<const std::vector<DepthLevel>>> out;
  for (const auto& [id, entry] : recent_targets_) out[id] = entry.pyramid;
  return out;
}

}  // namespace semap
