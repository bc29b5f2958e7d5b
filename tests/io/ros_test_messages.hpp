#pragma once
// Shared by the ROS1 and rosbag2 reader tests: ROS messages made from TUM frames (the
// writers' plain structs, test_rosbag_writer.hpp), a small real frame for the encoding
// cases, image_transport's compressedDepth, pixel comparison and single-threaded tracking.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "io/image_io.hpp"
#include "semap/io/dataset.hpp"
#include "test_rosbag_writer.hpp"
#include "test_support.hpp"
#include "tracking/tracker.hpp"

namespace semap::test::ros {

namespace fs = std::filesystem;

/// "1305031229.528748" -> {1305031229, 528748000}, exactly (no floating point).
inline RosStamp stamp_from_text(const std::string& text) {
  const size_t dot = text.find('.');
  RosStamp s;
  s.sec = static_cast<uint32_t>(std::stoul(text.substr(0, dot)));
  if (dot != std::string::npos) {
    std::string frac = text.substr(dot + 1);
    frac.resize(9, '0');
    s.nsec = static_cast<uint32_t>(std::stoul(frac));
  }
  return s;
}

inline RosImage colour_message(const std::string& topic, RosStamp stamp, const cv::Mat& bgr, const std::string& encoding) {
  cv::Mat converted;
  if (encoding == "rgb8") cv::cvtColor(bgr, converted, cv::COLOR_BGR2RGB);
  else if (encoding == "mono8") cv::cvtColor(bgr, converted, cv::COLOR_BGR2GRAY);
  else if (encoding == "rgba8") cv::cvtColor(bgr, converted, cv::COLOR_BGR2RGBA);
  else converted = bgr.clone();
  RosImage m{topic, stamp, encoding, uint32_t(bgr.cols), uint32_t(bgr.rows),
             uint32_t(bgr.cols * converted.elemSize()), false, {}};
  m.data.assign(converted.datastart, converted.dataend);
  return m;
}

/// 32FC1 metres with NaN for missing (the ROS convention), or 16UC1 millimetres.
inline RosImage depth_message(const std::string& topic, RosStamp stamp, const cv::Mat& depth_m, const std::string& encoding) {
  RosImage m{topic, stamp, encoding, uint32_t(depth_m.cols), uint32_t(depth_m.rows), 0, false, {}};
  if (encoding == "32FC1") {
    cv::Mat f = depth_m.clone();
    f.setTo(std::numeric_limits<float>::quiet_NaN(), depth_m == 0);
    m.step = uint32_t(depth_m.cols * 4);
    m.data.assign(f.datastart, f.dataend);
  } else {
    cv::Mat mm;
    depth_m.convertTo(mm, CV_16U, 1000.0);
    m.step = uint32_t(depth_m.cols * 2);
    m.data.assign(mm.datastart, mm.dataend);
  }
  return m;
}

inline RosCameraInfo info_message(const std::string& topic, RosStamp stamp, const PinholeIntrinsics& k,
                           const std::array<double, 5>& distortion = {0, 0, 0, 0, 0}) {
  RosCameraInfo info{topic, stamp, uint32_t(k.width), uint32_t(k.height), {}, {distortion.begin(), distortion.end()}};
  info.K = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
  return info;
}

inline bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

inline Trajectory track(const DatasetReader& reader, size_t frames) {
  TrackingConfig config;
  config.parallel = false;
  Tracker tracker(config, reader.camera());
  for (size_t i = 0; i < frames; ++i) tracker.track(reader.load(i));
  return tracker.finish();
}


/// A small real frame (the first TUM frame at 80x60) for the encoding bags.
struct SmallFrame {
  cv::Mat bgr, depth_m;
  cv::Mat mono_bgr;  ///< bgr through grey and back: what a mono8 image of it decodes to
  PinholeIntrinsics k;
};

inline SmallFrame small_frame() {
  SmallFrame s;
  const fs::path root = test::data_dir() / "tum_fr1_rpy";
  const auto folder = open_dataset(root);
  const Frame f = folder->load(0);
  cv::resize(f.rgb, s.bgr, {80, 60}, 0, 0, cv::INTER_AREA);
  cv::resize(f.depth, s.depth_m, {80, 60}, 0, 0, cv::INTER_NEAREST);
  // Millimetre-exact depths, so 16UC1 and 32FC1 carry the same values.
  for (auto it = s.depth_m.begin<float>(); it != s.depth_m.end<float>(); ++it) *it = std::round(*it * 1000.0f) / 1000.0f;
  s.k = folder->camera().depth.scaled(80.0 / 640.0);
  cv::Mat grey;
  cv::cvtColor(s.bgr, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(grey, s.mono_bgr, cv::COLOR_GRAY2BGR);
  return s;
}

inline std::vector<uint8_t> png_bytes(const cv::Mat& image) {
  std::vector<uint8_t> out;
  cv::imencode(".png", image, out);
  return out;
}

/// image_transport's compressedDepth: 12-byte header (format, depthQuantA, depthQuantB) + PNG.
inline std::vector<uint8_t> compressed_depth_bytes(const cv::Mat& depth_m, bool inverse_float) {
  int32_t format = 1;  // PNG
  float quant_a = 0, quant_b = 0;
  cv::Mat raw(depth_m.size(), CV_16UC1, cv::Scalar(0));
  if (inverse_float) {
    const float z0 = 100.0f, max_depth = 10.0f;  // the plugin's defaults
    quant_a = z0 * (z0 + 1.0f);
    quant_b = 1.0f - quant_a / max_depth;
    for (int r = 0; r < raw.rows; ++r)
      for (int c = 0; c < raw.cols; ++c) {
        const float z = depth_m.at<float>(r, c);
        if (z > 0 && z < max_depth) raw.at<uint16_t>(r, c) = uint16_t(quant_a / z + quant_b);
      }
  } else {
    depth_m.convertTo(raw, CV_16U, 1000.0);
  }
  std::vector<uint8_t> out(12);
  std::memcpy(out.data(), &format, 4);
  std::memcpy(out.data() + 4, &quant_a, 4);
  std::memcpy(out.data() + 8, &quant_b, 4);
  const auto png = png_bytes(raw);
  out.insert(out.end(), png.begin(), png.end());
  return out;
}

inline double mean_abs_diff(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat d;
  cv::absdiff(a, b, d);
  return cv::mean(d)[0];
}

/// Calls fn, expecting one semap::Error line that names `file` and contains `what` (printed
/// with `tag`, so the test log shows the messages users get).
template <class F>
void expect_one_line_error(F&& fn, const std::string& file, const std::string& what, const char* tag) {
  try {
    fn();
  } catch (const Error& e) {
    const std::string message = e.what();
    std::cout << "[" << tag << "] " << message << std::endl;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find(file), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
    return;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "non-semap exception: " << e.what();
    return;
  }
  ADD_FAILURE() << file << " read without error (expected '" << what << "')";
}

/// Topics of a camera driver's recording.
struct CameraTopics {
  std::string colour, colour_info, depth, depth_info;
};

/// The first `frames` frames of a TUM fr1 folder as the camera drivers record them: the raw
/// (distorted) images, rgb8 colour and 32FC1 depth (NaN = none, each with its own timestamp from
/// the file names), camera_info with fr1's plumb_bob distortion, plus an /imu topic. `Bag` is
/// either test writer (ROS 1 or rosbag2).
template <class Bag>
void write_tum_frames(Bag& bag, const DatasetReader& folder, size_t frames, const CameraTopics& topics) {
  const CameraModel lens = tum_camera_preset(1);
  for (size_t i = 0; i < frames; ++i) {
    const Frame f = folder.load(i);
    const cv::Mat raw_rgb = cv::imread(f.rgb_path, cv::IMREAD_COLOR);
    const cv::Mat raw_depth_m = read_depth_image(f.depth_path, lens.depth_scale);
    const RosStamp rgb_t = stamp_from_text(fs::path(f.rgb_path).stem().string());
    const RosStamp depth_t = stamp_from_text(fs::path(f.depth_path).stem().string());
    bag.write(colour_message(topics.colour, rgb_t, raw_rgb, "rgb8"));
    bag.write(info_message(topics.colour_info, rgb_t, lens.depth, lens.distortion));
    bag.write(depth_message(topics.depth, depth_t, raw_depth_m, "32FC1"));
    bag.write(info_message(topics.depth_info, depth_t, lens.depth, lens.distortion));
    bag.write_imu("/imu", rgb_t);
  }
}

}  // namespace semap::test::ros
