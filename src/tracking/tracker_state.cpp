#include "tracking/tracker_state.hpp"

#include "core/archive.hpp"

namespace semap {
namespace {

constexpr uint32_t kTrackerStateFormat = 1;

void put_pose(ByteWriter& w, const Pose& T) { w.put_bytes(T.matrix().data(), 16 * sizeof(double)); }

Pose get_pose(ByteReader& r) {
  Pose T;
  r.read(T.matrix().data(), 16 * sizeof(double));
  if (!T.matrix().allFinite() || !is_valid_pose(T, 1e-4)) r.fail("a pose is not a rigid transform");
  return T;
}

void put_features(ByteWriter& w, const FrameFeatures& f) {
  w.put(static_cast<uint64_t>(f.keypoints.size()));
  for (const cv::KeyPoint& k : f.keypoints) {
    w.put(k.pt.x), w.put(k.pt.y), w.put(k.size), w.put(k.angle), w.put(k.response);
    w.put(static_cast<int32_t>(k.octave)), w.put(static_cast<int32_t>(k.class_id));
  }
  w.put_mat(f.descriptors);
  w.put(static_cast<uint64_t>(f.points.size()));
  for (const Eigen::Vector3d& p : f.points) w.put_bytes(p.data(), 3 * sizeof(double));
}

FrameFeatures get_features(ByteReader& r) {
  FrameFeatures f;
  f.keypoints.resize(r.get_count(28));
  for (cv::KeyPoint& k : f.keypoints) {
    k.pt.x = r.get<float>(), k.pt.y = r.get<float>(), k.size = r.get<float>(), k.angle = r.get<float>();
    k.response = r.get<float>(), k.octave = r.get<int32_t>(), k.class_id = r.get<int32_t>();
  }
  f.descriptors = r.get_mat();
  f.points.resize(r.get_count(24));
  for (Eigen::Vector3d& p : f.points) r.read(p.data(), 3 * sizeof(double));
  if (f.points.size() != f.keypoints.size() || (!f.keypoints.empty() && f.descriptors.rows != int(f.keypoints.size())))
    r.fail("keypoints, descriptors and points differ in number");
  return f;
}

void put_keyframe(ByteWriter& w, const Keyframe& kf, const Pose& T_world_kf) {
  w.put(static_cast<int32_t>(kf.id));
  w.put(static_cast<uint64_t>(kf.frame_index));
  w.put(kf.timestamp);
  put_pose(w, T_world_kf);
  w.put(static_cast<int32_t>(kf.parent));
  put_pose(w, kf.T_parent_this);
  w.put_mat(kf.depth);
  w.put_mat(kf.gray);
  put_features(w, kf.features);
  w.put(static_cast<uint64_t>(kf.code.size()));
  w.put_bytes(kf.code.data(), kf.code.size() * sizeof(uint16_t));
}

std::shared_ptr<Keyframe> get_keyframe(ByteReader& r, int expected_id, Pose& T_world_kf) {
  auto kf = std::make_shared<Keyframe>();
  kf->id = r.get<int32_t>();
  if (kf->id != expected_id) r.fail("keyframe ids are not 0, 1, 2, ...");
  kf->frame_index = r.get<uint64_t>();
  kf->timestamp = r.get<double>();
  T_world_kf = get_pose(r);
  kf->parent = r.get<int32_t>();
  if (kf->parent < -1 || kf->parent >= kf->id) r.fail("keyframe " + std::to_string(kf->id) + " has a bad parent");
  kf->T_parent_this = get_pose(r);
  kf->depth = r.get_mat();
  kf->gray = r.get_mat();
  if (kf->depth.type() != CV_32FC1 || kf->gray.type() != CV_8UC1 || kf->depth.size() != kf->gray.size())
    r.fail("keyframe " + std::to_string(kf->id) + " images are not a CV_32FC1 depth and a CV_8UC1 grey of one size");
  kf->features = get_features(r);
  kf->code.resize(r.get_count(sizeof(uint16_t)));
  r.read(kf->code.data(), kf->code.size() * sizeof(uint16_t));
  return kf;
}

}  // namespace

std::string encode_tracker_state(const TrackerState& state) {
  ByteWriter w;
  w.put(kTrackerStateFormat);
  w.put(static_cast<uint64_t>(state.keyframes.size()));
  for (size_t i = 0; i < state.keyframes.size(); ++i) put_keyframe(w, *state.keyframes[i], state.T_world_keyframe[i]);
  w.put(static_cast<uint64_t>(state.edges.size()));
  for (const PoseGraphEdge& e : state.edges) {
    w.put(static_cast<int32_t>(e.from)), w.put(static_cast<int32_t>(e.to));
    put_pose(w, e.T_from_to);
    w.put_bytes(e.information.data(), 36 * sizeof(double));
    w.put(static_cast<uint8_t>(e.is_loop));
  }
  return std::move(w.bytes());
}

TrackerState decode_tracker_state(std::string_view bytes, const std::filesystem::path& path) {
  ByteReader r(bytes, path, kTrackingSection);
  if (const uint32_t format = r.get<uint32_t>(); format != kTrackerStateFormat)
    r.fail("tracking format " + std::to_string(format) + ", this build reads " + std::to_string(kTrackerStateFormat));
  TrackerState state;
  const size_t n = r.get_count(1);
  for (size_t i = 0; i < n; ++i) {
    Pose T_world_kf;
    state.keyframes.push_back(get_keyframe(r, static_cast<int>(i), T_world_kf));
    state.T_world_keyframe.push_back(T_world_kf);
  }
  state.edges.resize(r.get_count(2 * 4 + 16 * 8 + 36 * 8 + 1));
  for (PoseGraphEdge& e : state.edges) {
    e.from = r.get<int32_t>(), e.to = r.get<int32_t>();
    if (e.from < 0 || e.to < 0 || size_t(e.from) >= n || size_t(e.to) >= n) r.fail("a pose-graph edge names no keyframe");
    e.T_from_to = get_pose(r);
    r.read(e.information.data(), 36 * sizeof(double));
    if (!e.information.allFinite()) r.fail("an edge's information is not finite");
    e.is_loop = r.get<uint8_t>() != 0;
  }
  r.expect_end();
  return state;
}

TrackerState append_tracker_state(TrackerState a, const TrackerState& b, const Pose& T_a_b,
                                  const std::vector<PoseGraphEdge>& links) {
  const int shift = static_cast<int>(a.keyframes.size());
  for (size_t i = 0; i < b.keyframes.size(); ++i) {
    auto kf = std::make_shared<Keyframe>(*b.keyframes[i]);  // images and features are shared, not copied
    kf->id += shift;
    if (kf->parent >= 0) kf->parent += shift;
    a.keyframes.push_back(std::move(kf));
    a.T_world_keyframe.push_back(orthonormalized(T_a_b * b.T_world_keyframe[i]));
  }
  for (PoseGraphEdge e : b.edges) {
    e.from += shift;
    e.to += shift;
    a.edges.push_back(e);
  }
  for (PoseGraphEdge e : links) {
    e.to += shift;
    e.is_loop = true;
    a.edges.push_back(e);
  }
  return a;
}

}  // namespace semap
