#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "semap/io/dataset.hpp"
#include "io/image_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "io_test_util.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::throws_naming;

/// Median of the valid (non-zero) depths of a frame, metres.
double median_depth(const cv::Mat& depth) {
  std::vector<float> v;
  v.reserve(depth.total());
  for (int r = 0; r < depth.rows; ++r)
    for (int c = 0; c < depth.cols; ++c)
      if (depth.at<float>(r, c) > 0) v.push_back(depth.at<float>(r, c));
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct DecodeStats {
  size_t frames = 0, wrong_size = 0, implausible_depth = 0, bad_gt = 0;
};

/// Decodes every frame once, on a few threads (load() is const and thread-safe).
DecodeStats decode_all(const DatasetReader& reader) {
  std::atomic<size_t> next{0}, frames{0}, wrong_size{0}, implausible{0}, bad_gt{0};
  auto worker = [&] {
    for (size_t i; (i = next++) < reader.size();) {
      const Frame f = reader.load(i);
      ++frames;
      if (f.rgb.size() != cv::Size(640, 480) || f.depth.size() != cv::Size(640, 480) || f.rgb.type() != CV_8UC3 ||
          f.depth.type() != CV_32FC1)
        ++wrong_size;
      const double m = median_depth(f.depth);
      if (!(m >= 0.5 && m <= 5.0)) ++implausible;
      if (!f.gt_T_world_camera || !is_valid_pose(*f.gt_T_world_camera, 1e-6)) ++bad_gt;
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < std::max(2u, std::thread::hardware_concurrency()); ++t) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  return {frames, wrong_size, implausible, bad_gt};
}

double stamp_of(const std::string& path) { return std::stod(fs::path(path).stem().string()); }

TEST(Datasets, TumFr1RpyAllFrames) {
  SEMAP_REQUIRE_DATA(root, "tum_fr1_rpy");
  const auto reader = open_dataset(root);
  EXPECT_EQ(reader->format(), "tum");
  ASSERT_EQ(reader->size(), 200u);  // every colour frame has a depth map within 0.02 s (associate.py: 200)
  const CameraModel& cam = reader->camera();
  EXPECT_DOUBLE_EQ(cam.depth.fx, 517.3);  // freiburg1 preset from the folder name "tum_fr1_rpy"
  EXPECT_DOUBLE_EQ(cam.depth.cy, 255.3);
  EXPECT_DOUBLE_EQ(cam.depth_scale, 5000.0);
  EXPECT_FALSE(cam.colour.has_value());
  for (const auto& r : reader->records()) {
    EXPECT_LT(std::abs(stamp_of(r.rgb.string()) - stamp_of(r.depth.string())), 0.02);
    EXPECT_DOUBLE_EQ(r.timestamp, stamp_of(r.rgb.string()));
  }
  // Ground truth of frame 0 lies between the mocap samples around it.
  const Trajectory gt = read_tum_trajectory(root / "groundtruth.txt");
  const auto after = std::lower_bound(gt.begin(), gt.end(), reader->records()[0].timestamp,
                                      [](const StampedPose& p, double t) { return p.timestamp < t; });
  ASSERT_NE(after, gt.begin());
  const Eigen::Vector3d p = reader->records()[0].gt_T_world_camera->translation();
  EXPECT_LT((p - after->T_world_camera.translation()).norm(), 0.01);
  EXPECT_LT((p - std::prev(after)->T_world_camera.translation()).norm(), 0.01);
  EXPECT_EQ(reader->ground_truth().size(), 200u);

  const DecodeStats s = decode_all(*reader);
  EXPECT_EQ(s.frames, 200u);
  EXPECT_EQ(s.wrong_size, 0u);
  EXPECT_EQ(s.implausible_depth, 0u);
  EXPECT_EQ(s.bad_gt, 0u);
}

TEST(Datasets, SevenScenesRedkitchen500Frames) {
  SEMAP_REQUIRE_DATA(root, "7scenes_redkitchen");
  const auto reader = open_dataset(root);
  EXPECT_EQ(reader->format(), "7scenes");
  ASSERT_EQ(reader->size(), 500u);
  EXPECT_DOUBLE_EQ(reader->camera().depth.fx, 585.0);
  EXPECT_DOUBLE_EQ(reader->camera().depth.cx, 320.0);
  EXPECT_DOUBLE_EQ(reader->camera().depth_scale, 1000.0);
  for (size_t i = 0; i < reader->size(); i += 97) {
    const auto& r = reader->records()[i];
    char expected[32];
    std::snprintf(expected, sizeof expected, "frame-%06zu", i);
    EXPECT_EQ(r.rgb.filename().string(), std::string(expected) + ".color.jpg");
    EXPECT_EQ(r.depth.filename().string(), std::string(expected) + ".depth.png");
  }
  // Pose of frame 0 from frame-000000.pose.txt (camera-to-world).
  const Eigen::Vector3d t0 = reader->records()[0].gt_T_world_camera->translation();
  EXPECT_LT((t0 - Eigen::Vector3d(-0.3404563, 0.0164698, 0.2965692)).norm(), 1e-6);

  const DecodeStats s = decode_all(*reader);
  EXPECT_EQ(s.frames, 500u);
  EXPECT_EQ(s.wrong_size, 0u);
  EXPECT_EQ(s.implausible_depth, 0u);
  EXPECT_EQ(s.bad_gt, 0u);
}

TEST(Datasets, YcbVideoLabelsAndPoses) {
  SEMAP_REQUIRE_DATA(root, "ycb_video_0000");
  const auto reader = open_dataset(root);
  EXPECT_EQ(reader->format(), "ycb");
  ASSERT_EQ(reader->size(), 10u);
  EXPECT_DOUBLE_EQ(reader->camera().depth.fx, 1066.778);
  EXPECT_DOUBLE_EQ(reader->camera().depth_scale, 10000.0);
  EXPECT_TRUE(reader->has_label_ground_truth());
  ASSERT_TRUE(reader->has_ground_truth());
  for (size_t i = 0; i < reader->size(); ++i) {
    const Frame f = reader->load(i);
    ASSERT_TRUE(f.has_labels() && f.has_instances());
    const int mug = cv::countNonZero(f.instances == 14);
    EXPECT_GT(mug, 500) << "frame " << i;
    EXPECT_EQ(cv::countNonZero(f.labels == id(Label::kCup)), mug);
    EXPECT_GT(cv::countNonZero(f.labels == id(Label::kBox)), 500);  // gelatin box + foam brick
    EXPECT_EQ(cv::countNonZero(f.labels == id(Label::kCup) & f.instances != 14), 0);
    const double m = median_depth(f.depth);
    EXPECT_GT(m, 0.3);
    EXPECT_LT(m, 3.0);
    ASSERT_TRUE(f.gt_T_world_camera && is_valid_pose(*f.gt_T_world_camera, 1e-6));
  }
  // The camera barely moves over these 10 frames (a slow hand-held video).
  const Trajectory gt = reader->ground_truth();
  EXPECT_LT((gt.front().T_world_camera.translation() - gt.back().T_world_camera.translation()).norm(), 0.05);
  // Opening the video folder itself finds the intrinsics and poses two levels up.
  const auto video = open_dataset(root / "data" / "0000" / "");
  EXPECT_EQ(video->size(), 10u);
  EXPECT_DOUBLE_EQ(video->camera().depth.cy, 241.3109);
  EXPECT_TRUE(video->has_ground_truth());
}

// ---------------------------------------------------------------- generated folders

/// A tiny TUM-layout dataset: n frames of size `size`, depth 1.5 m.
void write_tum_folder(const fs::path& dir, int n, cv::Size size = {64, 48}) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::string rgb = "# color images\n", depth = "# depth\n", gt = "# gt\n";
  for (int i = 0; i < n; ++i) {
    const std::string stamp = std::to_string(100.0 + i / 30.0);
    write_image(dir / "rgb" / (stamp + ".png"), cv::Mat(size, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i)));
    write_depth_image(dir / "depth" / (stamp + ".png"), cv::Mat(size, CV_32FC1, cv::Scalar(1.5)), 5000.0);
    rgb += stamp + " rgb/" + stamp + ".png\n";
    depth += std::to_string(100.0 + i / 30.0 + 0.004) + " depth/" + stamp + ".png\n";
    gt += stamp + " " + std::to_string(0.1 * i) + " 0 0 0 0 0 1\n";
  }
  test::write_text(dir / "rgb.txt", rgb);
  test::write_text(dir / "depth.txt", depth);
  test::write_text(dir / "groundtruth.txt", gt);
}

TEST(Datasets, GeneratedTumFolderWithPresetFromName) {
  test::TempDir tmp;
  const fs::path dir = tmp / "rgbd_dataset_freiburg2_desk";
  write_tum_folder(dir, 4);
  // Depth lists are 4 ms after colour: associated; a yaml sets the 64x48 camera size (and a
  // principal point inside it: the preset's cx 318.6 lies outside a 64-pixel image, issue 22).
  test::write_text(dir / "dataset.yaml", "camera: {width: 64, height: 48, cx: 32, cy: 24}\n");
  auto reader = open_dataset(dir);
  ASSERT_EQ(reader->size(), 4u);
  EXPECT_DOUBLE_EQ(reader->camera().depth.fx, 517.3);  // yaml over the default preset
  fs::remove(dir / "dataset.yaml");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir)->load(0); }, "expected 640x480"));
  EXPECT_DOUBLE_EQ(open_dataset(dir)->camera().depth.fx, 520.9);  // freiburg2 from the folder name
  // An associations.txt written by TUM's associate.py keeps it a TUM folder (not 7-Scenes).
  test::write_text(dir / "associations.txt", "100 rgb/100.000000.png 100.004 depth/100.000000.png\n");
  EXPECT_EQ(open_dataset(dir)->format(), "tum");

  test::write_text(dir / "dataset.yaml", "format: tum\ncamera: {fx: 100, fy: 101, cx: 32, cy: 24, width: 64, height: 48, depth_scale: 5000}\n");
  reader = open_dataset(dir);
  EXPECT_DOUBLE_EQ(reader->camera().depth.fy, 101.0);
  const Frame f = reader->load(3);
  EXPECT_NEAR(f.depth.at<float>(10, 10), 1.5f, 1e-6);
  EXPECT_EQ(f.rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(3, 6, 9));
  ASSERT_TRUE(f.gt_T_world_camera);
  EXPECT_NEAR(f.gt_T_world_camera->translation().x(), 0.3, 1e-9);
}

TEST(Datasets, LensDistortionIsUndistortedOnLoad) {
  test::TempDir tmp;
  const fs::path dir = tmp / "lens";
  write_tum_folder(dir, 2);
  const std::string camera = "format: tum\ncamera: {fx: 100, fy: 100, cx: 32, cy: 24, width: 64, height: 48, ";
  test::write_text(dir / "dataset.yaml", camera + "distortion: [0.2, 0, 0, 0, 0]}\n");
  const auto reader = open_dataset(dir);
  EXPECT_FALSE(reader->camera().has_distortion());  // the delivered images are pinhole images
  const Frame f = reader->load(1);
  // k1 = 0.2 pulls the corner's source pixel 1 px outside the stored image: no depth there;
  // the centre is where it was (constant 1.5 m in the generated folder).
  EXPECT_EQ(f.depth.at<float>(0, 0), 0.0f);
  EXPECT_NEAR(f.depth.at<float>(24, 32), 1.5f, 1e-6);
  EXPECT_EQ(reader->load_depth(1).at<float>(0, 0), 0.0f);
  // The freiburg1 preset carries TUM's published lens; a yaml camera has none unless it says so.
  test::write_text(dir / "dataset.yaml", camera + "}\n");
  EXPECT_NEAR(open_dataset(dir)->load(1).depth.at<float>(0, 0), 1.5f, 1e-6);
  EXPECT_TRUE(tum_camera_preset(1).has_distortion());
  EXPECT_FALSE(tum_camera_preset(3).has_distortion());
  test::write_text(dir / "dataset.yaml", camera + "distortion: [0.2, 0]}\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "'camera.distortion' must list 5 numbers"));
  test::write_text(dir / "dataset.yaml", camera + "distortion: [200, 0, 0, 0, 0]}\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "distortion coefficient 200"));
}

TEST(Datasets, GeneratedSyntheticLayout) {
  test::TempDir tmp;
  const fs::path dir = tmp.path();
  for (auto sub : {"rgb", "depth", "label", "instance"}) fs::create_directories(dir / sub);
  test::write_text(dir / "dataset.yaml",
                   "format: synthetic\ncamera: {fx: 50, fy: 50, cx: 15.5, cy: 11.5, width: 32, height: 24, depth_scale: 5000}\n");
  std::string lists[4], gt;
  const char* names[4] = {"rgb", "depth", "label", "instance"};
  for (int i = 0; i < 3; ++i) {
    char file[16];
    std::snprintf(file, sizeof file, "%06d.png", i);
    const std::string stamp = std::to_string(i / 30.0);
    write_image(dir / "rgb" / file, cv::Mat(24, 32, CV_8UC3, cv::Scalar(10, 20, 30)));
    cv::Mat depth(24, 32, CV_32FC1, cv::Scalar(2.0 + i));
    depth.at<float>(0, 0) = 0;
    write_depth_image(dir / "depth" / file, depth, 5000.0);
    cv::Mat labels(24, 32, CV_8UC1, cv::Scalar(id(Label::kFloor)));
    labels(cv::Rect(4, 4, 8, 8)).setTo(id(Label::kChair));
    write_image(dir / "label" / file, labels);
    cv::Mat instances(24, 32, CV_16UC1, cv::Scalar(0));
    instances(cv::Rect(4, 4, 8, 8)).setTo(300 + i);
    write_image(dir / "instance" / file, instances);
    for (int k = 0; k < 4; ++k) lists[k] += stamp + " " + names[k] + "/" + file + "\n";
    gt += stamp + " 0 0 " + std::to_string(i) + " 0 0 0 1\n";
  }
  for (int k = 0; k < 4; ++k) test::write_text(dir / (std::string(names[k]) + ".txt"), lists[k]);
  test::write_text(dir / "groundtruth.txt", gt);

  const auto reader = open_dataset(dir);
  EXPECT_EQ(reader->format(), "synthetic");
  ASSERT_EQ(reader->size(), 3u);
  EXPECT_DOUBLE_EQ(reader->camera().depth.cx, 15.5);
  EXPECT_TRUE(reader->has_label_ground_truth());
  const Frame f = reader->load(2);
  EXPECT_EQ(f.labels.type(), CV_8UC1);
  EXPECT_EQ(f.labels.at<uint8_t>(5, 5), id(Label::kChair));
  EXPECT_EQ(f.labels.at<uint8_t>(20, 20), id(Label::kFloor));
  EXPECT_EQ(f.instances.type(), CV_16UC1);
  EXPECT_EQ(f.instances.at<uint16_t>(5, 5), 302);
  EXPECT_FLOAT_EQ(f.depth.at<float>(1, 1), 4.0f);
  EXPECT_EQ(f.depth.at<float>(0, 0), 0.0f);
  EXPECT_NEAR(f.gt_T_world_camera->translation().z(), 2.0, 1e-12);
  // Noisy labels were not written: asking for them names the missing list.
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir, DatasetOptions{true}); }, "label_noisy.txt"));
  // A label list that misses a frame.
  test::write_text(dir / "label.txt", lists[2].substr(0, lists[2].rfind('\n', lists[2].size() - 2) + 1));
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "label.txt"));
}

// ---------------------------------------------------------------- bad-input corpus

TEST(DatasetBadInput, FoldersAndLists) {
  test::TempDir tmp;
  EXPECT_TRUE(throws_naming([&] { open_dataset(tmp / "no_such_folder"); }, "no_such_folder: dataset folder not found"));
  fs::create_directories(tmp / "empty");
  EXPECT_TRUE(throws_naming([&] { open_dataset(tmp / "empty"); }, "looked for"));

  const fs::path dir = tmp / "fr1_test";
  write_tum_folder(dir, 5, {640, 480});
  ASSERT_EQ(open_dataset(dir)->size(), 5u);
  const std::string rgb = test::read_bytes(dir / "rgb.txt"), depth = test::read_bytes(dir / "depth.txt");

  fs::remove(dir / "depth.txt");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "depth.txt: list file not found"));
  test::write_text(dir / "depth.txt", depth);

  test::write_text(dir / "rgb.txt", rgb + "101 rgb/absent.png\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "rgb.txt:7: listed image"));
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "absent.png"));

  // Duplicate and decreasing timestamps (line 4 repeats / precedes line 3).
  std::vector<std::string> lines;
  for (size_t s = 0, e; (e = rgb.find('\n', s)) != std::string::npos; s = e + 1) lines.push_back(rgb.substr(s, e - s + 1));
  test::write_text(dir / "rgb.txt", lines[0] + lines[1] + lines[2] + lines[2] + lines[3]);
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "rgb.txt:4: duplicate timestamp"));
  test::write_text(dir / "rgb.txt", lines[0] + lines[2] + lines[1] + lines[3]);
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "rgb.txt:3: timestamp not increasing"));
  test::write_text(dir / "rgb.txt", lines[0] + "nan rgb/x.png\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "rgb.txt:2"));
  test::write_text(dir / "rgb.txt", "# no frames\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "no frames"));
  test::write_text(dir / "rgb.txt", rgb);

  const std::string gt = test::read_bytes(dir / "groundtruth.txt");
  test::write_text(dir / "groundtruth.txt", gt + "200 0 0 NaN 0 0 0 1\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "groundtruth.txt:7"));
  test::write_text(dir / "groundtruth.txt", gt + "200 0 0 0 0.5 0 0 1\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "groundtruth.txt:7"));
  test::write_text(dir / "groundtruth.txt", gt);

  test::write_text(dir / "dataset.yaml", "format: tum\ncamera: {fx: [1, 2]\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "dataset.yaml"));
  test::write_text(dir / "dataset.yaml", "format: tum\ncamera: {fx: 500, focal: 3}\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "dataset.yaml: unknown key 'camera.focal'"));
  test::write_text(dir / "dataset.yaml", "format: kinect\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "dataset.yaml"));
  test::write_text(dir / "dataset.yaml", "camera: {fx: -5}\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "dataset.yaml"));
  test::write_text(dir / "dataset.yaml", "camera: {width: 1e30}\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "dataset.yaml"));
  test::write_text(dir / "dataset.yaml", "? [a, b]\n: 1\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "dataset.yaml"));
  test::write_text(dir / "dataset.yaml", "- just\n- a list\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "dataset.yaml"));
  fs::remove(dir / "dataset.yaml");
}

TEST(DatasetBadInput, ImagesInsideADataset) {
  test::TempDir tmp;
  const fs::path dir = tmp / "freiburg1_bad";
  write_tum_folder(dir, 6, {640, 480});
  const auto reader = open_dataset(dir);
  ASSERT_EQ(reader->size(), 6u);
  const auto& rec = reader->records();
  reader->load(0);

  // Truncated depth PNG and truncated colour PNG.
  const std::string depth = test::read_bytes(rec[1].depth);
  test::write_bytes(rec[1].depth, depth.substr(0, depth.size() / 2));
  EXPECT_TRUE(throws_naming([&] { reader->load(1); }, rec[1].depth.string()));
  const std::string colour = test::read_bytes(rec[2].rgb);
  test::write_bytes(rec[2].rgb, colour.substr(0, colour.size() - 20));
  EXPECT_TRUE(throws_naming([&] { reader->load(2); }, rec[2].rgb.string()));
  // 8-bit depth.
  write_image(rec[3].depth, cv::Mat(480, 640, CV_8UC1, cv::Scalar(9)));
  EXPECT_TRUE(throws_naming([&] { reader->load(3); }, rec[3].depth.string() + ": 8-bit depth"));
  // Depth of the wrong size for the camera.
  write_depth_image(rec[4].depth, cv::Mat(240, 320, CV_32FC1, cv::Scalar(1.0)), 5000.0);
  EXPECT_TRUE(throws_naming([&] { reader->load(4); }, rec[4].depth.string()));
  // RGB and depth of different sizes: the message names both files.
  write_image(rec[5].rgb, cv::Mat(240, 320, CV_8UC3, cv::Scalar(1, 2, 3)));
  EXPECT_TRUE(throws_naming([&] { reader->load(5); }, rec[5].rgb.string()));
  EXPECT_TRUE(throws_naming([&] { reader->load(5); }, rec[5].depth.string()));
  // All-zero depth is allowed here (the pipeline decides whether to skip the frame).
  write_depth_image(rec[0].depth, cv::Mat::zeros(480, 640, CV_32FC1), 5000.0);
  EXPECT_EQ(cv::countNonZero(reader->load(0).depth), 0);
  EXPECT_TRUE(throws_naming([&] { reader->load(99); }, "out of range"));
}

TEST(DatasetBadInput, SevenScenesTruncatedJpegAndMissingDepth) {
  test::TempDir tmp;
  const fs::path dir = tmp.path();
  for (int i = 0; i < 3; ++i) {
    char stem[32];
    std::snprintf(stem, sizeof stem, "frame-%06d", i);
    cv::Mat colour(480, 640, CV_8UC3);
    cv::randu(colour, 0, 255);
    write_image(dir / (std::string(stem) + ".color.jpg"), colour);
    write_depth_image(dir / (std::string(stem) + ".depth.png"), cv::Mat(480, 640, CV_32FC1, cv::Scalar(2.0)), 1000.0);
    test::write_text(dir / (std::string(stem) + ".pose.txt"), "1 0 0 0\n0 1 0 0\n0 0 1 " + std::to_string(i) + "\n0 0 0 1\n");
  }
  auto reader = open_dataset(dir);  // no lists: frames found by name, 30 Hz timestamps
  EXPECT_EQ(reader->format(), "7scenes");
  ASSERT_EQ(reader->size(), 3u);
  EXPECT_NEAR(reader->records()[2].timestamp, 2 / 30.0, 1e-12);
  EXPECT_NEAR(reader->load(2).gt_T_world_camera->translation().z(), 2.0, 1e-12);
  EXPECT_FLOAT_EQ(reader->load(1).depth.at<float>(7, 7), 2.0f);

  const fs::path jpg = dir / "frame-000001.color.jpg";
  const std::string bytes = test::read_bytes(jpg);
  test::write_bytes(jpg, bytes.substr(0, bytes.size() * 2 / 3));
  EXPECT_TRUE(throws_naming([&] { reader->load(1); }, jpg.string()));

  test::write_text(dir / "frame-000002.pose.txt", "1 0 0 0\n0 2 0 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "frame-000002.pose.txt"));
  fs::remove(dir / "frame-000002.depth.png");
  EXPECT_TRUE(throws_naming([&] { open_dataset(dir); }, "frame-000002.depth.png"));
}

}  // namespace
}  // namespace semap
