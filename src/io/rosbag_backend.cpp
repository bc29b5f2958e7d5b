// ROS1 bag access (see rosbag_backend.hpp). Built as C++17 (src/io/CMakeLists.txt).
#include "io/rosbag_backend.hpp"

#include "semap/core/error.hpp"

#ifdef SEMAP_WITH_ROSBAG

#include <console_bridge/console.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <mutex>
#include <new>

namespace semap::io_detail::rosbag_backend {

namespace {

// Header and image metadata only: deserialised from the record without copying the pixels.
// The "*" MD5 sum makes rosbag accept it for any connection; callers check the datatype.
template <bool kCompressed>
struct MetaMessage {
  ImageMeta meta;
};

}  // namespace
}  // namespace semap::io_detail::rosbag_backend

namespace ros::message_traits {
template <bool C>
struct MD5Sum<semap::io_detail::rosbag_backend::MetaMessage<C>> {
  static const char* value() { return "*"; }
  static const char* value(const semap::io_detail::rosbag_backend::MetaMessage<C>&) { return "*"; }
};
template <bool C>
struct DataType<semap::io_detail::rosbag_backend::MetaMessage<C>> {
  static const char* value() { return "*"; }
  static const char* value(const semap::io_detail::rosbag_backend::MetaMessage<C>&) { return "*"; }
};
}  // namespace ros::message_traits

namespace ros::serialization {
template <bool C>
struct Serializer<semap::io_detail::rosbag_backend::MetaMessage<C>> {
  // std_msgs/Header (seq, stamp, frame_id), then Image: height, width, encoding, ... or
  // CompressedImage: format, data.
  template <typename Stream>
  static void read(Stream& stream, semap::io_detail::rosbag_backend::MetaMessage<C>& m) {
    uint32_t seq = 0;
    std::string frame_id;
    stream.next(seq);
    stream.next(m.meta.header_stamp.sec);
    stream.next(m.meta.header_stamp.nsec);
    stream.next(frame_id);
    if constexpr (!C) {
      stream.next(m.meta.height);
      stream.next(m.meta.width);
    }
    stream.next(m.meta.encoding);
  }
};
}  // namespace ros::serialization

namespace semap::io_detail::rosbag_backend {

namespace {

MessageType type_of(const std::string& datatype) {
  if (datatype == "sensor_msgs/Image") return MessageType::image;
  if (datatype == "sensor_msgs/CompressedImage") return MessageType::compressed_image;
  if (datatype == "sensor_msgs/CameraInfo") return MessageType::camera_info;
  return MessageType::other;
}

Stamp stamp_of(const ros::Time& t) { return {t.sec, t.nsec}; }

/// Header stamp, size and encoding of an Image / CompressedImage message, and its bag time.
ImageMeta meta_of(const rosbag::MessageInstance& m, const std::filesystem::path& bag) {
  ImageMeta meta;
  const MessageType type = type_of(m.getDataType());
  if (type == MessageType::image) meta = m.instantiate<MetaMessage<false>>()->meta;
  else if (type == MessageType::compressed_image) meta = m.instantiate<MetaMessage<true>>()->meta;
  else throw Error(bag, m.getTopic() + " is " + m.getDataType() + ", not an image topic");
  meta.bag_stamp = stamp_of(m.getTime());
  return meta;
}

CompressedData compressed_of(sensor_msgs::CompressedImage& msg) {
  CompressedData out;
  out.format = msg.format;
  out.data.swap(msg.data);
  return out;
}

}  // namespace

bool available() { return true; }

struct Bag::Impl {
  std::filesystem::path path;
  rosbag::Bag bag;
  std::mutex mutex;
  std::vector<rosbag::MessageInstance> messages;  ///< indexed messages, by handle

  /// Runs f under the lock, turning rosbag's exceptions into one semap::Error naming the bag.
  template <class F>
  auto guarded(const std::string& what, F&& f) {
    std::lock_guard<std::mutex> lock(mutex);
    try {
      return f();
    } catch (const rosbag::BagException& e) {
      throw Error(path, what + ": " + e.what() + " (corrupt or truncated bag?)");
    } catch (const ros::Exception& e) {
      throw Error(path, what + ": " + e.what() + " (corrupt or truncated bag?)");
    } catch (const std::bad_alloc&) {
      throw Error(path, what + ": implausible record size (corrupt bag?)");
    } catch (const std::length_error&) {
      throw Error(path, what + ": implausible record size (corrupt bag?)");
    }
  }

  template <class T>
  boost::shared_ptr<T> first(const std::string& topic) {
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& m : view)
      if (auto p = m.instantiate<T>()) return p;
    throw Error(path, "topic " + topic + " has no readable message");
  }

  const rosbag::MessageInstance& message(size_t handle) const {
    if (handle >= messages.size()) throw Error(path, "message handle out of range");
    return messages[handle];
  }
};

Bag::Bag(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  // rosbag also logs its errors through console_bridge; the exception says it once.
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
  impl_->guarded("cannot open bag", [&] {
    impl_->bag.open(path.string(), rosbag::bagmode::Read);
    return 0;
  });
}

Bag::~Bag() = default;

const std::filesystem::path& Bag::path() const { return impl_->path; }

std::vector<Topic> Bag::topics() const {
  return impl_->guarded("cannot list topics", [&] {
    rosbag::View view(impl_->bag);
    std::vector<Topic> topics;
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      bool seen = false;
      for (const Topic& t : topics) seen |= t.name == c->topic;
      if (!seen) topics.push_back({c->topic, c->datatype, type_of(c->datatype), 0});
    }
    for (Topic& t : topics) t.messages = rosbag::View(impl_->bag, rosbag::TopicQuery(t.name)).size();
    return topics;
  });
}

ImageMeta Bag::first_image_meta(const std::string& topic) const {
  return impl_->guarded("cannot read " + topic, [&] {
    rosbag::View view(impl_->bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& m : view) return meta_of(m, impl_->path);
    throw Error(impl_->path, "topic " + topic + " has no message");
  });
}

CompressedData Bag::first_compressed(const std::string& topic) const {
  return impl_->guarded("cannot read " + topic, [&] {
    return compressed_of(*impl_->first<sensor_msgs::CompressedImage>(topic));
  });
}

CameraInfoData Bag::first_camera_info(const std::string& topic) const {
  return impl_->guarded("cannot read " + topic, [&] {
    const auto info = impl_->first<sensor_msgs::CameraInfo>(topic);
    CameraInfoData out;
    out.header_stamp = stamp_of(info->header.stamp);
    out.width = info->width;
    out.height = info->height;
    for (size_t k = 0; k < 9; ++k) out.K[k] = info->K[k];
    out.distortion_model = info->distortion_model;
    out.D = info->D;
    return out;
  });
}

std::vector<IndexedMessage> Bag::index(const std::vector<std::string>& topics) const {
  return impl_->guarded("cannot index the image topics", [&] {
    rosbag::View view(impl_->bag, rosbag::TopicQuery(topics));
    std::vector<IndexedMessage> out;
    for (const rosbag::MessageInstance& m : view) {
      IndexedMessage im;
      for (size_t k = 0; k < topics.size(); ++k)
        if (topics[k] == m.getTopic()) im.topic = k;
      im.meta = meta_of(m, impl_->path);
      im.handle = impl_->messages.size();
      impl_->messages.push_back(m);
      out.push_back(std::move(im));
    }
    return out;
  });
}

ImageData Bag::read_image(size_t handle) const {
  return impl_->guarded("cannot read an image message", [&] {
    const auto msg = impl_->message(handle).instantiate<sensor_msgs::Image>();
    if (!msg) throw Error(impl_->path, impl_->message(handle).getTopic() + ": not a sensor_msgs/Image");
    ImageData out;
    out.width = msg->width;
    out.height = msg->height;
    out.step = msg->step;
    out.big_endian = msg->is_bigendian != 0;
    out.encoding = msg->encoding;
    out.data.swap(msg->data);
    return out;
  });
}

CompressedData Bag::read_compressed(size_t handle) const {
  return impl_->guarded("cannot read a compressed image message", [&] {
    const auto msg = impl_->message(handle).instantiate<sensor_msgs::CompressedImage>();
    if (!msg) throw Error(impl_->path, impl_->message(handle).getTopic() + ": not a sensor_msgs/CompressedImage");
    return compressed_of(*msg);
  });
}

}  // namespace semap::io_detail::rosbag_backend

#else  // !SEMAP_WITH_ROSBAG

namespace semap::io_detail::rosbag_backend {

bool available() { return false; }

struct Bag::Impl {};

Bag::Bag(const std::filesystem::path& path) {
  throw Error(path, "this semap was built without ROS bag support (install librosbag-storage-dev and "
                    "libsensor-msgs-dev, then rebuild)");
}
Bag::~Bag() = default;
const std::filesystem::path& Bag::path() const { throw Error("rosbag", "built without ROS bag support"); }
std::vector<Topic> Bag::topics() const { return {}; }
ImageMeta Bag::first_image_meta(const std::string&) const { return {}; }
CompressedData Bag::first_compressed(const std::string&) const { return {}; }
CameraInfoData Bag::first_camera_info(const std::string&) const { return {}; }
std::vector<IndexedMessage> Bag::index(const std::vector<std::string>&) const { return {}; }
ImageData Bag::read_image(size_t) const { return {}; }
CompressedData Bag::read_compressed(size_t) const { return {}; }

}  // namespace semap::io_detail::rosbag_backend

#endif
