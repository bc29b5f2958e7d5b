// ObjectMap as a map.semap section (issue 19):
//   u32 format | u32 class count C | u32 next id | u64 instance count | per instance: u32 id, i32 n,
//   i32 s, i32 s_total, u8 state, u8 changed, u8 decided class, u64 first frame, u64 last frame,
//   u64 last step, f64[C] score sum, u64 points, per point f32 x y z + u8 r g b,
//   u64 co-associations, per entry (ascending id) u32 id, i32 count
// Point frames are not kept: a saved map's points are fixed (kSavedMapFrame). The voxel index,
// centroid sum and box are rebuilt from the points.
#include <algorithm>

#include "core/archive.hpp"
#include "objects/object_map.hpp"
#include "objects/object_mapper.hpp"

namespace semap {
namespace {

// Format 2 (issue 38) stores the class count: classes are appended after "other", so a map
// written with fewer classes still reads (format 1 had no count: 39 classes, ids 0..38).
constexpr uint32_t kObjectStateFormat = 2;
constexpr uint32_t kFormat1Classes = 39;
/// Issue 44 (fuzz_map_archive): a saved object point farther out than this is corrupt (the map
/// voxel key of a point at 1e20 m overflowed its integer cell).
constexpr float kMaxObjectCoordinateM = 1e6f;

void put_instance(ByteWriter& w, const ObjectInstance& inst) {
  w.put(inst.id), w.put(static_cast<int32_t>(inst.n));
  w.put(static_cast<int32_t>(inst.association_count)), w.put(static_cast<int32_t>(inst.total_associations));
  w.put(static_cast<uint8_t>(inst.state)), w.put(static_cast<uint8_t>(inst.changed)), w.put(inst.decided_class);
  w.put(static_cast<uint64_t>(inst.first_frame)), w.put(static_cast<uint64_t>(inst.last_frame));
  w.put(static_cast<uint64_t>(inst.last_step));
  std::vector<double> scores = inst.score_sum;
  scores.resize(kNumClasses, 0.0);
  w.put_bytes(scores.data(), scores.size() * sizeof(double));
  w.put(static_cast<uint64_t>(inst.points.size()));
  for (size_t i = 0; i < inst.points.size(); ++i) {
    w.put_bytes(inst.points[i].data(), 3 * sizeof(float));
    w.put(inst.colours[i]);
  }
  std::vector<std::pair<uint32_t, int>> co(inst.co_association.begin(), inst.co_association.end());
  std::sort(co.begin(), co.end());  // unordered_map order is not stable: bytes must be
  w.put(static_cast<uint64_t>(co.size()));
  for (const auto& [id, count] : co) w.put(id), w.put(static_cast<int32_t>(count));
}

}  // namespace

std::string ObjectMap::encode_state() const {
  ByteWriter w;
  w.put(kObjectStateFormat);
  w.put(static_cast<uint32_t>(kNumClasses));
  w.put(next_id_);
  w.put(static_cast<uint64_t>(instances_.size()));
  for (const ObjectInstance& inst : instances_) put_instance(w, inst);
  return std::move(w.bytes());
}

void ObjectMap::decode_state(std::string_view bytes, const std::filesystem::path& path) {
  ByteReader r(bytes, path, kObjectsSection);
  const uint32_t format = r.get<uint32_t>();
  if (format != 1 && format != kObjectStateFormat)
    r.fail("objects format " + std::to_string(format) + ", this build reads 1 and " + std::to_string(kObjectStateFormat));
  const uint32_t classes = format == 1 ? kFormat1Classes : r.get<uint32_t>();
  if (classes > static_cast<uint32_t>(kNumClasses))
    r.fail("objects have " + std::to_string(classes) + " classes, this build knows " + std::to_string(kNumClasses));
  const uint32_t next_id = r.get<uint32_t>();
  std::vector<ObjectInstance> instances(r.get_count(64));
  for (ObjectInstance& inst : instances) {
    inst.id = r.get<uint32_t>();
    if (inst.id == 0 || inst.id >= next_id) r.fail("an object id is not below the next id");
    inst.n = r.get<int32_t>(), inst.association_count = r.get<int32_t>(), inst.total_associations = r.get<int32_t>();
    const uint8_t state = r.get<uint8_t>();
    if (state > static_cast<uint8_t>(InstanceState::kStable)) r.fail("bad object state");
    inst.state = static_cast<InstanceState>(state);
    inst.changed = r.get<uint8_t>() != 0;
    inst.decided_class = r.get<ClassId>();
    if (inst.decided_class >= kNumClasses) r.fail("bad object class");
    inst.first_frame = r.get<uint64_t>(), inst.last_frame = r.get<uint64_t>(), inst.last_step = r.get<uint64_t>();
    inst.score_sum.assign(kNumClasses, 0.0);
    r.read(inst.score_sum.data(), classes * sizeof(double));
    const size_t n_points = r.get_count(3 * sizeof(float) + sizeof(Rgb8));
    std::vector<Eigen::Vector3f> points(n_points);
    std::vector<Rgb8> colours(n_points);
    for (size_t i = 0; i < n_points; ++i) {
      r.read(points[i].data(), 3 * sizeof(float));
      if (!points[i].allFinite()) r.fail("an object point is not finite");
      if (points[i].cwiseAbs().maxCoeff() > kMaxObjectCoordinateM) r.fail("an object point lies beyond 1e6 m");
      colours[i] = r.get<Rgb8>();
    }
    add_points(inst, points, colours, {kSavedMapFrame});
    if (inst.points.size() != n_points) r.fail("two points of an object share a map voxel");
    const size_t n_co = r.get_count(8);
    for (size_t i = 0; i < n_co; ++i) {
      const uint32_t id = r.get<uint32_t>();
      inst.co_association[id] = r.get<int32_t>();
    }
  }
  r.expect_end();
  instances_ = std::move(instances);
  next_id_ = next_id;
}

}  // namespace semap

namespace semap {

std::string ObjectMapper::encode_state() const {
  ByteWriter w;
  w.put(static_cast<uint64_t>(step_));
  w.put_string(map_.encode_state());
  return std::move(w.bytes());
}

namespace {
struct MapperSection {
  size_t step = 0;
  std::string map_bytes;
};
MapperSection read_mapper_section(std::string_view bytes, const std::filesystem::path& path) {
  ByteReader r(bytes, path, kObjectsSection);
  MapperSection out;
  out.step = static_cast<size_t>(r.get<uint64_t>());
  out.map_bytes = r.get_string();
  r.expect_end();
  return out;
}
}  // namespace

void ObjectMapper::restore_state(std::string_view bytes, const std::filesystem::path& path) {
  const MapperSection saved = read_mapper_section(bytes, path);
  map_.decode_state(saved.map_bytes, path);
  step_ = saved.step;
}

namespace {
std::vector<uint32_t> ids_of(const std::vector<ObjectInstance>& instances) {
  std::vector<uint32_t> ids;
  for (const ObjectInstance& inst : instances) ids.push_back(inst.id);
  return ids;
}
}  // namespace

void ObjectMapper::restore_views(std::string_view bytes, const std::filesystem::path& path) {
  best_views_.decode(bytes, path, ids_of(map_.instances()));
}

ObjectMapMergeCounts ObjectMapper::merge_state(std::string_view bytes, const std::filesystem::path& path,
                                               const Eigen::Isometry3f& T_this_other, const std::string* views_bytes) {
  ObjectMap other(config_);
  other.decode_state(read_mapper_section(bytes, path).map_bytes, path);
  BestViews other_views(best_views_.camera());
  if (views_bytes) other_views.decode(*views_bytes, path, ids_of(other.instances()));
  ObjectMapMergeCounts counts = map_.merge_map(other, T_this_other);
  if (views_bytes) best_views_.merge(other_views, counts.ids);
  return counts;
}

}  // namespace semap
