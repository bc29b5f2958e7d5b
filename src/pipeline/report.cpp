#include "pipeline/report.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "semap/core/gravity.hpp"
#include "semap/core/labels.hpp"
#include "core/paths.hpp"
#include "semap/core/error.hpp"
#include "semap/eval/consistency_metrics.hpp"
#include "semap/pipeline/navigation_outputs.hpp"

namespace semap {
namespace {

std::string format_value(const nlohmann::json& v) {
  if (v.is_number_float()) {
    std::ostringstream s;
    s.precision(4);
    s << v.get<double>();
    return s.str();
  }
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

/// Flattens nested JSON objects into "a.b.c" -> value rows.
void flatten(const nlohmann::json& j, const std::string& prefix, std::vector<std::pair<std::string, std::string>>& rows) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object())
      flatten(*it, key, rows);
    else if (!it->is_array())
      rows.emplace_back(key, format_value(*it));
  }
}

/// Where to write an object's name: above its footprint, else below, else further up or down
/// in steps of one line, the first spot that overlaps no label placed before and stays inside
/// the image.
cv::Rect place_label(const std::string& text, const cv::Rect& footprint, const std::vector<cv::Rect>& placed,
                     cv::Size image) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline);
  const int w = size.width + 4, h = size.height + baseline + 4;
  const auto clamp_rect = [&](int x, int y) {
    return cv::Rect(std::clamp(x, 0, std::max(0, image.width - w)), std::clamp(y, 0, std::max(0, image.height - h)), w, h);
  };
  const auto is_free = [&](const cv::Rect& r) {
    return std::none_of(placed.begin(), placed.end(), [&](const cv::Rect& p) { return (p & r).area() > 0; });
  };
  for (int step = 0; step < 12; ++step) {
    for (const cv::Rect& r : {clamp_rect(footprint.x, footprint.y - h - step * h),
                              clamp_rect(footprint.x, footprint.y + footprint.height + step * h)})
      if (is_free(r)) return r;
  }
  return clamp_rect(footprint.x, footprint.y - h);
}

}  // namespace

cv::Mat render_topdown(const TriangleMesh& mesh, const Trajectory& trajectory,
                       const std::vector<ReportObject>& objects, int max_side_px,
                       const std::vector<std::pair<double, double>>& trajectory_error_m) {
  const Eigen::Vector3d up = estimate_gravity(mesh, trajectory).up_W;
  // Orthonormal basis (ex, ey) of the ground plane.
  Eigen::Vector3d ex = up.unitOrthogonal();
  Eigen::Vector3d ey = up.cross(ex);
  double cam_max_h = -1e9;
  for (const auto& p : trajectory) cam_max_h = std::max(cam_max_h, up.dot(p.T_world_camera.translation()));
  const double cut_h = trajectory.empty() ? 1e9 : cam_max_h + 0.3;  // drop the ceiling

  std::vector<Eigen::Vector2d> ground;
  Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
  auto extend = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector2d g(ex.dot(p), ey.dot(p));
    lo = lo.cwiseMin(g);
    hi = hi.cwiseMax(g);
  };
  for (const auto& v : mesh.vertices.points)
    if (up.dot(v.cast<double>()) < cut_h) extend(v.cast<double>());
  for (const auto& p : trajectory) extend(p.T_world_camera.translation());
  if (lo.x() > hi.x()) { lo.setZero(); hi.setOnes(); }
  const double margin = 0.05 * std::max(hi.x() - lo.x(), hi.y() - lo.y()) + 1e-3;
  lo.array() -= margin;
  hi.array() += margin;
  const double scale = max_side_px / std::max(hi.x() - lo.x(), hi.y() - lo.y());
  const int w = std::max(1, static_cast<int>((hi.x() - lo.x()) * scale));
  const int h = std::max(1, static_cast<int>((hi.y() - lo.y()) * scale));
  cv::Mat image(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  auto to_px = [&](const Eigen::Vector3d& p) {
    return cv::Point(static_cast<int>((ex.dot(p) - lo.x()) * scale), static_cast<int>((hi.y() - ey.dot(p)) * scale));
  };

  // Painter's algorithm: low triangles first, so table tops cover the floor under them.
  const auto& verts = mesh.vertices.points;
  std::vector<std::pair<float, uint32_t>> order;
  order.reserve(mesh.triangles.size());
  for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const float height = static_cast<float>(up.dot((verts[tri[0]] + verts[tri[1]] + verts[tri[2]]).cast<double>() / 3.0));
    if (height < cut_h) order.emplace_back(height, t);
  }
  std::sort(order.begin(), order.end());
  const bool labelled = mesh.vertices.has_labels();
  const bool coloured = mesh.vertices.has_colours();
  for (const auto& [height, t] : order) {
    const auto& tri = mesh.triangles[t];
    cv::Point pts[3];
    for (int k = 0; k < 3; ++k) pts[k] = to_px(verts[tri[k]].cast<double>());
    // Class colour where labelled, else the vertex colour, else grey shaded by height.
    const ClassId label = labelled ? mesh.vertices.labels[tri[0]] : 0;
    const float rel = std::clamp(static_cast<float>((height - order.front().first) / (cut_h - order.front().first + 1e-6)), 0.f, 1.f);
    const auto grey = static_cast<uint8_t>(110 + 120 * rel);
    Rgb8 c{grey, grey, grey};
    if (label != 0) c = class_colour(label);
    else if (coloured && !labelled) c = mesh.vertices.colours[tri[0]];
    cv::fillConvexPoly(image, pts, 3, cv::Scalar(c.b, c.g, c.r), cv::LINE_8);
  }
  // Trajectory: dark grey, or from green (no error) to red (the run's largest error) by ATE.
  const std::map<double, double> error_at(trajectory_error_m.begin(), trajectory_error_m.end());
  double max_error = 1e-9;
  for (const auto& [t, e] : trajectory_error_m) max_error = std::max(max_error, e);
  for (size_t i = 1; i < trajectory.size(); ++i) {
    cv::Scalar colour(40, 40, 40);
    if (const auto it = error_at.find(trajectory[i].timestamp); it != error_at.end()) {
      const double f = std::clamp(it->second / max_error, 0.0, 1.0);
      colour = cv::Scalar(30, 200 * (1 - f), 60 + 195 * f);  // BGR
    }
    cv::line(image, to_px(trajectory[i - 1].T_world_camera.translation()), to_px(trajectory[i].T_world_camera.translation()),
             colour, 3, cv::LINE_AA);
  }
  if (!trajectory.empty()) cv::circle(image, to_px(trajectory.front().T_world_camera.translation()), 6, cv::Scalar(0, 0, 0), -1);
  // Object footprints (convex hull of the projected box corners), then their names, placed
  // where they overlap no name drawn before (issue 43: labels of nearby objects collided).
  std::vector<cv::Rect> hulls;
  for (const auto& obj : objects) {
    std::vector<cv::Point> pts, hull;
    for (const auto& c : obj.corners) pts.push_back(to_px(c));
    cv::convexHull(pts, hull);
    const Rgb8 c = class_colour(obj.class_id);
    cv::polylines(image, hull, true, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
    cv::polylines(image, hull, true, cv::Scalar(c.b, c.g, c.r), 1, cv::LINE_AA);
    hulls.push_back(cv::boundingRect(hull));
  }
  std::vector<cv::Rect> placed;
  for (size_t i = 0; i < objects.size(); ++i) {
    const std::string text = std::string(class_name(objects[i].class_id)) + " " + std::to_string(objects[i].id);
    const cv::Rect label = place_label(text, hulls[i], placed, image.size());
    placed.push_back(label);
    const cv::Point origin(label.x + 2, label.y + label.height - 4);
    cv::putText(image, text, origin, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(255, 255, 255), 3, cv::LINE_AA);
    cv::putText(image, text, origin, cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  return image;
}

nlohmann::json timings_json(const std::map<std::string, TimingSummary>& timings) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [stage, s] : timings) {
    j[stage] = {{"count", s.count}, {"mean_ms", s.mean_ms}, {"median_ms", s.median_ms}, {"p95_ms", s.p95_ms},
                {"total_ms", s.total_ms}};
    if (s.cpu_count == 0) continue;
    j[stage]["cpu_mean_ms"] = s.cpu_mean_ms;  // CPU of the stage's thread and its TBB helpers
    j[stage]["cpu_total_ms"] = s.cpu_total_ms;
  }
  return j;
}

std::map<std::string, int> objects_per_class(const std::vector<ObjectSummary>& objects) {
  std::map<std::string, int> out;
  for (const ObjectSummary& o : objects) ++out[std::string(class_name(o.class_id))];
  return out;
}

std::vector<ReportObject> report_objects(const std::vector<ObjectSummary>& objects) {
  std::vector<ReportObject> out;
  for (const ObjectSummary& o : objects) {
    ReportObject r{o.id, o.class_id, {}};
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3f s((k & 1) ? 0.5f : -0.5f, (k & 2) ? 0.5f : -0.5f, (k & 4) ? 0.5f : -0.5f);
      r.corners[k] = (o.box.center + o.box.rotation * s.cwiseProduct(o.box.extent)).cast<double>();
    }
    out.push_back(r);
  }
  return out;
}

namespace {

/// Per stage that worked on frames: its milliseconds on each frame of `frames` (summed over its
/// calls on that frame; null where it did not run), rounded to the microsecond.
nlohmann::json stage_ms_per_frame(const std::vector<FrameResult>& frames,
                                  const std::map<std::string, std::vector<StageSample>>& stage_samples) {
  std::map<size_t, size_t> position;  // Frame::index -> position in `frames`
  for (size_t i = 0; i < frames.size(); ++i) position.emplace(frames[i].frame_index, i);
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [stage, samples] : stage_samples) {
    std::vector<double> ms(frames.size(), 0.0);
    std::vector<bool> ran(frames.size(), false);
    for (const StageSample& sample : samples) {
      if (!sample.frame_index) continue;
      const auto it = position.find(*sample.frame_index);
      if (it == position.end()) continue;  // e.g. a frame read but skipped (no ground-truth pose)
      ms[it->second] += sample.wall_ms;
      ran[it->second] = true;
    }
    if (std::none_of(ran.begin(), ran.end(), [](bool r) { return r; })) continue;  // run once, not per frame
    nlohmann::json column = nlohmann::json::array();
    for (size_t i = 0; i < ms.size(); ++i)
      column.push_back(ran[i] ? nlohmann::json(std::round(ms[i] * 1000.0) / 1000.0) : nlohmann::json(nullptr));
    out[stage] = std::move(column);
  }
  return out;
}

}  // namespace

nlohmann::json frames_json(const std::vector<FrameResult>& frames,
                           const std::map<std::string, std::vector<StageSample>>& stage_samples,
                           const std::optional<AteResult>& ate) {
  nlohmann::json j = {{"timestamp_s", nlohmann::json::array()}, {"status", nlohmann::json::array()},
                      {"ransac_inliers", nlohmann::json::array()}, {"tracking_ms", nlohmann::json::array()},
                      {"add_frame_ms", nlohmann::json::array()}};
  for (const FrameResult& f : frames) {
    j["timestamp_s"].push_back(f.timestamp);
    j["status"].push_back(to_string(f.status));
    j["ransac_inliers"].push_back(f.ransac_inliers);
    j["tracking_ms"].push_back(f.tracking_ms);
    j["add_frame_ms"].push_back(f.total_ms);
  }
  j["stage_ms"] = stage_ms_per_frame(frames, stage_samples);
  if (!ate) return j;
  // ATE per frame where the frame's pose associated with ground truth (null elsewhere).
  std::map<double, double> error_by_time(ate->per_pose_error_m.begin(), ate->per_pose_error_m.end());
  j["ate_m"] = nlohmann::json::array();
  for (const FrameResult& f : frames) {
    const auto it = error_by_time.find(f.timestamp);
    j["ate_m"].push_back(it == error_by_time.end() ? nlohmann::json(nullptr) : nlohmann::json(it->second));
  }
  return j;
}

void write_run_report(const std::filesystem::path& dir, const RunResult& result, const MapOutputs& outputs) {
  const cv::Mat topdown =
      render_topdown(outputs.mesh, outputs.trajectory, report_objects(outputs.objects), 900,
                     result.evaluation.ate ? result.evaluation.ate->per_pose_error_m : std::vector<std::pair<double, double>>{});
  std::vector<uint8_t> png;
  if (!cv::imencode(".png", topdown, png)) throw Error(dir / "topdown.png", "cannot encode");
  const std::string topdown_png(png.begin(), png.end());
  write_file_atomic(dir / "topdown.png", topdown_png);
  nlohmann::json report = to_json(result);
  report["consistency"] = to_json(evaluate_consistency(outputs.mesh, outputs.trajectory));  // issue 38
  report["gravity"] = gravity_report_json(outputs.navigation.gravity);  // issue 39
  report["navigation"] = navigation_report_json(outputs.navigation);
  write_file_atomic(dir / "report.json", report.dump(2) + "\n");
  ReportPictures pictures{topdown_png, render_grid_picture(outputs.navigation.grid, outputs.trajectory),
                          object_cards(outputs.objects, outputs.navigation.gravity.up_W, outputs.trajectory)};
  write_report_html(dir, report, pictures);
}


RunResult library_run_result(const Mapper& mapper, const MapOutputs& outputs) {
  RunResult r;
  r.mapper = mapper.stats();
  r.poses = r.mapper.external_poses ? PoseSource::given : PoseSource::track;  // the caller's poses, not ground truth
  r.frames_read = r.mapper.frames;
  r.mesh_vertices = outputs.mesh.vertices.size();
  r.mesh_triangles = outputs.mesh.triangles.size();
  r.objects_per_class = objects_per_class(outputs.objects);
  r.threads = mapper.config().pipeline.threads;
  r.timings = mapper.timings();
  r.frames = mapper.frame_results();
  r.stage_samples = mapper.stage_samples();
  r.peak_rss_mb = static_cast<double>(peak_rss_bytes()) / (1024.0 * 1024.0);
  r.driver_measured = false;
  return r;
}

std::string summary_table(const nlohmann::json& report) {
  std::vector<std::pair<std::string, std::string>> rows;
  for (const char* section : {"summary", "evaluation", "objects_per_class"})
    if (report.contains(section)) flatten(report[section], section, rows);
  size_t width = 0;
  for (const auto& r : rows) width = std::max(width, r.first.size());
  std::ostringstream s;
  s << std::string(width + 20, '-') << "\n";
  for (const auto& [k, v] : rows) s << k << std::string(width - k.size() + 2, ' ') << v << "\n";
  if (report.contains("timings")) {
    s << std::string(width + 20, '-') << "\nstage" << std::string(width > 3 ? width - 3 : 2, ' ') << "mean ms  p95 ms\n";
    for (auto it = report["timings"].begin(); it != report["timings"].end(); ++it) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%7.2f %7.2f", (*it)["mean_ms"].get<double>(), (*it)["p95_ms"].get<double>());
      s << it.key() << std::string(width > it.key().size() ? width - it.key().size() + 2 : 2, ' ') << buf << "\n";
    }
  }
  s << std::string(width + 20, '-') << "\n";
  return s.str();
}

}  // namespace semap
