#include "sequence_slices.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <opencv2/core.hpp>
#include <sstream>

#include "io/image_io.hpp"
#include "semap/core/error.hpp"
#include "semap/io/dataset.hpp"

namespace semap::test {

namespace fs = std::filesystem;

namespace {

/// The output frames' source indices (first..last every step, optionally reversed).
std::vector<size_t> kept_frames(const SliceSpec& spec, size_t source_frames) {
  std::vector<size_t> kept;
  if (!spec.frames.empty()) {
    for (const size_t i : spec.frames)
      if (i < source_frames) kept.push_back(i);
    if (spec.reverse) std::reverse(kept.begin(), kept.end());
    return kept;
  }
  const size_t last = std::min(spec.last, source_frames == 0 ? 0 : source_frames - 1);
  for (size_t i = spec.first; i <= last && i < source_frames; i += std::max<size_t>(1, spec.step)) kept.push_back(i);
  if (spec.reverse) std::reverse(kept.begin(), kept.end());
  return kept;
}

std::string stamp(double t) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(6) << t;
  return s.str();
}

/// Links `link` to the absolute `target` (copies when the file system has no symlinks).
void link_file(const fs::path& target, const fs::path& link) {
  std::error_code ec;
  fs::create_symlink(fs::absolute(target), link, ec);
  if (ec) fs::copy_file(target, link, fs::copy_options::overwrite_existing);
}

void write_dataset_yaml(const fs::path& file, const CameraModel& camera, const std::string& source) {
  const PinholeIntrinsics& k = camera.depth;
  std::ofstream out(file);
  out << std::setprecision(10) << "format: tum\n"
      << "description: \"test slice of " << source << " (tests/sequence_slices)\"\n"
      << "camera:\n  fx: " << k.fx << "\n  fy: " << k.fy << "\n  cx: " << k.cx << "\n  cy: " << k.cy
      << "\n  width: " << k.width << "\n  height: " << k.height << "\n  depth_scale: " << camera.depth_scale << "\n";
  if (!out) throw Error(file, "cannot write dataset.yaml");
}

}  // namespace

SequenceSlice write_sequence_slice(const fs::path& source_dir, const SliceSpec& spec, const fs::path& out_dir) {
  const auto reader = open_dataset(source_dir);
  const std::vector<FrameRecord>& records = reader->records();
  SequenceSlice slice;
  slice.dir = out_dir;
  slice.source_index = kept_frames(spec, records.size());
  if (slice.source_index.empty()) throw Error(source_dir, "empty slice: " + describe(spec));
  fs::create_directories(out_dir / "rgb");
  fs::create_directories(out_dir / "depth");
  std::ofstream rgb_list(out_dir / "rgb.txt"), depth_list(out_dir / "depth.txt"), gt(out_dir / "groundtruth.txt");
  rgb_list << "# timestamp filename\n";
  depth_list << "# timestamp filename\n";
  gt << "# timestamp tx ty tz qx qy qz qw\n";
  const CameraModel& camera = reader->camera();
  const cv::Size size(camera.depth.width, camera.depth.height);
  // Reversed: mirrored timestamps t' = t_first + t_last - t stay increasing.
  const double t_lo = records[*std::min_element(slice.source_index.begin(), slice.source_index.end())].timestamp;
  const double t_hi = records[*std::max_element(slice.source_index.begin(), slice.source_index.end())].timestamp;
  for (size_t i = 0; i < slice.size(); ++i) {
    const FrameRecord& r = records[slice.source_index[i]];
    if (!r.gt_T_world_camera) throw Error(source_dir, "frame " + std::to_string(slice.source_index[i]) + " has no ground truth");
    const double t = spec.reverse ? t_lo + t_hi - r.timestamp : r.timestamp;
    char name[32];
    std::snprintf(name, sizeof(name), "%06zu", i);
    const bool blank = i >= spec.blank_begin && i < spec.blank_end;
    slice.blank.push_back(blank);
    const fs::path rgb_rel = fs::path("rgb") / (std::string(name) + (blank ? ".png" : r.rgb.extension().string()));
    const fs::path depth_rel = fs::path("depth") / (std::string(name) + ".png");
    if (blank) {
      write_image(out_dir / rgb_rel, cv::Mat(size, CV_8UC3, cv::Scalar::all(0)));
      write_image(out_dir / depth_rel, cv::Mat(size, CV_16UC1, cv::Scalar(0)));
    } else {
      link_file(r.rgb, out_dir / rgb_rel);
      link_file(r.depth, out_dir / depth_rel);
    }
    rgb_list << stamp(t) << " " << rgb_rel.string() << "\n";
    depth_list << stamp(t) << " " << depth_rel.string() << "\n";
    const Pose& p = *r.gt_T_world_camera;
    const Eigen::Quaterniond q(p.linear());
    gt << stamp(t) << std::setprecision(9) << " " << p.translation().x() << " " << p.translation().y() << " "
       << p.translation().z() << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w() << "\n";
  }
  if (!rgb_list || !depth_list || !gt) throw Error(out_dir, "cannot write the slice lists");
  write_dataset_yaml(out_dir / "dataset.yaml", camera, source_dir.filename().string());
  return slice;
}

std::vector<size_t> frames_by_motion(const fs::path& source_dir, double min_translation_m, double min_rotation_deg) {
  const auto reader = open_dataset(source_dir);
  const std::vector<FrameRecord>& records = reader->records();
  std::vector<size_t> kept;
  for (size_t i = 0; i < records.size(); ++i) {
    if (!records[i].gt_T_world_camera) throw Error(source_dir, "frame " + std::to_string(i) + " has no ground truth");
    if (!kept.empty()) {
      const Pose step = records[kept.back()].gt_T_world_camera->inverse() * *records[i].gt_T_world_camera;
      if (step.translation().norm() < min_translation_m && rotation_angle(step) * 180.0 / M_PI < min_rotation_deg)
        continue;
    }
    kept.push_back(i);
  }
  return kept;
}

std::string describe(const SliceSpec& spec) {
  std::ostringstream s;
  if (!spec.frames.empty()) {
    s << spec.frames.size() << " chosen frames " << spec.frames.front() << ".." << spec.frames.back();
    if (spec.reverse) s << " reversed";
    return s.str();
  }
  s << "k=" << spec.step << " frames " << spec.first << "..";
  if (spec.last == std::numeric_limits<size_t>::max()) s << "end";
  else s << spec.last;
  if (spec.reverse) s << " reversed";
  if (spec.blank_end > spec.blank_begin) s << " blank " << spec.blank_begin << ".." << spec.blank_end - 1;
  return s.str();
}

}  // namespace semap::test
