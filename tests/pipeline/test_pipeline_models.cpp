// `semap run` with the network segmenters on real frames (issue 5's "semap run can use
// --segmenter yolo:PATH / semantic:PATH"): 7-Scenes redkitchen, ground-truth poses, the test
// models from ../shared/models. The kitchen has a dining table and chairs in view from frame 0:
// both must reach the labelled mesh, and YOLO's instances the object map.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "semap/core/labels.hpp"
#include "core/progress.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

size_t vertices_labelled(const TriangleMesh& mesh, Label label) {
  size_t n = 0;
  for (const ClassId c : mesh.vertices.labels) n += c == id(label);
  return n;
}

RunResult run_with(const std::filesystem::path& dataset, const std::filesystem::path& out, const std::string& segmenter) {
  Progress::set_mode(-1);
  SemapConfig config;
  config.tsdf.voxel_size = 0.03;
  RunOptions o;
  o.dataset = dataset;
  o.out_dir = out;
  o.poses = PoseSource::groundtruth;
  o.segmenter = segmenter;
  o.max_frames = 40;
  o.show_progress = false;
  config.pipeline.threads = 1;  // every requested frame is segmented (no drops)
  return run_pipeline(o, config);
}

TEST(PipelineModels, YoloSegmenterLabelsTableAndChairsAndMapsThem) {
  SEMAP_REQUIRE_DATA(kitchen, "7scenes_redkitchen");
  SEMAP_REQUIRE_MODEL(model, "yolov8n-seg-320.onnx");
  test::TempDir out("semap_pipeline_yolo");
  const RunResult result = run_with(kitchen, out.path(), "yolo:" + model.string());
  EXPECT_GE(result.mapper.segmented_frames, 8u);
  const TriangleMesh mesh = read_ply(out / "mesh.ply");
  std::printf("yolo: %zu table, %zu chair vertices of %zu; objects %s\n", vertices_labelled(mesh, Label::kTable),
              vertices_labelled(mesh, Label::kChair), mesh.vertices.size(),
              nlohmann::json(result.objects_per_class).dump().c_str());
  EXPECT_GT(vertices_labelled(mesh, Label::kTable), 200u);
  EXPECT_GT(vertices_labelled(mesh, Label::kChair), 100u);
  const auto count = [&](const char* name) {
    const auto it = result.objects_per_class.find(name);
    return it == result.objects_per_class.end() ? 0 : it->second;
  };
  EXPECT_GE(count("table"), 1);
  EXPECT_GE(count("chair"), 1);
}

TEST(PipelineModels, SemanticSegmenterLabelsTableAndChairs) {
  SEMAP_REQUIRE_DATA(kitchen, "7scenes_redkitchen");
  SEMAP_REQUIRE_MODEL(model, "deeplabv3-mnv2-voc-257.onnx");
  test::TempDir out("semap_pipeline_semantic");
  const RunResult result = run_with(kitchen, out.path(), "semantic:" + model.string());
  EXPECT_GE(result.mapper.segmented_frames, 8u);
  const TriangleMesh mesh = read_ply(out / "mesh.ply");
  std::printf("semantic: %zu table, %zu chair vertices of %zu\n", vertices_labelled(mesh, Label::kTable),
              vertices_labelled(mesh, Label::kChair), mesh.vertices.size());
  EXPECT_GT(vertices_labelled(mesh, Label::kTable) + vertices_labelled(mesh, Label::kChair), 200u);
}

// The product's default shape on real frames, small enough for ThreadSanitizer
// (scripts/ci-sanitize.sh): threaded stages, tracking with its loop-closure worker, YOLO on
// its own thread with the default schedule (every 5th frame and keyframes).
TEST(PipelineModels, ThreadedTrackedRunWithYolo) {
  SEMAP_REQUIRE_DATA(kitchen, "7scenes_redkitchen");
  SEMAP_REQUIRE_MODEL(model, "yolov8n-seg-320.onnx");
  test::TempDir out("semap_pipeline_threaded_yolo");
  Progress::set_mode(-1);
  SemapConfig config;
  config.tsdf.voxel_size = 0.04;
  config.pipeline.threads = 2;
  config.tracking.background_loop_closure = true;
  RunOptions o;
  o.dataset = kitchen;
  o.out_dir = out.path();
  o.poses = PoseSource::track;
  o.segmenter = "yolo:" + model.string();
  o.max_frames = 30;
  o.show_progress = false;
  const RunResult result = run_pipeline(o, config);
  ASSERT_TRUE(result.evaluation.ate);
  std::printf("threaded yolo: ATE %.2f cm, %zu segmented, %zu dropped, %zu fused, %zu objects\n",
              result.evaluation.ate->rmse * 100, result.mapper.segmented_frames, result.mapper.segmentations_dropped,
              result.mapper.frames_fused, result.mapper.objects);
  EXPECT_LE(result.evaluation.ate->rmse, 0.05);
  EXPECT_GE(result.mapper.segmented_frames, 4u);
  EXPECT_EQ(result.mapper.frames_fused + result.mapper.lost_frames, 30u);
  EXPECT_GE(result.mapper.objects, 1u);
}

}  // namespace
}  // namespace semap
