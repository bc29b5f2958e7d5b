// ROS1 bag access (see rosbag_backend.hpp). Built as C++17 (src/io/CMakeLists.txt).
#include "io/rosbag_backend.hpp"

#include "semap/core/error.hpp"

#ifdef SEMAP_WITH_ROSBAG

#include <console_bridge/console.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cstring>
#include <mutex>
#include <new>
#include <string>

#include "io/rosbag_validate.hpp"

namespace semap::io_detail::rosbag_backend {

namespace {

// Our own message types, read with checked lengths (issue 44): ROS's generated deserialisers
// resize a vector to its declared length before checking it against the message (a CameraInfo
// declaring 0x20000001 distortion coefficients wraps the byte count and allocates 4 GiB), so
// every variable-length array here is checked against the bytes left first. The "*" MD5 sum
// makes rosbag accept them for any connection; callers check the datatype (datatype_is).

/// Header and image metadata only, without copying the pixels.
template <bool kCompressed>
struct MetaMessage {
  ImageMeta meta;
};
struct ImageMessage {
  ImageData image;
};
struct CompressedMessage {
  CompressedData image;
};
struct CameraInfoMessage {
  CameraInfoData info;
};

}  // namespace
}  // namespace semap::io_detail::rosbag_backend

#define SEMAP_ANY_ROS_MESSAGE(T)                                  \
  template <>                                                     \
  struct MD5Sum<T> {                                              \
    static const char* value() { return "*"; }                    \
    static const char* value(const T&) { return "*"; }            \
  };                                                              \
  template <>                                                     \
  struct DataType<T> {                                            \
    static const char* value() { return "*"; }                    \
    static const char* value(const T&) { return "*"; }            \
  };
namespace ros::message_traits {
SEMAP_ANY_ROS_MESSAGE(semap::io_detail::rosbag_backend::MetaMessage<false>)
SEMAP_ANY_ROS_MESSAGE(semap::io_detail::rosbag_backend::MetaMessage<true>)
SEMAP_ANY_ROS_MESSAGE(semap::io_detail::rosbag_backend::ImageMessage)
SEMAP_ANY_ROS_MESSAGE(semap::io_detail::rosbag_backend::CompressedMessage)
SEMAP_ANY_ROS_MESSAGE(semap::io_detail::rosbag_backend::CameraInfoMessage)
}  // namespace ros::message_traits
#undef SEMAP_ANY_ROS_MESSAGE

namespace ros::serialization {

/// A length-prefixed array of T, its length checked against the bytes left before allocating.
template <typename Stream, typename T>
void next_checked(Stream& stream, std::vector<T>& v) {
  uint32_t count = 0;
  stream.next(count);
  if (count > stream.getLength() / sizeof(T))
    throw StreamOverrunException("array of " + std::to_string(count) + " elements overruns its message");
  v.resize(count);
  if (count > 0) std::memcpy(v.data(), stream.advance(static_cast<uint32_t>(count * sizeof(T))), count * sizeof(T));
}

/// std_msgs/Header: seq, stamp, frame_id.
template <typename Stream>
void next_header(Stream& stream, semap::io_detail::rosbag_backend::Stamp& stamp) {
  uint32_t seq = 0;
  std::string frame_id;
  stream.next(seq);
  stream.next(stamp.sec);
  stream.next(stamp.nsec);
  stream.next(frame_id);
}

template <bool C>
struct Serializer<semap::io_detail::rosbag_backend::MetaMessage<C>> {
  // Image: height, width, encoding, ...; CompressedImage: format, data.
  template <typename Stream>
  static void read(Stream& stream, semap::io_detail::rosbag_backend::MetaMessage<C>& m) {
    next_header(stream, m.meta.header_stamp);
    if constexpr (!C) {
      stream.next(m.meta.height);
      stream.next(m.meta.width);
    }
    stream.next(m.meta.encoding);
  }
};

template <>
struct Serializer<semap::io_detail::rosbag_backend::ImageMessage> {
  // sensor_msgs/Image: header, height, width, encoding, is_bigendian, step, data.
  template <typename Stream>
  static void read(Stream& stream, semap::io_detail::rosbag_backend::ImageMessage& m) {
    semap::io_detail::rosbag_backend::Stamp stamp;
    uint8_t big_endian = 0;
    next_header(stream, stamp);
    stream.next(m.image.height);
    stream.next(m.image.width);
    stream.next(m.image.encoding);
    stream.next(big_endian);
    stream.next(m.image.step);
    next_checked(stream, m.image.data);
    m.image.big_endian = big_endian != 0;
  }
};

template <>
struct Serializer<semap::io_detail::rosbag_backend::CompressedMessage> {
  // sensor_msgs/CompressedImage: header, format, data.
  template <typename Stream>
  static void read(Stream& stream, semap::io_detail::rosbag_backend::CompressedMessage& m) {
    semap::io_detail::rosbag_backend::Stamp stamp;
    next_header(stream, stamp);
    stream.next(m.image.format);
    next_checked(stream, m.image.data);
  }
};

template <>
struct Serializer<semap::io_detail::rosbag_backend::CameraInfoMessage> {
  // sensor_msgs/CameraInfo: header, height, width, distortion_model, D, K (R, P, binning and
  // ROI follow and are not read).
  template <typename Stream>
  static void read(Stream& stream, semap::io_detail::rosbag_backend::CameraInfoMessage& m) {
    next_header(stream, m.info.header_stamp);
    stream.next(m.info.height);
    stream.next(m.info.width);
    stream.next(m.info.distortion_model);
    next_checked(stream, m.info.D);
    for (double& k : m.info.K) stream.next(k);
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

/// The message deserialised as T after checking its connection's datatype.
template <class T>
boost::shared_ptr<T> instantiate(const rosbag::MessageInstance& m, const char* datatype, const std::filesystem::path& bag) {
  if (m.getDataType() != datatype) throw Error(bag, m.getTopic() + " is " + m.getDataType() + ", not " + datatype);
  auto p = m.instantiate<T>();
  if (!p) throw Error(bag, m.getTopic() + ": unreadable " + datatype + " message");
  return p;
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
  boost::shared_ptr<T> first(const std::string& topic, const char* datatype) {
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& m : view) return instantiate<T>(m, datatype, path);
    throw Error(path, "topic " + topic + " has no message");
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
  validate_ros1_bag(path);  // issue 44: librosbag trusts every offset and length in the file
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
    return impl_->first<CompressedMessage>(topic, "sensor_msgs/CompressedImage")->image;
  });
}

CameraInfoData Bag::first_camera_info(const std::string& topic) const {
  return impl_->guarded("cannot read " + topic, [&] {
    return impl_->first<CameraInfoMessage>(topic, "sensor_msgs/CameraInfo")->info;
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
    return std::move(instantiate<ImageMessage>(impl_->message(handle), "sensor_msgs/Image", impl_->path)->image);
  });
}

CompressedData Bag::read_compressed(size_t handle) const {
  return impl_->guarded("cannot read a compressed image message", [&] {
    return std::move(instantiate<CompressedMessage>(impl_->message(handle), "sensor_msgs/CompressedImage", impl_->path)->image);
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
