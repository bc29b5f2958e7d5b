#pragma once
// Internal to io/: rosbag2 recordings (ROS 2 Humble, Jazzy) without ROS: a bag folder
// (metadata.yaml + storage files, read in the listed order) or a single .db3 / .mcap file.
// Storage: SQLite3 .db3 (rosbag2_storage_default_plugins' schema of Humble and Jazzy: tables
// topics and messages) or MCAP (mcap_reader.hpp); messages in CDR (cdr_reader.hpp). The
// result serves the dataset reader of rosbag_dataset.cpp like a ROS1 bag.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "io/rosbag_backend.hpp"

namespace semap::io_detail {

/// The storage files of a rosbag2 folder, in recording order: metadata.yaml's
/// relative_file_paths, else (a recording cut off before metadata.yaml was written) the
/// folder's .db3 / .mcap files in natural order (bag_0, bag_1, ..., bag_10).
std::vector<std::filesystem::path> rosbag2_storage_files(const std::filesystem::path& folder);

/// True for a folder holding metadata.yaml naming rosbag2 storage, or .db3 / .mcap files.
bool is_rosbag2_folder(const std::filesystem::path& folder);

/// Opens a bag folder or a single storage file. Throws semap::Error naming the file.
std::unique_ptr<rosbag_backend::BagSource> open_rosbag2_source(const std::filesystem::path& path);

}  // namespace semap::io_detail
