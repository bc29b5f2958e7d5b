#include "pipeline/map_archive.hpp"

#include "core/archive.hpp"
#include "semap/io/config_loader.hpp"

namespace semap {
namespace {

void put_intrinsics(ByteWriter& w, const PinholeIntrinsics& k) {
  w.put(k.fx), w.put(k.fy), w.put(k.cx), w.put(k.cy);
  w.put(static_cast<int32_t>(k.width)), w.put(static_cast<int32_t>(k.height));
}

PinholeIntrinsics get_intrinsics(ByteReader& r) {
  PinholeIntrinsics k;
  k.fx = r.get<double>(), k.fy = r.get<double>(), k.cx = r.get<double>(), k.cy = r.get<double>();
  k.width = r.get<int32_t>(), k.height = r.get<int32_t>();
  return k;
}

}  // namespace

std::string encode_camera_section(const CameraModel& camera) {
  ByteWriter w;
  put_intrinsics(w, camera.depth);
  w.put(camera.depth_scale);
  w.put_bytes(camera.distortion.data(), camera.distortion.size() * sizeof(double));
  w.put(static_cast<uint8_t>(camera.colour.has_value()));
  if (camera.colour) {
    put_intrinsics(w, camera.colour->intrinsics);
    w.put_bytes(camera.colour->T_depth_colour.matrix().data(), 16 * sizeof(double));
  }
  return std::move(w.bytes());
}

CameraModel decode_camera_section(std::string_view bytes, const std::filesystem::path& path) {
  ByteReader r(bytes, path, kCameraSection);
  CameraModel camera;
  camera.depth = get_intrinsics(r);
  camera.depth_scale = r.get<double>();
  r.read(camera.distortion.data(), camera.distortion.size() * sizeof(double));
  if (r.get<uint8_t>() != 0) {
    CameraModel::ColourCamera colour;
    colour.intrinsics = get_intrinsics(r);
    r.read(colour.T_depth_colour.matrix().data(), 16 * sizeof(double));
    camera.colour = colour;
  }
  r.expect_end();
  validate_camera(camera, path.string());
  return camera;
}

std::string encode_config_section(const SemapConfig& config) {
  SemapConfig copy = config;  // visit() takes a mutable visitor target
  return dump_config([&](ParamVisitor& v) { copy.visit(v); });
}

SemapConfig decode_config_section(const std::string& yaml, const std::filesystem::path& path) {
  SemapConfig config;
  load_config_string(yaml, path.string() + " (its configuration)", [&](ParamVisitor& v) { config.visit(v); });
  config.validate();
  return config;
}

void require_same_ferns(const TrackingConfig& saved, const TrackingConfig& given, const std::filesystem::path& path) {
  auto check = [&](const char* key, double a, double b) {
    if (a != b)
      throw Error(path, std::string("tracking.") + key + " is " + std::to_string(b) + " here but " + std::to_string(a) +
                            " in the saved map: its keyframes cannot be recognised (use the map's value)");
  };
  check("fern_count", saved.ferns.fern_count, given.ferns.fern_count);
  check("fern_tests", saved.ferns.fern_tests, given.ferns.fern_tests);
  check("fern_width", saved.ferns.width, given.ferns.width);
  check("fern_height", saved.ferns.height, given.ferns.height);
  check("seed", double(saved.seed), double(given.seed));
  check("min_depth", saved.min_depth, given.min_depth);
  check("max_depth", saved.max_depth, given.max_depth);
}

std::filesystem::path map_file_of(const std::filesystem::path& folder_or_file) {
  std::error_code ec;
  return std::filesystem::is_directory(folder_or_file, ec) ? folder_or_file / "map.semap" : folder_or_file;
}

}  // namespace semap
