// ROS bags as a dataset (ROS1 .bag, and rosbag2 through the same BagSource: rosbag2_bag.hpp):
// one colour and one depth image topic (sensor_msgs/Image or CompressedImage), intrinsics from their sensor_msgs/CameraInfo (K), colour and depth
// associated by header timestamp like the TUM lists. Opening indexes the messages (each
// record is read once for its header, the pixels are not decoded); load(i) decodes frame i.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <opencv2/imgproc.hpp>

#include "semap/core/error.hpp"
#include "io/association.hpp"
#include "io/dataset_layouts.hpp"
#include "io/image_io.hpp"
#include "io/rosbag2_bag.hpp"
#include "io/rosbag_backend.hpp"
#include "semap/io/trajectory_io.hpp"

namespace semap::io_detail {

namespace fs = std::filesystem;
namespace rb = rosbag_backend;

namespace {

// REP 118: 16UC1 depth images are millimetres (32FC1 ones metres; the scale then only
// matters to consumers that store depth in 16-bit units).
constexpr double kRosDepthScale = 1000.0;
constexpr uint32_t kMaxImageSide = 16384;

enum class Role { colour, depth, unsupported };

struct ImageTopic {
  std::string name;
  bool compressed = false;
  std::string encoding;  ///< Image: encoding; CompressedImage: format
  Role role = Role::unsupported;
};

std::string first_token(const std::string& format) {
  std::string token = format.substr(0, format.find(';'));
  token.erase(std::remove(token.begin(), token.end(), ' '), token.end());
  return token;
}

bool is_colour_encoding(const std::string& e) {
  return e == "rgb8" || e == "bgr8" || e == "mono8" || e == "rgba8" || e == "bgra8";
}
bool is_depth_encoding(const std::string& e) { return e == "16UC1" || e == "32FC1"; }

Role role_of(bool compressed, const std::string& encoding) {
  if (!compressed) return is_colour_encoding(encoding) ? Role::colour : is_depth_encoding(encoding) ? Role::depth : Role::unsupported;
  if (encoding.find("rvl") != std::string::npos) return Role::unsupported;
  const std::string token = first_token(encoding);
  if (encoding.find("compressedDepth") != std::string::npos || is_depth_encoding(token)) return Role::depth;
  if (is_colour_encoding(token) || token == "jpeg" || token == "png") return Role::colour;
  return Role::unsupported;
}

/// Exactly the decimal value sec.nsec, correctly rounded: a bag written from a TUM list gives
/// back the list's timestamps bit for bit.
double stamp_seconds(rb::Stamp s) {
  if (s.nsec >= 1000000000u) return s.sec + s.nsec * 1e-9;
  char text[32];
  const int n = std::snprintf(text, sizeof text, "%u.%09u", s.sec, s.nsec);
  double value = 0;
  std::from_chars(text, text + n, value);
  return value;
}

std::string stamp_text(rb::Stamp s) {
  char text[32];
  std::snprintf(text, sizeof text, "%u.%09u", s.sec, s.nsec);
  return text;
}

std::string without_slash(const std::string& topic) { return topic.rfind('/', 0) == 0 ? topic.substr(1) : topic; }

std::string names(const std::vector<ImageTopic>& topics) {
  std::string out;
  for (const auto& t : topics) out += (out.empty() ? "" : ", ") + t.name + " (" + t.encoding + ")";
  return out.empty() ? "none" : out;
}

/// image_transport republishes X as X/compressed and X/compressedDepth: the same stream.
std::string base_topic(const std::string& name) {
  for (const std::string suffix : {"/compressed", "/compressedDepth"})
    if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
      return name.substr(0, name.size() - suffix.size());
  return name;
}

const ImageTopic& choose_topic(const std::vector<ImageTopic>& topics, Role role, const std::string& requested,
                               const fs::path& bag) {
  const std::string what = role == Role::colour ? "colour" : "depth";
  const std::string flag = role == Role::colour ? "--rgb-topic (dataset option rgb_topic)"
                                                : "--depth-topic (dataset option depth_topic)";
  if (!requested.empty()) {
    for (const auto& t : topics) {
      if (without_slash(t.name) != without_slash(requested)) continue;
      if (t.role != role) throw Error(bag, t.name + " has encoding '" + t.encoding + "', not a supported " + what + " image");
      return t;
    }
    throw Error(bag, "no image topic " + requested + " (image topics: " + names(topics) + ")");
  }
  std::vector<const ImageTopic*> candidates;
  for (const auto& t : topics)
    if (t.role == role) candidates.push_back(&t);
  std::erase_if(candidates, [&](const ImageTopic* t) {
    return t->compressed && std::any_of(candidates.begin(), candidates.end(), [&](const ImageTopic* raw) {
             return !raw->compressed && raw->name == base_topic(t->name);
           });
  });
  if (candidates.size() == 1) return *candidates.front();
  if (candidates.empty())
    throw Error(bag, "no " + what + " image topic (" +
                         (role == Role::colour ? "rgb8, bgr8, mono8, rgba8, bgra8 or a compressed colour image"
                                               : "16UC1, 32FC1 or compressedDepth") +
                         "); image topics: " + names(topics));
  std::string list;
  for (const auto* t : candidates) list += (list.empty() ? "" : ", ") + t->name;
  throw Error(bag, "several " + what + " image topics (" + list + "); choose one with " + flag);
}

/// The CameraInfo of an image topic: <namespace>/camera_info (ROS convention), else the only
/// CameraInfo topic of the bag.
std::optional<std::string> camera_info_topic(const std::vector<rb::Topic>& topics, const std::string& image_topic) {
  const std::string base = base_topic(image_topic);
  const std::string wanted = base.substr(0, base.rfind('/') + 1) + "camera_info";
  std::vector<std::string> infos;
  for (const auto& t : topics)
    if (t.type == rb::MessageType::camera_info) infos.push_back(t.name);
  for (const auto& name : infos)
    if (without_slash(name) == without_slash(wanted)) return name;
  if (infos.size() == 1) return infos.front();
  return std::nullopt;
}

PinholeIntrinsics intrinsics_from(const rb::CameraInfoData& info, const rb::ImageMeta& image, const fs::path& bag,
                                  const std::string& info_topic) {
  PinholeIntrinsics k;
  k.fx = info.K[0], k.fy = info.K[4], k.cx = info.K[2], k.cy = info.K[5];
  for (double v : info.K)
    if (!std::isfinite(v)) throw Error(bag, info_topic + ": NaN or Inf in K");
  if (!(k.fx > 0 && k.fy > 0)) throw Error(bag, info_topic + ": K has no positive focal lengths (uncalibrated camera?)");
  const bool has_size = info.width > 0 && info.height > 0;
  if (has_size && (info.width != image.width || info.height != image.height))
    throw Error(bag, info_topic + " is " + std::to_string(info.width) + "x" + std::to_string(info.height) +
                         " but its images are " + std::to_string(image.width) + "x" + std::to_string(image.height));
  k.width = static_cast<int>(image.width);
  k.height = static_cast<int>(image.height);
  return k;
}

/// The CameraInfo's lens distortion in OpenCV order (k1 k2 p1 p2 k3), undistorted where frames
/// enter (DatasetReader::load). plumb_bob is exact; rational_polynomial's k4..k6 are not
/// modelled (warned); another model with a non-zero D (equidistant fisheye) keeps the images
/// as they are (warned).
std::array<double, 5> distortion_from(const rb::CameraInfoData& info, const fs::path& bag,
                                      const std::string& info_topic) {
  std::array<double, 5> d{0, 0, 0, 0, 0};
  const bool any = std::any_of(info.D.begin(), info.D.end(), [](double v) { return v != 0; });
  if (!any) return d;
  for (double v : info.D)
    if (!std::isfinite(v)) throw Error(bag, info_topic + ": NaN or Inf in D");
  const bool plumb_bob = info.distortion_model == "plumb_bob" && info.D.size() == 5;
  const bool rational = info.distortion_model == "rational_polynomial" && info.D.size() == 8;
  if (!plumb_bob && !rational) {
    spdlog::warn("{}: {} has lens distortion model '{}' with {} coefficients; semap undistorts plumb_bob and "
                 "rational_polynomial only and uses these images as they are (pinhole)",
                 bag.string(), info_topic, info.distortion_model, info.D.size());
    return d;
  }
  std::copy_n(info.D.begin(), 5, d.begin());
  if (rational && std::any_of(info.D.begin() + 5, info.D.end(), [](double v) { return v != 0; }))
    spdlog::warn("{}: {}: rational_polynomial k4..k6 are not modelled; undistorting with k1 k2 p1 p2 k3", bag.string(),
                 info_topic);
  return d;
}

/// One image message of a stream, in time order.
struct StreamMessage {
  double t = 0;
  rb::Stamp stamp;
  size_t handle = 0;
};

std::vector<StreamMessage> stream_of(const std::vector<rb::IndexedMessage>& messages, size_t topic,
                                     const std::string& name, const fs::path& bag) {
  std::vector<StreamMessage> out;
  for (const auto& m : messages) {
    if (m.topic != topic) continue;
    // The sensor's stamp (what TUM's lists hold); the recording time when the driver left it 0.
    const rb::Stamp s = m.meta.header_stamp.is_zero() ? m.meta.bag_stamp : m.meta.header_stamp;
    out.push_back({stamp_seconds(s), s, m.handle});
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  const size_t before = out.size();
  out.erase(std::unique(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.t == b.t; }), out.end());
  if (out.size() != before)
    spdlog::warn("{}: {} has {} messages with a repeated timestamp; keeping the first of each", bag.string(), name,
                 before - out.size());
  return out;
}

// ------------------------------------------------------------------ decoding

void check_layout(const rb::ImageData& im, size_t bytes_per_pixel, const std::string& where) {
  if (im.width == 0 || im.height == 0 || im.width > kMaxImageSide || im.height > kMaxImageSide)
    throw Error(where, "implausible image size " + std::to_string(im.width) + "x" + std::to_string(im.height));
  if (im.step < im.width * bytes_per_pixel) throw Error(where, "row step " + std::to_string(im.step) + " shorter than a row");
  const size_t expected = size_t{im.step} * im.height;
  if (im.data.size() != expected)
    throw Error(where, "image data has " + std::to_string(im.data.size()) + " bytes, height x step is " +
                           std::to_string(expected) + (im.data.size() < expected ? " (truncated message)" : ""));
}

cv::Mat decode_raw_colour(rb::ImageData im, const std::string& where) {
  const std::string& e = im.encoding;
  if (!is_colour_encoding(e)) throw Error(where, "colour encoding '" + e + "' is not supported (rgb8, bgr8, mono8, rgba8, bgra8)");
  const int channels = e == "mono8" ? 1 : (e == "rgb8" || e == "bgr8") ? 3 : 4;
  check_layout(im, channels, where);
  const cv::Mat view(static_cast<int>(im.height), static_cast<int>(im.width), CV_8UC(channels), im.data.data(), im.step);
  cv::Mat bgr;  // always a copy: `view` points into the message
  if (e == "rgb8") cv::cvtColor(view, bgr, cv::COLOR_RGB2BGR);
  else if (e == "rgba8") cv::cvtColor(view, bgr, cv::COLOR_RGBA2BGR);
  else if (e == "bgr8") view.copyTo(bgr);
  else bgr = to_bgr(where, view);  // mono8, bgra8: converted into a new image
  return bgr;
}

template <class T>
T host_order(const uint8_t* p, bool big_endian) {
  T v;
  std::memcpy(&v, p, sizeof v);
  if (big_endian) {
    uint8_t b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    std::reverse(b, b + sizeof v);
    std::memcpy(&v, b, sizeof v);
  }
  return v;
}

cv::Mat millimetres_to_metres(const cv::Mat& raw) { return depth_units_to_metres(raw, kRosDepthScale); }

cv::Mat decode_raw_depth(const rb::ImageData& im, const std::string& where) {
  const bool mm = im.encoding == "16UC1";
  if (!mm && im.encoding != "32FC1") throw Error(where, "depth encoding '" + im.encoding + "' is not supported (16UC1, 32FC1)");
  check_layout(im, mm ? 2 : 4, where);
  const int rows = static_cast<int>(im.height), cols = static_cast<int>(im.width);
  if (mm) {
    cv::Mat raw(rows, cols, CV_16UC1);
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) raw.at<uint16_t>(r, c) = host_order<uint16_t>(&im.data[r * size_t{im.step} + 2 * c], im.big_endian);
    return millimetres_to_metres(raw);
  }
  cv::Mat depth(rows, cols, CV_32FC1);
  for (int r = 0; r < rows; ++r) {
    float* out = depth.ptr<float>(r);
    for (int c = 0; c < cols; ++c) {
      const float v = host_order<float>(&im.data[r * size_t{im.step} + 4 * c], im.big_endian);
      out[c] = std::isfinite(v) && v > 0 ? v : 0.0f;  // NaN = no measurement
    }
  }
  return depth;
}

/// image_transport compresses colour as bgr8 (or mono8), which is how OpenCV decodes it.
cv::Mat decode_compressed_colour(const rb::CompressedData& msg, const std::string& where) {
  return decode_colour_bytes(std::string(msg.data.begin(), msg.data.end()), where);
}

/// compressedDepth (image_transport): a 12-byte header (format, depthQuantA, depthQuantB) then a
/// 16-bit PNG of millimetres (16UC1) or of quantised inverse depth (32FC1: z = A / (v - B)).
cv::Mat decode_compressed_depth(const rb::CompressedData& msg, const std::string& where) {
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto& d = msg.data;
  const std::string encoding = first_token(msg.format);
  if (msg.format.find("rvl") != std::string::npos) throw Error(where, "RVL-compressed depth is not supported (use png)");
  size_t offset = 0;
  if (d.size() > 20 && std::memcmp(d.data() + 12, kPng, 8) == 0) offset = 12;
  else if (d.size() < 8 || std::memcmp(d.data(), kPng, 8) != 0) throw Error(where, "compressed depth is not a PNG");
  const cv::Mat raw = decode_image_bytes(std::string(d.begin() + offset, d.end()), where);
  if (raw.type() != CV_16UC1) throw Error(where, "compressed depth PNG is not 16-bit single-channel");
  if (encoding != "32FC1") return millimetres_to_metres(raw);
  if (offset == 0) throw Error(where, "32FC1 compressedDepth without its quantisation header");
  float quant_a = 0, quant_b = 0;
  std::memcpy(&quant_a, d.data() + 4, 4);
  std::memcpy(&quant_b, d.data() + 8, 4);
  cv::Mat depth(raw.size(), CV_32FC1);
  for (int r = 0; r < raw.rows; ++r)
    for (int c = 0; c < raw.cols; ++c) {
      const uint16_t v = raw.at<uint16_t>(r, c);
      const float z = v ? quant_a / (static_cast<float>(v) - quant_b) : 0.0f;
      depth.at<float>(r, c) = std::isfinite(z) && z > 0 ? z : 0.0f;
    }
  return depth;
}

// ------------------------------------------------------------------ the reader

class RosbagDataset : public DatasetReader {
 public:
  RosbagDataset(std::string format, std::unique_ptr<rb::BagSource> bag, const ImageTopic& rgb, const ImageTopic& depth)
      : format_(std::move(format)), bag_(std::move(bag)), rgb_(rgb), depth_(depth) {
    root_ = bag_->path();
  }
  std::string format() const override { return format_; }

  cv::Mat decode_depth(size_t i) const override {
    check_index(i);
    const std::string where = records_[i].depth.string();
    cv::Mat depth = depth_.compressed ? decode_compressed_depth(bag_->read_compressed(handles_[i].second), where)
                                      : decode_raw_depth(bag_->read_image(handles_[i].second), where);
    if (depth.cols != camera_.depth.width || depth.rows != camera_.depth.height)
      throw Error(where, "depth image is " + std::to_string(depth.cols) + "x" + std::to_string(depth.rows) +
                             ", camera expects " + std::to_string(camera_.depth.width) + "x" +
                             std::to_string(camera_.depth.height));
    return depth;
  }

  Frame decode(size_t i) const override {
    cv::Mat depth = decode_depth(i);  // checks i
    const std::string where = records_[i].rgb.string();
    cv::Mat rgb = rgb_.compressed ? decode_compressed_colour(bag_->read_compressed(handles_[i].first), where)
                                  : decode_raw_colour(bag_->read_image(handles_[i].first), where);
    return make_frame(i, std::move(depth), std::move(rgb), records_[i].rgb);
  }

  using DatasetReader::set_camera;
  void add_frame(FrameRecord record, size_t rgb_handle, size_t depth_handle) {
    records_.push_back(std::move(record));
    handles_.emplace_back(rgb_handle, depth_handle);
  }
  void attach(const Trajectory& ground_truth) { attach_ground_truth(records_, ground_truth); }

 private:
  std::string format_;
  std::unique_ptr<rb::BagSource> bag_;
  ImageTopic rgb_, depth_;
  std::vector<std::pair<size_t, size_t>> handles_;  ///< per frame: colour, depth message
};

/// Size and metadata of a topic's first image (a compressed one is decoded for its size).
rb::ImageMeta first_image(const rb::BagSource& bag, const ImageTopic& topic) {
  rb::ImageMeta meta = bag.first_image_meta(topic.name);
  if (!topic.compressed) return meta;
  const std::string where = bag.path().string() + ":" + topic.name;
  const rb::CompressedData msg = bag.first_compressed(topic.name);
  const cv::Mat image = topic.role == Role::depth ? decode_compressed_depth(msg, where) : decode_compressed_colour(msg, where);
  meta.width = static_cast<uint32_t>(image.cols);
  meta.height = static_cast<uint32_t>(image.rows);
  return meta;
}

std::vector<ImageTopic> image_topics(const rb::BagSource& bag, const std::vector<rb::Topic>& topics) {
  std::vector<ImageTopic> out;
  for (const auto& t : topics) {
    if (t.type != rb::MessageType::image && t.type != rb::MessageType::compressed_image) continue;
    if (t.messages == 0) continue;
    ImageTopic it;
    it.name = t.name;
    it.compressed = t.type == rb::MessageType::compressed_image;
    it.encoding = bag.first_image_meta(t.name).encoding;
    it.role = role_of(it.compressed, it.encoding);
    out.push_back(std::move(it));
  }
  return out;
}

/// Depth intrinsics from the depth topic's CameraInfo (else the colour one's); a separate
/// colour camera when the colour CameraInfo differs (extrinsic: identity, /tf is not read).
CameraModel bag_camera(const rb::BagSource& bag, const std::vector<rb::Topic>& topics, const ImageTopic& rgb,
                       const ImageTopic& depth) {
  const fs::path& path = bag.path();
  const rb::ImageMeta rgb_meta = first_image(bag, rgb), depth_meta = first_image(bag, depth);
  auto depth_info = camera_info_topic(topics, depth.name), rgb_info = camera_info_topic(topics, rgb.name);
  if (!depth_info && !rgb_info)
    throw Error(path, "no sensor_msgs/CameraInfo for " + depth.name + " or " + rgb.name + " (intrinsics unknown)");
  CameraModel camera;
  camera.depth_scale = kRosDepthScale;
  if (!depth_info) spdlog::warn("{}: no CameraInfo for {}; using {} (depth registered to colour)", path.string(), depth.name, *rgb_info);
  const std::string depth_info_name = depth_info ? *depth_info : *rgb_info;
  // Issue 44: one CameraInfo serves both cameras (registered images) only at one resolution. At
  // another, the second camera's intrinsics are unknown: scaling them is right only for the same
  // lens and sensor crop, which a bag does not say, so it is an error (also when the CameraInfo
  // gives no size to compare with).
  const auto size_text = [](const rb::ImageMeta& m) { return std::to_string(m.width) + "x" + std::to_string(m.height); };
  if ((!rgb_info || *rgb_info == depth_info_name) && size_text(rgb_meta) != size_text(depth_meta))
    throw Error(path, "only " + depth_info_name + " describes both " + rgb.name + " (" + size_text(rgb_meta) + ") and " +
                          depth.name + " (" + size_text(depth_meta) + "): the intrinsics at the other resolution are "
                          "unknown (give each image topic its own CameraInfo)");
  const rb::CameraInfoData depth_camera_info = bag.first_camera_info(depth_info_name);
  camera.depth = intrinsics_from(depth_camera_info, depth_meta, path, depth_info_name);
  camera.distortion = distortion_from(depth_camera_info, path, depth_info_name);
  const std::string rgb_info_name = rgb_info ? *rgb_info : *depth_info;
  const rb::CameraInfoData rgb_camera_info = bag.first_camera_info(rgb_info_name);
  PinholeIntrinsics colour = intrinsics_from(rgb_camera_info, rgb_meta, path, rgb_info_name);
  if (!(colour == camera.depth)) {
    spdlog::warn("{}: colour and depth cameras differ; registering colour to depth with an identity extrinsic "
                 "(the bag's /tf is not read)", path.string());
    camera.colour = CameraModel::ColourCamera{colour, Pose::Identity()};
    if (distortion_from(rgb_camera_info, path, rgb_info_name) != std::array<double, 5>{0, 0, 0, 0, 0})
      spdlog::warn("{}: {} has lens distortion; only the depth camera's is corrected", path.string(), rgb_info_name);
  }
  return camera;
}

void index_frames(RosbagDataset& reader, const rb::BagSource& bag, const ImageTopic& rgb, const ImageTopic& depth) {
  const auto messages = bag.index({rgb.name, depth.name});
  const auto rgb_stream = stream_of(messages, 0, rgb.name, bag.path());
  const auto depth_stream = stream_of(messages, 1, depth.name, bag.path());
  std::vector<double> rgb_t, depth_t;
  for (const auto& m : rgb_stream) rgb_t.push_back(m.t);
  for (const auto& m : depth_stream) depth_t.push_back(m.t);
  const auto pairs = associate_timestamps(rgb_t, depth_t, kMaxTimeDifference);
  for (const auto& [i, j] : pairs) {
    FrameRecord r;
    r.timestamp = rgb_stream[i].t;
    r.rgb = bag.path().string() + ":" + rgb.name + "@" + stamp_text(rgb_stream[i].stamp);
    r.depth = bag.path().string() + ":" + depth.name + "@" + stamp_text(depth_stream[j].stamp);
    reader.add_frame(std::move(r), rgb_stream[i].handle, depth_stream[j].handle);
  }
  if (pairs.size() < rgb_stream.size())
    spdlog::info("{}: {} of {} colour images have no depth image within {} s", bag.path().string(),
                 rgb_stream.size() - pairs.size(), rgb_stream.size(), kMaxTimeDifference);
}

}  // namespace

std::unique_ptr<DatasetReader> open_bag_source(std::unique_ptr<rb::BagSource> bag, const std::string& format,
                                               const DatasetOptions& options) {
  const fs::path path = bag->path();
  const auto topics = bag->topics();
  const auto images = image_topics(*bag, topics);
  const ImageTopic rgb = choose_topic(images, Role::colour, options.rgb_topic, path);
  const ImageTopic depth = choose_topic(images, Role::depth, options.depth_topic, path);
  const CameraModel camera = bag_camera(*bag, topics, rgb, depth);
  const rb::BagSource& bag_ref = *bag;
  auto reader = std::make_unique<RosbagDataset>(format, std::move(bag), rgb, depth);
  reader->set_camera(camera, path.string());
  index_frames(*reader, bag_ref, rgb, depth);
  // TUM publishes each bag's ground truth beside it as <name>-groundtruth.txt.
  const fs::path gt = path.parent_path() / (path.stem().string() + "-groundtruth.txt");
  if (fs::exists(gt)) reader->attach(read_tum_trajectory(gt));
  return reader;
}

std::unique_ptr<DatasetReader> open_rosbag(const fs::path& path, const DatasetOptions& options) {
  return open_bag_source(std::make_unique<rb::Bag>(path), "rosbag", options);
}

std::unique_ptr<DatasetReader> open_rosbag2(const fs::path& path, const DatasetOptions& options) {
  return open_bag_source(open_rosbag2_source(path), "rosbag2", options);
}

}  // namespace semap::io_detail
