// The `semap segment` CLI. (The segmentation hand-off of the pipeline: tests/pipeline/test_segmentation_schedule.)
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "semap/core/error.hpp"
#include "semap/core/labels.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

TEST(SegmentCli, WritesFourFilesPerImageAndFailsCleanly) {
  SEMAP_REQUIRE_MODEL(model, "yolov8n-seg-320.onnx");
  SEMAP_REQUIRE_DATA(root, "ycb_video_0000");
  ASSERT_TRUE(std::filesystem::exists(test::semap_executable())) << "semap not built";
  test::TempDir out;
  const auto image = root / "data/0000/000001-color.png";
  const auto r = test::run_command(test::semap_executable().string() + " segment " + image.string() +
                                   " --model yolo:" + model.string() + " --out " + out.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* ext : {".label.png", ".instances.png", ".json", ".overlay.png"})
    EXPECT_TRUE(std::filesystem::exists(out / (std::string("000001-color") + ext))) << ext;
  const cv::Mat label = cv::imread((out / "000001-color.label.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(label.type(), CV_16UC1);
  EXPECT_GT(cv::countNonZero(label == id(Label::kCup)), 1000);
  std::ifstream in(out / "000001-color.json");
  const auto j = nlohmann::json::parse(in);
  bool cup = false;
  for (const auto& inst : j.at("instances")) {
    cup |= inst.at("class") == "cup";
    EXPECT_EQ(inst.at("box").size(), 4u);
    EXPECT_TRUE(inst.contains("score") && inst.contains("class_id") && inst.contains("id"));
  }
  EXPECT_TRUE(cup);
  const auto bad = test::run_command(test::semap_executable().string() + " segment " + image.string() +
                                     " --model yolo:/nonexistent/m.onnx --out " + out.path().string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("/nonexistent/m.onnx"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace semap
