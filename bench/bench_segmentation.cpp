// Segmentation benchmark (issue 5): ms per frame of each model on 2 cores, and Soft-NMS vs
// hard NMS recall (instances at mask IoU 0.5) on synthetic side-by-side objects (emulated
// candidates from ground truth, and the real YOLO on the renders) and on real frames.
// Prints one JSON object. Usage: bench_segmentation [frames_per_model=20] [synth_frames=12]
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/paths.hpp"
#include "segmentation/nms_evaluation.hpp"
#include "segmentation/semantic_segmenter.hpp"
#include "segmentation/yolo_segmenter.hpp"
#include "synth/renderer.hpp"
#include "synth/scene.hpp"
#include "synth/trajectory.hpp"

using namespace semap;
using Clock = std::chrono::steady_clock;

namespace {

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

nlohmann::json time_stats(std::vector<double> ms) {
  std::sort(ms.begin(), ms.end());
  double sum = 0;
  for (double m : ms) sum += m;
  return {{"runs", ms.size()}, {"mean_ms", sum / ms.size()}, {"median_ms", ms[ms.size() / 2]},
          {"min_ms", ms.front()}, {"max_ms", ms.back()}};
}

std::vector<cv::Mat> real_frames(const std::filesystem::path& data) {
  std::vector<cv::Mat> frames;
  for (int i = 1; i <= 10; ++i) {
    cv::Mat m = cv::imread((data / "ycb_video_0000/data/0000" / cv::format("%06d-color.png", i)).string());
    if (!m.empty()) frames.push_back(m);
  }
  for (int i : {0, 200, 400}) {
    cv::Mat m = cv::imread((data / "7scenes_redkitchen" / cv::format("frame-%06d.color.jpg", i)).string());
    if (!m.empty()) frames.push_back(m);
  }
  return frames;
}

}  // namespace

int main(int argc, char** argv) {
  const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 20;
  const int synth_frames = argc > 2 ? std::max(1, std::atoi(argv[2])) : 12;
  cv::setNumThreads(2);
  const auto models = semap::models_dir(std::filesystem::path(SEMAP_SHARED_DIR) / "models");
  const auto data = semap::data_dir(std::filesystem::path(SEMAP_SHARED_DIR) / "data");
  nlohmann::json out;
  out["threads"] = cv::getNumThreads();
  const std::vector<cv::Mat> frames = real_frames(data);
  out["real_frames"] = frames.size();

  SegmentationConfig config;
  // --- Timing: YOLO-seg (network + decode split) and DeepLab.
  const auto yolo_path = models / "yolov8n-seg-320.onnx";
  const auto deeplab_path = models / "deeplabv3-mnv2-voc-257.onnx";
  if (std::filesystem::exists(yolo_path) && !frames.empty()) {
    YoloSegmenter yolo(yolo_path, config);
    yolo.segment_image(frames[0]);  // warm-up
    std::vector<double> total, net, dec;
    for (int r = 0; r < runs; ++r) {
      const cv::Mat& img = frames[r % frames.size()];
      const auto t0 = Clock::now();
      const auto cand = yolo.run_network(img);
      const double t_net = ms_since(t0);
      const auto t1 = Clock::now();
      yolo.decode(cand);
      dec.push_back(ms_since(t1));
      net.push_back(t_net);
      total.push_back(ms_since(t0));
    }
    out["yolov8n_seg_320"] = {{"model", yolo_path.string()},
                              {"input", {yolo.input_size().width, yolo.input_size().height}},
                              {"image", {frames[0].cols, frames[0].rows}},
                              {"total", time_stats(total)},
                              {"network", time_stats(net)},
                              {"decode_nms_masks", time_stats(dec)}};
  }
  if (std::filesystem::exists(deeplab_path) && !frames.empty()) {
    for (bool probs : {true, false}) {
      SegmentationConfig c = config;
      c.semantic.probabilities = probs;
      SemanticSegmenter deeplab(deeplab_path, c);
      deeplab.segment_image(frames[0]);
      std::vector<double> total;
      for (int r = 0; r < runs; ++r) {
        const auto t0 = Clock::now();
        deeplab.segment_image(frames[r % frames.size()]);
        total.push_back(ms_since(t0));
      }
      out[probs ? "deeplabv3_mnv2_257_with_probabilities" : "deeplabv3_mnv2_257_labels_only"] = {
          {"model", deeplab_path.string()}, {"total", time_stats(total)}};
    }
  }

  // --- Soft vs hard NMS on synthetic renders (touching chairs / boxes, objects on the table).
  const SyntheticScene scene = make_scene(1, 12);
  const PinholeIntrinsics k = synth_intrinsics(640, 480);
  RecallFigures gt_hard, gt_soft, yolo_hard, yolo_soft;
  std::unique_ptr<YoloSegmenter> yolo_soft_seg, yolo_hard_seg;
  if (std::filesystem::exists(yolo_path)) {
    SegmentationConfig soft = config, hard = config;
    hard.yolo.nms = NmsMethod::hard;
    yolo_soft_seg = std::make_unique<YoloSegmenter>(yolo_path, soft);
    yolo_hard_seg = std::make_unique<YoloSegmenter>(yolo_path, hard);
  }
  const JitterCandidateParams jp;
  for (int i = 0; i < synth_frames; ++i) {
    const RenderedFrame f = render(scene, loop_pose(scene.room.size, i * 300 / synth_frames, 300), k);
    JitterCandidateParams p = jp;
    p.seed = 100 + i;
    const CandidateSet c = jittered_candidates(f.labels, f.instances, p);
    auto masks_of = [&](const std::vector<NmsResult>& kept) {
      std::vector<cv::Mat> m;
      for (const auto& r : kept) m.push_back(c.masks[r.index]);
      return m;
    };
    gt_hard += match_masks(f.instances, masks_of(hard_nms(c.boxes, config.yolo.nms_iou, false, 100)), p.min_pixels);
    gt_soft += match_masks(f.instances,
                           masks_of(soft_nms(c.boxes, config.yolo.soft_nms_sigma, config.yolo.score_floor, false, 100)),
                           p.min_pixels);
    if (yolo_soft_seg) {
      auto masks_of_result = [](const SegmentationResult& r) {
        std::vector<cv::Mat> m;
        for (const auto& inst : r.instances) m.push_back(inst.mask);
        return m;
      };
      const auto cand = yolo_soft_seg->run_network(f.rgb);
      yolo_soft += match_masks(f.instances, masks_of_result(yolo_soft_seg->decode(cand)), p.min_pixels);
      yolo_hard += match_masks(f.instances, masks_of_result(yolo_hard_seg->decode(cand)), p.min_pixels);
    }
  }
  auto fig = [](const RecallFigures& r) {
    return nlohmann::json{{"ground_truth", r.ground_truth}, {"matched", r.matched}, {"kept", r.kept},
                          {"recall", r.recall()}, {"precision", r.precision()}};
  };
  out["synthetic_nms"] = {{"frames", synth_frames},
                          {"emulated_candidates", {{"hard", fig(gt_hard)}, {"soft", fig(gt_soft)}}},
                          {"yolo_on_renders", {{"hard", fig(yolo_hard)}, {"soft", fig(yolo_soft)}}}};
  // --- Real frames: instance counts with hard vs soft on the same candidates.
  if (yolo_soft_seg && !frames.empty()) {
    nlohmann::json real = nlohmann::json::array();
    for (size_t i = 0; i < frames.size(); ++i) {
      const auto cand = yolo_soft_seg->run_network(frames[i]);
      auto names = [](const SegmentationResult& r) {
        std::vector<std::string> n;
        for (const auto& inst : r.instances) n.push_back(std::string(class_name(inst.class_id)));
        return n;
      };
      real.push_back({{"frame", i}, {"hard", names(yolo_hard_seg->decode(cand))}, {"soft", names(yolo_soft_seg->decode(cand))}});
    }
    out["real_nms_instances"] = real;
  }
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
