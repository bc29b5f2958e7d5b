// Object map speed (issue 6): ms per keyframe for segmentation-to-segments (METHODS.md C2,
// supervoxel-guided and mask back-projection) and for association + optimisation (C4-C5) on
// a synthetic sequence, and association time against the number of map instances. Prints JSON.
//   bench_objects [--frames N] [--step K] [--out DIR]
//   bench_objects --real DATASET --model yolo:PATH|groundtruth [--step K] [--out DIR] [--config C.yaml]
//     (real data: ground-truth poses of the dataset, the network's instances; writes DIR/objects.json
//     and prints the objects; C.yaml is a semap config, its objects section applies)
#include <chrono>
#include <ctime>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "bench/bench_options.hpp"
#include "semap/io/dataset.hpp"
#include "semap/pipeline/outputs.hpp"
#include "semap/pipeline/semap_config.hpp"
#include "semap/segmentation/segmenter_factory.hpp"
#include "objects/object_mapper.hpp"
#include "synth/synth_config.hpp"

using namespace semap;
using Clock = std::chrono::steady_clock;

namespace {
double ms(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

SegmentationResult gt_segmentation(const Frame& frame) {
  SegmentationResult seg;
  double max_id = 0;
  cv::minMaxLoc(frame.instances, nullptr, &max_id);
  for (int inst = 1; inst <= static_cast<int>(max_id); ++inst) {
    InstanceDetection det;
    cv::compare(frame.instances, inst, det.mask, cv::CMP_EQ);
    if (cv::countNonZero(det.mask) == 0) continue;
    std::vector<int> votes(kNumClasses, 0);
    for (int v = 0; v < frame.labels.rows; ++v)
      for (int u = 0; u < frame.labels.cols; ++u)
        if (det.mask.at<uint8_t>(v, u)) ++votes[frame.labels.at<uint8_t>(v, u)];
    votes[0] = 0;
    det.class_id = static_cast<ClassId>(std::max_element(votes.begin(), votes.end()) - votes.begin());
    det.score = 1.f;
    det.id = static_cast<uint16_t>(seg.instances.size() + 1);
    seg.instances.push_back(std::move(det));
  }
  return seg;
}

ObjectSegment random_box_segment(std::mt19937& rng, const Eigen::Vector3f& centre, ClassId cls) {
  std::uniform_real_distribution<float> u(-0.1f, 0.1f);
  ObjectSegment s;
  for (int i = 0; i < 1500; ++i) s.points.push_back(centre + Eigen::Vector3f(u(rng), u(rng), u(rng)));
  s.colours.assign(s.points.size(), Rgb8{});
  s.class_id = cls;
  s.score = 1.f;
  s.class_scores.assign(kNumClasses, 0.0);
  s.class_scores[cls] = 1.0;
  return s;
}
// Top-down picture (world x-y) of the object points coloured by class, with each object's
// axis-aligned footprint, id and class.
void write_topdown(const ObjectMapper& mapper, const std::filesystem::path& path) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e9f), hi = -lo;
  for (const auto& inst : mapper.instances())
    for (const auto& p : inst.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  if (lo.x() > hi.x()) return;
  const float scale = 800.f / std::max(hi.x() - lo.x(), hi.y() - lo.y());
  cv::Mat image(static_cast<int>((hi.y() - lo.y()) * scale) + 40, static_cast<int>((hi.x() - lo.x()) * scale) + 40,
                CV_8UC3, cv::Scalar(255, 255, 255));
  auto px = [&](const Eigen::Vector3f& p) {
    return cv::Point(static_cast<int>((p.x() - lo.x()) * scale) + 20, static_cast<int>((hi.y() - p.y()) * scale) + 20);
  };
  for (const auto& inst : mapper.instances()) {
    const Rgb8 c = class_colour(inst.class_id());
    for (const auto& p : inst.points) cv::circle(image, px(p), 1, cv::Scalar(c.b, c.g, c.r), -1);
  }
  for (const auto& inst : mapper.instances()) {
    Eigen::Vector3f box_lo = Eigen::Vector3f::Constant(1e9f), box_hi = -box_lo;
    for (const auto& p : inst.points) box_lo = box_lo.cwiseMin(p), box_hi = box_hi.cwiseMax(p);
    cv::rectangle(image, px(box_lo), px(box_hi), cv::Scalar(0, 0, 0), 1);
    const Eigen::Vector3f centre = inst.centroid();
    cv::putText(image, std::to_string(inst.id) + " " + std::string(class_name(inst.class_id())), px(centre),
                cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1);
  }
  cv::imwrite(path.string(), image);
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 100, step = 2;
  std::string real_dataset, model, config_path;
  std::filesystem::path out = std::filesystem::temp_directory_path() / "semap_bench_objects";
  const auto exit_code = bench::parse_options(
      argc, argv, 1,
      "[--frames N] [--step K] [--out DIR]\n"
      "       --real DATASET --model yolo:PATH|groundtruth [--step K] [--out DIR] [--config C.yaml]",
      [&](const std::string& key, const std::string& v) {
        if (key == "--frames") frames = std::stoi(v);
        else if (key == "--step") step = std::stoi(v);
        else if (key == "--out") out = v;
        else if (key == "--real") real_dataset = v;
        else if (key == "--model") model = v;
        else if (key == "--config") config_path = v;
        else return false;
        return true;
      });
  if (exit_code) return *exit_code;
  if (!real_dataset.empty()) {
    const auto reader = open_dataset(real_dataset);
    SegmentationConfig seg_config;
    auto segmenter = make_segmenter(model, seg_config, reader->camera());
    ObjectsConfig config;
    config.optimise_every = 10;  // keyframes, not frames
    if (!config_path.empty()) config = load_semap_config(config_path).objects;
    if (const char* mode = std::getenv("SEMAP_OBJECTS_MODE"))
      config.segmentation_mode = std::string_view(mode) == "backprojection" ? SegmentationMode::backprojection
                                                                           : SegmentationMode::supervoxel;
    ObjectMapper mapper(config, reader->camera());
    double network_ms = 0;
    nlohmann::json summary_pre;
    std::map<std::string, int> detections;
    size_t mask_pixels = 0;
    std::string mask_size;
    for (size_t i = 0; i < reader->size(); i += step) {
      const Frame frame = reader->load(i);
      if (!frame.gt_T_world_camera) continue;
      const auto t0 = Clock::now();
      const SegmentationResult seg = segmenter->segment(frame);
      network_ms += ms(t0, Clock::now());
      for (const auto& det : seg.instances) {
        ++detections[std::string(class_name(det.class_id))];
        mask_pixels += det.mask.empty() ? 0 : cv::countNonZero(det.mask);
        if (!det.mask.empty()) mask_size = std::to_string(det.mask.cols) + "x" + std::to_string(det.mask.rows);
      }
      mapper.process(frame, seg, *frame.gt_T_world_camera);
    }
    summary_pre["instances_before_finish"] = mapper.instances().size();
    mapper.finish();
    write_objects(mapper.summaries(), out);
    nlohmann::json summary = summary_pre;
    summary["keyframes"] = mapper.timings().frames;
    summary["network_ms_per_keyframe"] = network_ms / std::max<size_t>(1, mapper.timings().frames);
    summary["segmentation_ms_per_keyframe"] = mapper.timings().segmentation_ms / std::max<size_t>(1, mapper.timings().frames);
    summary["association_ms_per_keyframe"] = mapper.timings().association_ms / std::max<size_t>(1, mapper.timings().frames);
    std::map<std::string, int> per_class;
    const nlohmann::json doc = mapper.to_json();
    for (const auto& o : doc["objects"]) {
      ++per_class[o["class"].get<std::string>()];
      summary["objects"].push_back({{"id", o["id"]}, {"class", o["class"]}, {"n", o["n"]}, {"state", o["state"]},
                                    {"centroid", o["centroid"]}, {"extent", o["obb"]["extent"]}});
    }
    summary["per_class"] = per_class;
    summary["topdown_png"] = (out / "objects_topdown.png").string();
    write_topdown(mapper, out / "objects_topdown.png");
    summary["detections_per_class"] = detections;
    summary["mask_pixels"] = mask_pixels;
    summary["mask_size"] = mask_size;
    std::cout << summary.dump(2) << std::endl;
    return 0;
  }
  nlohmann::json report;
  SynthConfig synth;
  synth.frames = frames;
  synth.seed = 1;
  synth.objects = 10;
  std::filesystem::remove_all(out);
  generate_dataset(synth, out);
  const auto reader = open_dataset(out);
  std::vector<Frame> keyframes;
  std::vector<SegmentationResult> segs;
  for (size_t i = 0; i < reader->size(); i += step) {
    keyframes.push_back(reader->load(i));
    segs.push_back(gt_segmentation(keyframes.back()));
  }
  for (const SegmentationMode mode_value : {SegmentationMode::supervoxel, SegmentationMode::backprojection}) {
    const std::string mode(enum_name(kSegmentationModeNames, mode_value));
    ObjectsConfig config;
    config.segmentation_mode = mode_value;
    ObjectMapper mapper(config, reader->camera());
    const std::clock_t cpu0 = std::clock();
    for (size_t k = 0; k < keyframes.size(); ++k) mapper.process(keyframes[k], segs[k], *keyframes[k].gt_T_world_camera);
    mapper.finish();
    const double cpu_ms_per_keyframe = 1000.0 * (std::clock() - cpu0) / CLOCKS_PER_SEC / keyframes.size();
    const auto& t = mapper.timings();
    report["per_keyframe"][mode] = {{"keyframes", t.frames},
                                    {"image", std::to_string(synth.width) + "x" + std::to_string(synth.height)},
                                    {"pixel_stride", config.pixel_stride},
                                    {"segmentation_ms", t.segmentation_ms / t.frames},
                                    {"association_optimisation_ms", t.association_ms / t.frames},
                                    {"process_cpu_ms_total_per_keyframe", cpu_ms_per_keyframe},
                                    {"instances", mapper.instances().size()}};
  }
  {
    double load[1] = {0};
    if (getloadavg(load, 1) == 1) report["load_average_1min"] = load[0];
  }
  // Association time vs number of instances: N boxes on a grid, one frame of 10 segments.
  std::mt19937 rng(7);
  for (int n : {10, 50, 100, 200, 500, 1000}) {
    ObjectsConfig config;
    ObjectMap map(config);
    const int side = static_cast<int>(std::ceil(std::sqrt(n)));
    std::vector<ObjectSegment> seed_segments;
    for (int i = 0; i < n; ++i)
      seed_segments.push_back(random_box_segment(rng, Eigen::Vector3f(0.5f * (i % side), 0.5f * (i / side), 0), id(Label::kCup)));
    map.associate(seed_segments, 0, 1);
    std::vector<ObjectSegment> frame;
    for (int i = 0; i < 10; ++i) {
      const int target = (i * 97) % n;
      frame.push_back(random_box_segment(rng, Eigen::Vector3f(0.5f * (target % side), 0.5f * (target / side), 0) +
                                                  Eigen::Vector3f(0.01f, 0, 0),
                                         id(Label::kCup)));
    }
    const int repeats = 5;
    const auto t0 = Clock::now();
    for (int r = 0; r < repeats; ++r) map.associate(frame, 1 + r, 2 + r);
    const auto t1 = Clock::now();
    map.optimise(10, false);
    const auto t2 = Clock::now();
    report["association_vs_instances"].push_back({{"instances", n},
                                                  {"segments_per_frame", frame.size()},
                                                  {"association_ms_per_frame", ms(t0, t1) / repeats},
                                                  {"optimisation_ms", ms(t1, t2)}});
  }
  std::filesystem::remove_all(out);
  std::cout << report.dump(2) << std::endl;
  return 0;
}
