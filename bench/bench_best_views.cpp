// What keeping each object's best view costs (issue 43, objects/best_views.hpp). Prints JSON:
//  - vs_live_objects: ms per keyframe of BestViews::update against the number of live objects,
//    all in view (the worst case: every object scored): scoring alone (a repeated frame, no view
//    replaced) and scoring + JPEG encoding (a fresh BestViews, every view replaced); bytes per view.
//  - sequence: on a synthetic recording with ground-truth poses and masks, the object stage per
//    keyframe (C2 segmentation, C4-C5 association, best views) and the views' share of it (the
//    baseline: the same stage's other steps, same run); the views' bytes per object, their
//    map.semap section (stored, compressed) against the whole map.semap of a Mapper on the same
//    frames.
//   bench_best_views [--frames N] [--step K] [--repeats R] [--out DIR]
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <random>

#include "bench/bench_options.hpp"
#include "core/archive.hpp"
#include "objects/best_views.hpp"
#include "objects/object_mapper.hpp"
#include "semap/io/dataset.hpp"
#include "semap/mapper.hpp"
#include "synth/synth_config.hpp"

using namespace semap;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

PinholeIntrinsics vga_camera() {
  PinholeIntrinsics c;
  c.fx = c.fy = 525.0;
  c.cx = 319.5;
  c.cy = 239.5;
  c.width = 640;
  c.height = 480;
  return c;
}

/// A wall 2 m ahead (identity pose) with a random texture (JPEG's hard case), and `n` objects:
/// 0.25 m squares of 2,500 points each on the wall, spread over the image.
struct Scene {
  Frame frame;
  std::vector<ObjectInstance> objects;
};

Scene scene_with(size_t n, const PinholeIntrinsics& camera, std::mt19937& rng) {
  Scene s;
  s.frame.depth = cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  s.frame.rgb = cv::Mat(camera.height, camera.width, CV_8UC3);
  cv::randu(s.frame.rgb, cv::Scalar::all(0), cv::Scalar::all(255));
  const double half_w = 2.0 * (camera.width / 2.0 - 40) / camera.fx, half_h = 2.0 * (camera.height / 2.0 - 40) / camera.fy;
  std::uniform_real_distribution<float> x(-half_w, half_w), y(-half_h, half_h);
  for (size_t i = 0; i < n; ++i) {
    ObjectInstance o;
    o.id = static_cast<uint32_t>(i + 1);
    const float cx = x(rng), cy = y(rng);
    for (int a = 0; a < 50; ++a)
      for (int b = 0; b < 50; ++b) o.points.emplace_back(cx - 0.125f + 0.005f * a, cy - 0.125f + 0.005f * b, 2.0f);
    s.objects.push_back(std::move(o));
  }
  return s;
}

nlohmann::json vs_live_objects(int repeats) {
  const PinholeIntrinsics camera = vga_camera();
  std::mt19937 rng(3);
  nlohmann::json rows = nlohmann::json::array();
  for (const size_t n : {10, 50, 100, 200, 500}) {
    const Scene scene = scene_with(n, camera, rng);
    double encode_ms = 0, score_ms = 0;
    size_t bytes = 0, views = 0;
    for (int r = 0; r < repeats; ++r) {
      BestViews fresh(camera);
      auto t0 = Clock::now();
      fresh.update(scene.objects, scene.frame, Pose::Identity());  // every view new: scored and encoded
      encode_ms += ms_since(t0);
      t0 = Clock::now();
      fresh.update(scene.objects, scene.frame, Pose::Identity());  // the same views: scored, none replaced
      score_ms += ms_since(t0);
      bytes = fresh.bytes(), views = fresh.size();
    }
    rows.push_back({{"live_objects", n},
                    {"score_only_ms_per_keyframe", score_ms / repeats},
                    {"score_and_encode_all_ms_per_keyframe", encode_ms / repeats},
                    {"encode_ms_per_view", (encode_ms - score_ms) / repeats / std::max<size_t>(1, views)},
                    {"views", views},
                    {"bytes_per_view", double(bytes) / std::max<size_t>(1, views)}});
  }
  return rows;
}

/// The object stage alone (ObjectMapper, as the Mapper's object thread runs it) on every
/// step-th frame with its ground-truth masks and pose.
nlohmann::json object_stage(const DatasetReader& reader, size_t step) {
  ObjectMapper mapper(ObjectsConfig{}, reader.camera());
  for (size_t i = 0; i < reader.size(); i += step) {
    const Frame frame = reader.load(i);
    mapper.process(frame, segmentation_from_label_images(frame.labels, frame.instances), *frame.gt_T_world_camera);
  }
  mapper.finish();
  const ObjectMapperTimings& t = mapper.timings();
  const double k = static_cast<double>(std::max<size_t>(1, t.frames));
  const double stage_ms = t.segmentation_ms + t.association_ms + t.best_views_ms;
  const BestViews& views = mapper.best_views();
  return {{"keyframes", t.frames},
          {"segmentation_ms_per_keyframe", t.segmentation_ms / k},
          {"association_ms_per_keyframe", t.association_ms / k},
          {"best_views_ms_per_keyframe", t.best_views_ms / k},
          {"best_views_share_of_object_stage", t.best_views_ms / std::max(1e-9, stage_ms)},
          {"live_objects", mapper.instances().size()},
          {"objects_with_view", views.size()},
          {"view_bytes_per_object", double(views.bytes()) / std::max<size_t>(1, views.size())}};
}

/// A whole Mapper on the same frames (given poses and masks), saved: the views' part of map.semap.
nlohmann::json map_file(const DatasetReader& reader, size_t step, const fs::path& out) {
  SemapConfig config;
  config.pipeline.threads = 1;
  Mapper mapper(config, reader.camera());
  for (size_t i = 0; i < reader.size(); i += step) {
    const Frame frame = reader.load(i);
    FrameHints hints;
    hints.T_world_camera = frame.gt_T_world_camera;
    hints.segmentation = segmentation_from_label_images(frame.labels, frame.instances);
    mapper.add_frame(frame, hints);
  }
  mapper.finish();
  mapper.save(out / "map.semap");
  const ArchiveSections sections = read_map_archive(out / "map.semap");
  write_map_archive(out / "views_only.semap", {{kObjectViewsSection, sections.at(kObjectViewsSection)}});
  write_map_archive(out / "empty.semap", {});
  const double stored = double(fs::file_size(out / "views_only.semap") - fs::file_size(out / "empty.semap"));
  return {{"frames", mapper.stats().frames},
          {"objects", mapper.stats().objects},
          {"map_semap_bytes", fs::file_size(out / "map.semap")},
          {"views_section_bytes", sections.at(kObjectViewsSection).size()},
          {"views_section_stored_bytes", stored},
          {"views_share_of_map_semap", stored / double(fs::file_size(out / "map.semap"))}};
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 100, step = 2, repeats = 5;
  fs::path out = fs::temp_directory_path() / "semap_bench_best_views";
  const auto exit_code = bench::parse_options(argc, argv, 1, "[--frames N] [--step K] [--repeats R] [--out DIR]",
                                              [&](const std::string& key, const std::string& v) {
                                                if (key == "--frames") frames = std::stoi(v);
                                                else if (key == "--step") step = std::stoi(v);
                                                else if (key == "--repeats") repeats = std::stoi(v);
                                                else if (key == "--out") out = v;
                                                else return false;
                                                return true;
                                              });
  if (exit_code) return *exit_code;
  if (frames < 1 || step < 1 || repeats < 1) {
    std::cerr << "bench_best_views: --frames, --step and --repeats must be at least 1\n";
    return 2;
  }
  nlohmann::json report;
  report["vs_live_objects"] = vs_live_objects(repeats);
  fs::remove_all(out);
  SynthConfig synth;
  synth.frames = frames;
  synth.seed = 1;
  synth.objects = 10;
  generate_dataset(synth, out / "dataset");
  const auto reader = open_dataset(out / "dataset");
  report["sequence"] = object_stage(*reader, static_cast<size_t>(step));
  report["sequence"]["image"] = std::to_string(synth.width) + "x" + std::to_string(synth.height);
  report["map_semap"] = map_file(*reader, static_cast<size_t>(step), out);
  double load[1] = {0};
  if (getloadavg(load, 1) == 1) report["load_average_1min"] = load[0];
  fs::remove_all(out);
  std::cout << report.dump(2) << std::endl;
  return 0;
}
