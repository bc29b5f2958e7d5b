// Issue 44, class 4 and part of class 8, through the CLI: outputs never replace a file semap
// did not write, an output folder that is or holds an input is refused, `semap merge A A` is
// refused, options that cannot apply say so, and a folder or dangling symlink given for a file
// is named as what it is. Inputs are made here (one small `semap synth` dataset).
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include <opencv2/imgcodecs.hpp>

#include "io/output_folder.hpp"
#include "segmentation/groundtruth_segmenter.hpp"
#include "segmentation/segmentation_io.hpp"
#include "reliability/reliability_support.hpp"
#include "semap/pipeline/outputs.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::expect_one_line_error;
using test::run_semap;
using test::slurp;
using test::snapshot;
using test::spit;
using test::changes;

class OutputSafety : public test::CliSuite {
 protected:
  static void SetUpTestSuite() { make_suite("semap_output_safety"); }
};

TEST_F(OutputSafety, RunKeepsAUsersMeshAndWritesNothing) {
  const fs::path out = path("user_out");
  fs::create_directories(out);
  spit(out / "mesh.ply", "my own mesh");
  const auto before = snapshot(out);
  const auto r = run_semap(run_args(clean(), out));
  expect_one_line_error(r, {"mesh.ply", "not written by semap"});
  EXPECT_EQ(changes(before, snapshot(out)), "");
  EXPECT_EQ(slurp(out / "mesh.ply"), "my own mesh");
}

TEST_F(OutputSafety, RunRefusesTheDatasetOrAFolderHoldingItAsOut) {
  const fs::path data = copy("rec");
  fs::create_directory_symlink(data, path("rec_alias"));
  const auto before = snapshot(tmp_->path());
  for (const fs::path& out : {data, path("rec_alias"), tmp_->path()}) {
    const auto r = run_semap(run_args(data, out));
    expect_one_line_error(r, {out.string(), "input"});
  }
  EXPECT_EQ(changes(before, snapshot(tmp_->path())), "");
}

TEST_F(OutputSafety, MergeRefusesTheSameMapTwiceByAnyPath) {
  const fs::path map = path("map_a");
  ASSERT_EQ(run_semap(run_args(clean(), map)).exit_code, 0);
  // The files the run published at the top of its folder are those it checks before mapping.
  std::set<std::string> top_level;
  for (const std::string& file : OutputFolder::read_manifest(map, "run"))
    if (file.find('/') == std::string::npos) top_level.insert(file);
  EXPECT_EQ(top_level, std::set<std::string>(map_output_files().begin(), map_output_files().end()));
  fs::create_directory_symlink(map, path("map_alias"));
  for (const fs::path& other : {map, path("map_alias"), map / "map.semap"}) {
    const auto r = run_semap({"merge", map.string(), other.string(), "--out", path("merged").string()});
    expect_one_line_error(r, {"same map"});
  }
  EXPECT_FALSE(fs::exists(path("merged") / "map.semap"));
  // --resume: the saved map's folder is an input as well, also as the --out of `semap run`.
  const auto before = snapshot(map);
  const auto r = run_semap(run_args(clean(), path("map_alias"), {"--resume", map.string()}));
  expect_one_line_error(r, {"input"});
  EXPECT_EQ(changes(before, snapshot(map)), "");
}

TEST_F(OutputSafety, IgnoredOptionsAndWrongKindsOfPathSaySo) {
  // --rgb-topic on a folder: an error, not silently ignored.
  auto r = run_semap(run_args(clean(), path("topic_out"), {"--rgb-topic", "/camera/rgb"}));
  expect_one_line_error(r, {"--rgb-topic", "ROS bags only"});
  // A dangling symlink or a folder where a file is expected: named as what it is.
  fs::create_symlink(path("nowhere.bag"), path("dangling.bag"));
  r = run_semap(run_args(path("dangling.bag"), path("dangling_out")));
  expect_one_line_error(r, {"dangling.bag", "dangling symlink"});
  fs::create_directories(path("folder.bag"));
  r = run_semap(run_args(path("folder.bag"), path("folder_out")));
  expect_one_line_error(r, {"folder.bag", "is a folder"});
  r = run_semap({"merge", path("dangling.bag").string(), clean().string(), "--out", path("m").string()});
  expect_one_line_error(r, {"dangling.bag", "dangling symlink"});
  // Issue 44 (third round): `semap query OUT --class chiar` (misspelt) matched nothing and exited
  // 0; a class name the project does not know is an error, for --class and --near.
  for (const char* option : {"--class", "--near"}) {
    r = run_semap({"query", path("no_run").string(), option, "chiar"});
    expect_one_line_error(r, {option, "'chiar' is not a class name"});
  }
  r = run_semap({"query", path("no_run").string(), "--class", "chair"});  // known: on to the folder
  expect_one_line_error(r, {"no_run"});
}

// Issue 44 (third round), class 4 variants: `semap segment --model precomputed:DIR --out DIR`
// rewrote the precomputed segmentation it was reading (written by an earlier segment, so the
// manifest rule let it), and `--out` over the images' folder wrote beside the inputs. The
// images, the model or precomputed folder (and `semap run --segmenter precomputed:DIR`) are
// inputs like the dataset: an output folder that is or holds one is refused.
TEST_F(OutputSafety, SegmentAndRunNeverWriteIntoTheirImagesOrPrecomputedFolder) {
  const fs::path images = path("seg_images"), pre = path("precomputed");
  fs::create_directories(images);
  fs::create_directories(pre);
  fs::copy_file(clean() / "rgb" / "000000.png", images / "000000.png");
  const cv::Mat bgr = cv::imread((images / "000000.png").string(), cv::IMREAD_COLOR);
  cv::Mat labels(bgr.size(), CV_8UC1, cv::Scalar(0)), instances(bgr.size(), CV_16UC1, cv::Scalar(0));
  labels(cv::Rect(10, 10, 40, 30)).setTo(5);
  instances(cv::Rect(10, 10, 40, 30)).setTo(1);
  write_segmentation(pre, "000000", bgr, result_from_label_images(labels, instances), "test");
  const auto before = snapshot(tmp_->path());
  const std::string image = (images / "000000.png").string(), model = "precomputed:" + pre.string();
  for (const fs::path& out : {pre, images}) {
    const auto r = run_semap({"segment", image, "--model", model, "--out", out.string()});
    expect_one_line_error(r, {out.string(), "input"});
  }
  expect_one_line_error(run_semap(run_args(clean(), pre, {"--segmenter", model})), {pre.string(), "input"});
  EXPECT_EQ(changes(before, snapshot(tmp_->path())), "");
  // Elsewhere it writes (the refusals above are about the folder, not the inputs).
  const auto ok = run_semap({"segment", image, "--model", model, "--out", path("seg_out").string()});
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_EQ(slurp(path("seg_out") / "000000.json").empty(), false);
}

}  // namespace
}  // namespace semap
