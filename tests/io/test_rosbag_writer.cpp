// Built as C++17 (tests/io/CMakeLists.txt): the ROS message headers are not C++20.
#include "test_rosbag_writer.hpp"

#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

namespace semap::test {

struct BagWriter::Impl {
  rosbag::Bag bag;
};

namespace {
ros::Time time_of(RosStamp s) { return ros::Time(s.sec, s.nsec); }
}  // namespace

BagWriter::BagWriter(const std::filesystem::path& path, bool lz4) : impl_(std::make_unique<Impl>()) {
  impl_->bag.open(path.string(), rosbag::bagmode::Write);
  impl_->bag.setCompression(lz4 ? rosbag::compression::LZ4 : rosbag::compression::Uncompressed);
}

BagWriter::~BagWriter() { close(); }

void BagWriter::close() {
  if (impl_->bag.isOpen()) impl_->bag.close();
}

void BagWriter::write(const RosImage& image) {
  sensor_msgs::Image msg;
  msg.header.stamp = time_of(image.stamp);
  msg.header.frame_id = "camera";
  msg.encoding = image.encoding;
  msg.width = image.width;
  msg.height = image.height;
  msg.step = image.step;
  msg.is_bigendian = image.big_endian;
  msg.data = image.data;
  impl_->bag.write(image.topic, msg.header.stamp, msg);
}

void BagWriter::write(const RosCompressedImage& image) {
  sensor_msgs::CompressedImage msg;
  msg.header.stamp = time_of(image.stamp);
  msg.format = image.format;
  msg.data = image.data;
  impl_->bag.write(image.topic, msg.header.stamp, msg);
}

void BagWriter::write(const RosCameraInfo& info) {
  sensor_msgs::CameraInfo msg;
  msg.header.stamp = time_of(info.stamp);
  msg.width = info.width;
  msg.height = info.height;
  for (size_t k = 0; k < 9; ++k) msg.K[k] = info.K[k];
  msg.distortion_model = info.distortion_model;
  msg.D = info.D;
  impl_->bag.write(info.topic, msg.header.stamp, msg);
}

void BagWriter::write_imu(const std::string& topic, RosStamp stamp) {
  sensor_msgs::Imu msg;
  msg.header.stamp = time_of(stamp);
  msg.orientation.w = 1;
  impl_->bag.write(topic, msg.header.stamp, msg);
}

}  // namespace semap::test
