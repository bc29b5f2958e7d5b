// Issue 22 through the `semap` CLI, by the issue's headings. Every input is generated here from
// a small `semap synth` dataset. A bad input is one "semap: error:" line naming the file with
// exit code 1, within a time limit (no hang), without a crash report, and nothing is written
// outside the output folder or removed that semap did not write.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "semap/core/point_cloud.hpp"
#include "io/image_io.hpp"
#include "semap/io/ply_io.hpp"
#include "reliability/reliability_support.hpp"
#include "segmentation/segmentation_io.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::data_lines;
using test::expect_one_line_error;
using test::join_lines;
using test::listed;
using test::no_crash_report;
using test::run_semap;
using test::slurp;
using test::spit;
using test::changes;
using test::snapshot;
using test::tree;

bool has_staging(const fs::path& dir) {
  for (const auto& f : tree(dir))
    if (f.find(".semap-staging-") != std::string::npos) return true;
  return false;
}

class HardeningCli : public test::CliSuite {
 protected:
  static void SetUpTestSuite() {
    make_suite("semap_hardening_cli");
    // A precomputed segmentation of one image, for `semap segment --model precomputed:DIR`.
    const cv::Mat image = read_colour_image(listed(clean() / "rgb.txt", 0));
    fs::create_directories(tmp_->path() / "images");
    fs::create_directories(tmp_->path() / "images2");
    write_image(tmp_->path() / "images" / "frame.png", image);
    SegmentationResult result;
    result.labels = cv::Mat(image.size(), CV_8UC1, cv::Scalar(id(Label::kTable)));
    write_segmentation(tmp_->path() / "precomputed", "frame", image, result, "test");
  }
  /// A number of 20+ digits in `output`, outside the temp folder's own (random) name.
  static bool has_long_number(std::string output) {
    const std::string base = tmp_->path().string();
    for (size_t at; (at = output.find(base)) != std::string::npos;) output.erase(at, base.size());
    return std::regex_search(output, std::regex("[0-9]{20}"));
  }
};

// ------------------------------------------------------------ Data loss and writes where they must not go

TEST_F(HardeningCli, SynthNeverDeletesOrFillsAFolderItDidNotMake) {
  // A real dataset a user gave a dataset.yaml (as the README suggests), a folder holding only a
  // hidden file, and a plain file: all refused, byte for byte untouched.
  const fs::path tum = path("users_tum");
  fs::create_directories(tum / "rgb");
  spit(tum / "dataset.yaml", "format: tum\n");
  spit(tum / "rgb.txt", "1.0 rgb/1.png\n");
  spit(tum / "rgb" / "1.png", "200 real frames");
  const fs::path hidden = path("hidden_only");
  fs::create_directories(hidden);
  spit(hidden / ".keep", "");
  spit(path("a_file"), "not a folder");
  for (const fs::path& out : {tum, hidden, path("a_file")}) {
    SCOPED_TRACE(out.string());
    const auto before = snapshot(out);
    const auto r = run_semap({"synth", "--out", out.string(), "--frames", "2", "--width", "160", "--height", "120"});
    expect_one_line_error(r, {out.filename().string()});
    EXPECT_EQ(changes(before, snapshot(out)), "");
  }
  EXPECT_EQ(slurp(path("a_file")), "not a folder");

  // Its own folder: a re-run replaces its files, removes its stale ones, keeps the user's.
  const fs::path own = path("own");
  ASSERT_EQ(run_semap({"synth", "--out", own.string(), "--frames", "5", "--width", "160", "--height", "120"}).exit_code, 0);
  spit(own / "notes.txt", "mine");
  spit(own / "rgb" / "mine.png", "mine too");
  const auto r = run_semap({"synth", "--out", own.string(), "--frames", "3", "--width", "160", "--height", "120"});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(data_lines(own / "rgb.txt").size(), 3u);
  for (const char* sub : {"rgb", "depth", "label", "instance"}) {
    EXPECT_TRUE(fs::exists(own / sub / "000002.png")) << sub;
    EXPECT_FALSE(fs::exists(own / sub / "000003.png")) << sub << ": stale frame of the first run";
  }
  EXPECT_EQ(slurp(own / "notes.txt"), "mine");
  EXPECT_EQ(slurp(own / "rgb" / "mine.png"), "mine too");
  EXPECT_FALSE(has_staging(own));
}

TEST_F(HardeningCli, SignalsLeaveNothingThatLooksComplete) {
  for (const int signal_number : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(signal_number);
    const fs::path out = path("interrupted_" + std::to_string(signal_number)), log = out.string() + ".log";
    const pid_t pid = test::spawn_semap({"synth", "--out", out.string(), "--frames", "3000", "--width", "160",
                                         "--height", "120"}, log);
    // Wait until frames are being written into the staging folder, then interrupt.
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!(fs::exists(out) && has_staging(out) && !tree(out).empty() && tree(out).size() > 8) &&
           std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    ::kill(pid, signal_number);
    EXPECT_EQ(test::wait_exit(pid, 30), 128 + signal_number) << slurp(log);
    EXPECT_FALSE(fs::exists(out)) << "the folder it created is removed again";
    EXPECT_TRUE(no_crash_report(slurp(log)));
  }
  // Into an existing dataset: the earlier complete one stays exactly as it was.
  const fs::path own = path("own_interrupted");
  ASSERT_EQ(run_semap({"synth", "--out", own.string(), "--frames", "3", "--width", "160", "--height", "120"}).exit_code, 0);
  const auto before = snapshot(own);
  const pid_t pid = test::spawn_semap({"synth", "--out", own.string(), "--frames", "3000", "--width", "160",
                                       "--height", "120"}, own.string() + ".log");
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!has_staging(own) && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ::kill(pid, SIGINT);
  EXPECT_EQ(test::wait_exit(pid, 30), 130);
  EXPECT_EQ(changes(before, snapshot(own)), "");
}

TEST_F(HardeningCli, PlantedSymlinksCannotRedirectWritesOutsideOut) {
  const fs::path outside = path("outside");
  fs::create_directories(outside);
  // `semap run`: every old fixed temporary name planted as a symlink to a file outside.
  const fs::path out = path("planted_run");
  fs::create_directories(out);
  for (const char* name : {"report.json.tmp", "mesh.ply.tmp", "map.semap.tmp", "trajectory.txt.tmp",
                           "objects.json.tmp", "report.html.tmp", "topdown.png.tmp"}) {
    spit(outside / name, "victim");
    fs::create_symlink(outside / name, out / name);
  }
  const auto r = run_semap(run_args(clean(), out));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const auto& f : tree(outside)) EXPECT_EQ(slurp(outside / f), "victim") << f;

  // `semap view`: a `viewer` symlink to a folder outside is refused, nothing lands there.
  const fs::path viewer_target = path("viewer_target");
  fs::create_directories(viewer_target);
  fs::create_directory_symlink(viewer_target, out / "viewer");
  const auto v = run_semap({"view", out.string(), "--no-serve"});
  if (v.output.find("not built into this binary") != std::string::npos) SEMAP_SKIP_OR_FAIL(v.output);
  expect_one_line_error(v, {"viewer", "symlink"});
  EXPECT_TRUE(fs::is_empty(viewer_target));
  // A symlinked file inside a real viewer/ is not semap's (issue 44): refused, link and target kept.
  fs::remove(out / "viewer");
  fs::create_directories(out / "viewer");
  spit(outside / "index.victim", "victim");
  fs::create_symlink(outside / "index.victim", out / "viewer" / "index.html");
  const auto v2 = run_semap({"view", out.string(), "--no-serve"});
  expect_one_line_error(v2, {"index.html", "not written by semap"});
  EXPECT_TRUE(fs::is_symlink(out / "viewer" / "index.html"));
  EXPECT_EQ(slurp(outside / "index.victim"), "victim");
  // A file where the output folder is expected says what it is and what was expected (it said
  // "output folder is a regular file").
  const auto v3 = run_semap({"view", (out / "mesh.ply").string(), "--no-serve"});
  expect_one_line_error(v3, {"mesh.ply", "is a regular file, expected the output folder of `semap run`"});

  // `semap segment`: output names planted as symlinks are never followed nor replaced (issue 44).
  const fs::path seg = path("planted_segment");
  fs::create_directories(seg);
  for (const char* name : {"frame.label.png", "frame.json", ".frame.json.tmp", "frame.json.tmp"}) {
    spit(outside / (std::string("seg_") + name), "victim");
    fs::create_symlink(outside / (std::string("seg_") + name), seg / name);
  }
  const auto s = run_semap({"segment", (path("images") / "frame.png").string(), "--model",
                            "precomputed:" + path("precomputed").string(), "--out", seg.string()});
  expect_one_line_error(s, {"frame.json", "not written by semap"});
  for (const auto& f : tree(outside)) EXPECT_EQ(slurp(outside / f), "victim") << f;
  EXPECT_TRUE(fs::is_symlink(seg / "frame.label.png"));
  EXPECT_FALSE(fs::exists(seg / "frame.overlay.png"));
  // Two inputs with one name would overwrite each other's outputs: refused up front.
  fs::copy_file(path("images") / "frame.png", path("images2") / "frame.png", fs::copy_options::overwrite_existing);
  const auto twice = run_semap({"segment", (path("images") / "frame.png").string(), (path("images2") / "frame.png").string(),
                                "--model", "precomputed:" + path("precomputed").string(), "--out", path("seg_twice").string()});
  expect_one_line_error(twice, {"same name 'frame'"});
  EXPECT_FALSE(fs::exists(path("seg_twice")));
}

// ------------------------------------------------------------ Crashes, hangs, memory

TEST_F(HardeningCli, CameraMagnitudesOutsidePhysicalRangesAreOneLineErrors) {
  const std::string yaml = slurp(clean() / "dataset.yaml");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"cx", "1e12"}, {"cx", "1e6"}, {"cy", "-40"}, {"fx", "1e-9"}, {"fy", "1e12"}, {"depth_scale", "1e-9"}};
  for (const auto& [key, value] : cases) {
    SCOPED_TRACE(key + " " + value);
    const fs::path d = copy("camera_" + key + value);
    spit(d / "dataset.yaml", std::regex_replace(yaml, std::regex(key + ": [^,}]*"), key + ": " + value));
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = run_semap(run_args(d, d.string() + "_out"), 60);
    expect_one_line_error(r, {"dataset.yaml", "camera " + key});
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0);
    EXPECT_FALSE(has_long_number(r.output)) << r.output;
  }
}

TEST_F(HardeningCli, ImageBombsAreRefusedBeforeDecoding) {
  // A JPEG declaring 16384x16384 in a few hundred bytes.
  std::vector<uchar> jpg;
  cv::imencode(".jpg", cv::Mat(24, 32, CV_8UC3, cv::Scalar(1, 2, 3)), jpg);
  for (size_t pos = 2; pos + 9 < jpg.size(); pos += 2 + ((jpg[pos + 2] << 8) | jpg[pos + 3]))
    if (jpg[pos + 1] == 0xC0) {
      jpg[pos + 5] = jpg[pos + 7] = 0x40;
      jpg[pos + 6] = jpg[pos + 8] = 0x00;
      break;
    }
  const fs::path bomb = path("bombs") / "bomb.jpg";
  fs::create_directories(bomb.parent_path());
  spit(bomb, std::string(jpg.begin(), jpg.end()));
  // `semap segment`: refused from the header (test_hardening_io measures that no memory grows).
  const auto r = run_semap({"segment", bomb.string(), "--model", "precomputed:" + path("precomputed").string(), "--out",
                            path("bomb_out").string()}, 30);
  expect_one_line_error(r, {"bomb.jpg", "16384x16384"});
  EXPECT_FALSE(fs::exists(path("bomb_out")));
  // As a frame of a sequence: skipped with a warning naming it, like any unreadable frame.
  const fs::path d = copy("bomb_frame");
  spit(listed(d / "rgb.txt", 4), std::string(jpg.begin(), jpg.end()));
  const auto run = run_semap(run_args(d, d.string() + "_out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("16384x16384"), std::string::npos) << run.output;
  EXPECT_EQ(nlohmann::json::parse(slurp(d.string() + "_out/report.json"))["summary"]["frames_skipped"].get<int>(), 1);
}

TEST_F(HardeningCli, FifosDevicesAndFoldersNeverHang) {
  const fs::path fifo = path("fifo.yaml"), folder = path("a_folder.yaml");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  fs::create_directories(folder);
  const fs::path fifo_list = copy("fifo_list");
  fs::remove(fifo_list / "rgb.txt");
  ASSERT_EQ(mkfifo((fifo_list / "rgb.txt").c_str(), 0600), 0);
  const fs::path fifo_image = copy("fifo_image");
  fs::remove(listed(fifo_image / "depth.txt", 2));
  ASSERT_EQ(mkfifo(listed(fifo_image / "depth.txt", 2).c_str(), 0600), 0);
  const std::string model_dir = path("a_model_dir.onnx").string();
  fs::create_directories(model_dir);
  const auto with = [&](std::vector<std::string> extra) {
    auto args = run_args(clean(), path("fifo_out"));
    for (size_t k = 0; k + 1 < args.size() && extra.front() == "--segmenter"; ++k)
      if (args[k] == "--segmenter") args.erase(args.begin() + k, args.begin() + k + 2);
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  const std::vector<std::pair<std::vector<std::string>, std::vector<std::string>>> cases = {
      {run_args(fifo_list, path("fifo_out")), {"rgb.txt", "FIFO"}},
      {run_args(fifo_image, path("fifo_out")), {listed(fifo_image / "depth.txt", 2).filename().string(), "FIFO"}},
      {with({"--config", fifo.string()}), {"fifo.yaml", "FIFO"}},
      {with({"--config", "/dev/zero"}), {"/dev/zero", "character device"}},
      {with({"--config", folder.string()}), {"a_folder.yaml", "folder"}},
      {with({"--segmenter", "yolo:" + fifo.string()}), {"fifo.yaml", "FIFO"}},
      {with({"--segmenter", "yolo:" + model_dir}), {"a_model_dir.onnx", "folder"}},
      {with({"--segmenter", "semantic:" + model_dir}), {"a_model_dir.onnx", "folder"}},
      {{"config", "--check", fifo.string()}, {"fifo.yaml", "FIFO"}},
      {{"eval", "ate", "--gt", "/dev/zero", "--est", (clean() / "groundtruth.txt").string()}, {"/dev/zero"}},
      {{"eval", "semantic", "--gt", fifo.string(), "--map", (clean() / "gt_points.ply").string()}, {"fifo.yaml"}},
      {{"segment", fifo.string(), "--model", "precomputed:" + path("precomputed").string(), "--out",
        path("fifo_seg").string()}, {"fifo.yaml", "FIFO"}},
  };
  for (const auto& [args, names] : cases) {
    SCOPED_TRACE(args.back());
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = run_semap(args, 30);
    expect_one_line_error(r, names);
    EXPECT_EQ(r.output.find("basic_filebuf"), std::string::npos) << r.output;
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 20.0);
  }
  EXPECT_TRUE(tree(path("fifo_out")).empty());
  EXPECT_FALSE(fs::exists(path("fifo_seg")));
}

TEST_F(HardeningCli, GeoreferencedGroundTruthMapsLikeTheLocalOne) {
  const fs::path geo = copy("georeferenced");
  test::georeference(geo / "groundtruth.txt", {412345.0, 5312345.0, 120.0});
  const auto local = run_semap(run_args(clean(), path("local_out")));
  const auto far = run_semap(run_args(geo, path("geo_out")));
  ASSERT_EQ(local.exit_code, 0) << local.output;
  ASSERT_EQ(far.exit_code, 0) << far.output;
  EXPECT_NE(far.output.find("using a local origin"), std::string::npos) << far.output;
  EXPECT_NE(far.output.find("groundtruth.txt"), std::string::npos) << far.output;
  const size_t a = read_ply(path("local_out") / "mesh.ply").vertices.size();
  const size_t b = read_ply(path("geo_out") / "mesh.ply").vertices.size();
  std::printf("mesh vertices: local ground truth %zu, georeferenced %zu\n", a, b);
  EXPECT_GT(a, 1000u);
  EXPECT_NEAR(double(b), double(a), 0.02 * a) << "the georeferenced run maps the same scene";
}

// ------------------------------------------------------------ Silent wrong results and unclear errors

TEST_F(HardeningCli, ConfigFilesAreStrict) {
  const fs::path cfg = path("cfg");
  fs::create_directories(cfg);
  spit(cfg / "dup.yaml", "tsdf:\n  voxel_size: 0.02\n  voxel_size: 0.05\n");
  spit(cfg / "two_docs.yaml", "tsdf:\n  voxel_size: 0.05\n---\npipeline: {threads: 1}\n");
  spit(cfg / "bom.yaml", "\xEF\xBB\xBF# a comment first\ntsdf:\n  voxel_size: 0.05\n");
  expect_one_line_error(run_semap({"config", "--check", (cfg / "dup.yaml").string()}),
                        {"dup.yaml:3", "duplicate key 'voxel_size'"});
  expect_one_line_error(run_semap({"config", "--check", (cfg / "two_docs.yaml").string()}),
                        {"two_docs.yaml", "second YAML document"});
  const auto bom = run_semap({"config", "--check", (cfg / "bom.yaml").string()});
  EXPECT_EQ(bom.exit_code, 0) << bom.output;
  auto args = run_args(clean(), path("cfg_out"));
  args.insert(args.end(), {"--config", cfg.string()});
  expect_one_line_error(run_semap(args), {"cfg", "is a folder"});
  EXPECT_TRUE(tree(path("cfg_out")).empty());
}

TEST_F(HardeningCli, EveryCliErrorExitsOneWithOneCompactLine) {
  const std::string gt = (clean() / "groundtruth.txt").string();
  const std::vector<std::vector<std::string>> cases = {
      {},
      {"frobnicate"},
      {"--bogus"},
      {"run"},
      {"run", "x"},
      {"run", "x", "--out"},
      {"run", "x", "--out", "y", "--voxel", "abc"},
      {"run", "x", "--out", "y", "--voxel", "-1"},
      {"run", "x", "--out", "y", "--poses", "fly"},
      {"run", "x", "--out", "y", "--seg-noise", "5"},
      {"run", "x", "--out", "y", "extra"},
      {"view", "--port", "70000"},
      {"eval"},
      {"eval", "ate", "--gt", gt},
      {"eval", "ate", "--gt", gt, "--est", gt, "--max-dt", "nan"},
      {"eval", "objects", "--gt", gt, "--map", gt, "--voxel", "1e-9"},
      {"synth", "--out", path("never").string(), "--frames", "x"},
      {"config", "--check", path("absent.yaml").string()},
      {"demo", "--frames", "3"},
  };
  for (const auto& args : cases) {
    std::string shown;
    for (const auto& a : args) shown += a + " ";
    SCOPED_TRACE(shown);
    const auto r = run_semap(args, 30);
    expect_one_line_error(r, {});
    EXPECT_FALSE(has_long_number(r.output)) << r.output;
  }
  EXPECT_FALSE(fs::exists(path("never")));
  for (const char* ok : {"--help", "--version"}) EXPECT_EQ(run_semap({ok}).exit_code, 0) << ok;
  EXPECT_EQ(run_semap({"run", "--help"}).exit_code, 0);
}

TEST_F(HardeningCli, MessagesNameTheFileAndSayWhatItIs) {
  const fs::path dangling = copy("dangling_list");
  fs::remove(dangling / "rgb.txt");
  fs::create_symlink(dangling / "rgb_old.txt", dangling / "rgb.txt");
  expect_one_line_error(run_semap(run_args(dangling, path("msg_out"))), {"rgb.txt", "dangling symlink"});
  const fs::path loop = copy("loop_list");
  fs::remove(loop / "depth.txt");
  fs::create_symlink(loop / "depth.txt", loop / "depth.txt");
  expect_one_line_error(run_semap(run_args(loop, path("msg_out"))), {"depth.txt", "symlink loop"});
  // A 60 000-character argument (the shell's limit is 128 KiB) is shortened in the message.
  const std::string huge = path("h").string() + std::string(60000, 'x') + ".txt";
  const auto r = run_semap({"eval", "ate", "--gt", huge, "--est", (clean() / "groundtruth.txt").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_LT(r.output.size(), 3000u) << r.output.substr(0, 400);
  EXPECT_NE(r.output.find("characters"), std::string::npos) << r.output.substr(0, 400);
}

TEST_F(HardeningCli, EvaluationRefusesDuplicatesAndReportsUndefinedFigures) {
  const fs::path dir = path("eval");
  fs::create_directories(dir);
  spit(dir / "objects_dup.json", R"({"objects": [{"id": 3, "class": "cup", "point_count": 0},
                                                 {"id": 3, "class": "cup", "point_count": 0}]})");
  expect_one_line_error(run_semap({"eval", "objects", "--gt", (clean() / "scene.json").string(), "--map",
                                   (dir / "objects_dup.json").string()}),
                        {"objects_dup.json", "appears twice"});
  // RPE over 0.3 s of trajectory with a 1 s delta: null and why, not 0.0.
  const auto lines = data_lines(clean() / "groundtruth.txt");
  spit(dir / "short.txt", join_lines({lines.begin(), lines.begin() + 10}));
  const auto ate = run_semap({"eval", "ate", "--gt", (dir / "short.txt").string(), "--est", (dir / "short.txt").string(), "--json"});
  ASSERT_EQ(ate.exit_code, 0) << ate.output;
  const auto j = nlohmann::json::parse(ate.output);
  EXPECT_TRUE(j["rpe"]["trans_rmse_m_per_s"].is_null()) << j.dump();
  EXPECT_NE(j["rpe"]["reason"].get<std::string>().find("apart"), std::string::npos);
  const auto table = run_semap({"eval", "ate", "--gt", (dir / "short.txt").string(), "--est", (dir / "short.txt").string()});
  EXPECT_NE(table.output.find("n/a"), std::string::npos) << table.output;
  // NaN/Inf vertices: excluded and counted, the surface error stays finite.
  TriangleMesh map = read_ply(clean() / "gt_points.ply");
  const size_t finite = map.vertices.size();
  for (int k = 0; k < 7; ++k) map.vertices.push_back_from(map.vertices, 0), map.vertices.points.back().x() = k % 2 ? NAN : INFINITY;
  write_ply(dir / "nan_map.ply", map);
  const auto sem = run_semap({"eval", "semantic", "--gt", (clean() / "gt_points.ply").string(), "--map",
                              (dir / "nan_map.ply").string(), "--json"});
  ASSERT_EQ(sem.exit_code, 0) << sem.output;
  const auto s = nlohmann::json::parse(sem.output);
  EXPECT_EQ(s["map_vertices_non_finite"].get<size_t>(), 7u);
  EXPECT_EQ(s["map_vertices"].get<size_t>(), finite);
  EXPECT_LT(s["surface_error_mean_m"].get<double>(), 1e-6);
  EXPECT_NEAR(s["miou"].get<double>(), 1.0, 1e-9);
}

}  // namespace
}  // namespace semap
