// OpenNI2 cameras (Kinect v1, Xtion, Orbbec...) and .oni recordings as a FrameSource, through
// PCL's OpenNI2Grabber: its synchronised colour + depth callback fills a small queue that
// next() drains. A camera keeps only the newest frames (the mapper never lags behind it); a
// recording plays as fast as the consumer reads, without losing frames (the callback waits).
#include "io/openni2_source.hpp"

#include "semap/core/error.hpp"

#ifdef SEMAP_WITH_OPENNI2

#include <pcl/io/image.h>
#include <pcl/io/image_depth.h>
#include <pcl/io/openni2/openni2_device.h>
#include <pcl/io/openni2/openni2_device_manager.h>
#include <pcl/io/openni2_grabber.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "io/image_io.hpp"

namespace semap::io_detail {

namespace {

namespace fs = std::filesystem;
using Grabber = pcl::io::OpenNI2Grabber;

constexpr size_t kLiveQueue = 2;         // camera: keep the newest frames only
constexpr size_t kRecordingQueue = 4;    // recording: back-pressure instead of drops
constexpr double kOpenNIDepthScale = 1000.0;  // PIXEL_FORMAT_DEPTH_1_MM
constexpr double kFallbackFocal640 = 525.0;   // Kinect v1 / Xtion at 640 px wide
constexpr auto kCameraTimeout = std::chrono::seconds(5);
constexpr auto kRecordingEndTimeout = std::chrono::seconds(2);

bool has_oni_extension(const std::string& target) {
  return target.size() > 4 && target.compare(target.size() - 4, 4, ".oni") == 0;
}

/// PCL's exception text on one line, without the "void pcl::...(...) in FILE @ LINE : " parts.
std::string pcl_reason(const std::string& what) {
  static const std::regex kLocation(R"((\w+ )?[\w:~]+\([^()]*\)[^:]*?@ \d+ : )");
  static const std::regex kSpaces(R"(\s+)");
  std::string text = std::regex_replace(std::regex_replace(what, kLocation, ""), kSpaces, " ");
  while (!text.empty() && (text.back() == ' ' || text.back() == '.')) text.pop_back();
  return text;
}

std::string connected_uris() {
  std::string out;
  try {
    // Held in a local: a range-for over *temporary() destroys the shared_ptr before the loop
    // runs (ASan: heap-use-after-free).
    const auto uris = pcl::io::openni2::OpenNI2DeviceManager::getInstance()->getConnectedDeviceURIs();
    for (const auto& uri : *uris) out += (out.empty() ? "" : ", ") + uri;
  } catch (const std::exception&) {
  }
  return out.empty() ? "none" : out;
}

/// Pinhole model of the streams. OpenNI2 gives the field of view, not a calibration: the focal
/// length is width / (2 tan(hfov / 2)), principal point at the image centre (as PCL assumes).
CameraModel camera_of(pcl::io::openni2::OpenNI2Device& device, const std::string& where) {
  const auto depth_mode = device.getDepthVideoMode(), colour_mode = device.getColorVideoMode();
  const int w = depth_mode.x_resolution_, h = depth_mode.y_resolution_;
  const int cw = colour_mode.x_resolution_, ch = colour_mode.y_resolution_;
  if (w <= 0 || h <= 0 || cw <= 0 || ch <= 0) throw Error(where, "device reports no depth or colour video mode");
  // With hardware registration on (PCL's grabber enables it when supported) depth is in the colour camera.
  const bool registered = device.isImageRegistrationModeSupported();
  double focal = registered ? device.getColorFocalLength() * w / cw : device.getDepthFocalLength();
  if (!std::isfinite(focal) || focal <= 0) {
    focal = kFallbackFocal640 * w / 640.0;
    spdlog::warn("{}: the device reports no field of view; assuming a focal length of {} px", where, focal);
  }
  CameraModel camera;
  camera.depth_scale = kOpenNIDepthScale;
  camera.depth = {focal, focal, (w - 1) / 2.0, (h - 1) / 2.0, w, h};
  if (cw != w || ch != h) {
    const double s = double(cw) / w;
    camera.colour = CameraModel::ColourCamera{{focal * s, focal * s, (cw - 1) / 2.0, (ch - 1) / 2.0, cw, ch}, Pose::Identity()};
  }
  return camera;
}

class OpenNI2Source final : public FrameSource {
 public:
  OpenNI2Source(std::string spec, const std::string& target) : spec_(std::move(spec)) {
    std::error_code ec;
    recording_ = !target.empty() && fs::is_regular_file(target, ec);
    if (!recording_ && has_oni_extension(target)) throw Error(target, "OpenNI2 recording not found");
    open(target);
  }
  ~OpenNI2Source() override {
    request_stop();
    stop_grabber();
  }

  std::optional<Frame> next() override;
  const CameraModel& camera() const override { return camera_; }
  bool is_live() const override { return !recording_; }
  void request_stop() override {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    changed_.notify_all();
  }
  std::string name() const override { return spec_; }
  size_t size_hint() const override { return frame_count_; }
  size_t dropped_frames() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }

 private:
  void open(const std::string& target);
  void on_frames(const pcl::io::Image::Ptr& image, const pcl::io::DepthImage::Ptr& depth);
  Frame convert(const pcl::io::Image& image, const pcl::io::DepthImage& depth) const;
  void stop_grabber() {
    std::call_once(grabber_stopped_, [&] {
      try {
        grabber_->stop();
      } catch (...) {  // a device unplugged mid-run must not abort the shutdown
      }
    });
  }

  std::string spec_;
  bool recording_ = false;
  std::unique_ptr<Grabber> grabber_;
  std::once_flag grabber_stopped_;
  CameraModel camera_;
  size_t frame_count_ = 0;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Frame> queue_;
  bool stop_ = false, ended_ = false;
  size_t delivered_ = 0, dropped_ = 0;
  long last_frame_id_ = -1;
};

void OpenNI2Source::open(const std::string& target) {
  const std::string where = target.empty() ? "openni2" : spec_;
  try {
    grabber_ = std::make_unique<Grabber>(target);
  } catch (const std::exception& e) {
    const std::string reason = pcl_reason(e.what());
    if (reason.find("No devices connected") != std::string::npos)
      throw Error(where, "no OpenNI2 camera connected (or no permission to open its USB device)");
    throw Error(where, "cannot open the OpenNI2 " + std::string(recording_ ? "recording" : "device") + " (" + reason +
                           "); connected devices: " + connected_uris());
  }
  auto device = grabber_->getDevice();
  if (!device->hasColorSensor()) throw Error(where, "the device has no colour camera");
  std::function<Grabber::sig_cb_openni_image_depth_image> callback =
      [this](const pcl::io::Image::Ptr& image, const pcl::io::DepthImage::Ptr& depth, float) { on_frames(image, depth); };
  try {
    grabber_->registerCallback(callback);
    if (recording_) {
      device->setPlaybackSpeed(0.0);  // as fast as next() is called; the queue paces the player
      frame_count_ = static_cast<size_t>(std::max(0, std::min(device->getDepthFrameCount(), device->getColorFrameCount())));
    }
    grabber_->start();
  } catch (const std::exception& e) {
    throw Error(where, "cannot start the colour and depth streams: " + pcl_reason(e.what()));
  }
  camera_ = camera_of(*device, where);
  validate_camera(camera_, where);  // issue 44: the same camera check as every dataset reader
}

Frame OpenNI2Source::convert(const pcl::io::Image& image, const pcl::io::DepthImage& depth) const {
  Frame frame;
  cv::Mat rgb(static_cast<int>(image.getHeight()), static_cast<int>(image.getWidth()), CV_8UC3);
  image.fillRGB(image.getWidth(), image.getHeight(), rgb.data);
  cv::cvtColor(rgb, frame.rgb, cv::COLOR_RGB2BGR);
  cv::Mat raw(static_cast<int>(depth.getHeight()), static_cast<int>(depth.getWidth()), CV_16UC1);
  depth.fillDepthImageRaw(depth.getWidth(), depth.getHeight(), raw.ptr<unsigned short>());
  frame.depth = depth_units_to_metres(raw, kOpenNIDepthScale);
  frame.timestamp = depth.getTimestamp() * 1e-6;  // device clock, microseconds
  frame.rgb_path = frame.depth_path = spec_ + "#" + std::to_string(depth.getFrameID());
  return frame;
}

void OpenNI2Source::on_frames(const pcl::io::Image::Ptr& image, const pcl::io::DepthImage::Ptr& depth) {
  Frame frame = convert(*image, *depth);  // outside the lock: next() keeps draining meanwhile
  std::unique_lock<std::mutex> lock(mutex_);
  if (stop_ || ended_) return;
  const long id = static_cast<long>(depth->getFrameID());
  if (recording_ && id <= last_frame_id_) {  // the player started over: the recording has ended
    ended_ = true;
    changed_.notify_all();
    return;
  }
  last_frame_id_ = id;
  if (recording_) {
    changed_.wait(lock, [&] { return stop_ || queue_.size() < kRecordingQueue; });
    if (stop_) return;
  } else if (queue_.size() >= kLiveQueue) {
    queue_.pop_front();
    ++dropped_;
  }
  queue_.push_back(std::move(frame));
  changed_.notify_all();
}

std::optional<Frame> OpenNI2Source::next() {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto timeout = recording_ ? kRecordingEndTimeout : kCameraTimeout;
  const bool got = changed_.wait_for(lock, timeout, [&] { return stop_ || ended_ || !queue_.empty(); });
  if (stop_) {  // the camera stops streaming now, while the caller finishes its map
    lock.unlock();
    stop_grabber();
    return std::nullopt;
  }
  if (!got) {
    if (recording_) return std::nullopt;  // the player stopped delivering: end of the recording
    throw Error(spec_, "no frame from the camera for " + std::to_string(kCameraTimeout.count()) + " s (unplugged?)");
  }
  if (queue_.empty()) {  // the recording ended: stop its player (it would loop)
    lock.unlock();
    stop_grabber();
    return std::nullopt;
  }
  Frame frame = std::move(queue_.front());
  queue_.pop_front();
  frame.index = delivered_++;
  changed_.notify_all();  // room for the recording's player
  return frame;
}

}  // namespace

bool openni2_available() { return true; }

std::unique_ptr<FrameSource> open_openni2(const std::string& spec, const std::string& target) {
  return std::make_unique<OpenNI2Source>(spec, target);
}

}  // namespace semap::io_detail

#else  // !SEMAP_WITH_OPENNI2

namespace semap::io_detail {

bool openni2_available() { return false; }

std::unique_ptr<FrameSource> open_openni2(const std::string& spec, const std::string&) {
  throw Error(spec, "this semap was built without OpenNI2 support (install libpcl-dev and libopenni2-dev, then rebuild)");
}

}  // namespace semap::io_detail

#endif
