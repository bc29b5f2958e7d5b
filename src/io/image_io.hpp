#pragma once
// Image loading with validation: every failure is a semap::Error naming the file.
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace semap {

/// 8-bit colour image (CV_8UC3, BGR). Throws on missing/corrupt/truncated files.
cv::Mat read_colour_image(const std::filesystem::path& path);
/// 16-bit depth PNG converted to CV_32FC1 metres (raw / depth_scale; raw 0 and 65535 -> 0).
/// Throws on missing/corrupt files or a bit depth other than 16. When expected_size is not
/// empty, a different size is an error.
cv::Mat read_depth_image(const std::filesystem::path& path, double depth_scale, cv::Size expected_size = {});
/// CV_16UC1 raw depth -> CV_32FC1 metres (raw * (float)(1 / depth_scale); raw 0 and 65535 -> 0).
cv::Mat depth_units_to_metres(const cv::Mat& raw, double depth_scale);
/// 8- or 16-bit single-channel label/instance image, returned as CV_16UC1.
cv::Mat read_label_image(const std::filesystem::path& path, cv::Size expected_size = {});
/// An in-memory PNG or JPEG (e.g. a ROS CompressedImage), decoded with the same checks as the
/// files above (IMREAD_UNCHANGED); `source` names it in errors.
cv::Mat decode_image_bytes(const std::string& bytes, const std::filesystem::path& source);
/// decode_image_bytes for a colour image: CV_8UC3 BGR, as read_colour_image returns.
cv::Mat decode_colour_bytes(const std::string& bytes, const std::filesystem::path& source);
/// An 8-bit grey, BGR or BGRA image as CV_8UC3 BGR (other types: Error naming `source`).
cv::Mat to_bgr(const std::filesystem::path& source, cv::Mat image);
/// Float metres -> 16-bit PNG with depth_scale (values out of range -> 0). Atomic write.
void write_depth_image(const std::filesystem::path& path, const cv::Mat& depth_m, double depth_scale);
/// Writes any image OpenCV can encode (PNG for 16-bit), atomically. Throws on failure.
void write_image(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace semap
