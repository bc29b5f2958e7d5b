// `semap view` end to end: writes a small labelled output folder (mesh.ply, objects.json,
// trajectory.txt), serves it with `semap view`, loads the page in headless Chromium through
// viewer/test/screenshot.mjs and checks the screenshots: the mesh covers the canvas, the class
// toggles hide it, an object's panel opens on click, and the console shows no errors.
// Set SEMAP_VIEWER_TEST_DIR to an existing output folder (e.g. a `semap demo` output) to use
// it instead of the generated one.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include <sys/wait.h>
#include <unistd.h>

#include "semap/core/labels.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/io/ply_io.hpp"
#include "test_support.hpp"

namespace semap::test {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
const cv::Vec3b kClearColourBgr{0x28, 0x22, 0x1e};  // viewer/src/main.js CLEAR_COLOUR

// Appends an oriented box (12 triangles) to the mesh.
void add_box(TriangleMesh& mesh, const Eigen::Vector3f& centre, const Eigen::Vector3f& extent, float yaw_rad,
             Rgb8 colour, Label label, uint32_t instance) {
  const Eigen::Matrix3f rotation = Eigen::AngleAxisf(yaw_rad, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const auto base = static_cast<uint32_t>(mesh.vertices.size());
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3f corner((k & 1) ? 0.5f : -0.5f, (k & 2) ? 0.5f : -0.5f, (k & 4) ? 0.5f : -0.5f);
    mesh.vertices.points.push_back(centre + rotation * corner.cwiseProduct(extent));
    mesh.vertices.colours.push_back(colour);
    mesh.vertices.labels.push_back(id(label));
    mesh.vertices.instances.push_back(instance);
  }
  const int quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const auto& q : quads) {
    mesh.triangles.push_back({base + q[0], base + q[1], base + q[2]});
    mesh.triangles.push_back({base + q[0], base + q[2], base + q[3]});
  }
}

// A grid-tessellated rectangle (shared vertices, like a TSDF mesh) from origin along u and v.
void add_plane(TriangleMesh& mesh, const Eigen::Vector3f& origin, const Eigen::Vector3f& u, const Eigen::Vector3f& v,
               int cells, Label label) {
  const auto base = static_cast<uint32_t>(mesh.vertices.size());
  for (int j = 0; j <= cells; ++j) {
    for (int i = 0; i <= cells; ++i) {
      mesh.vertices.points.push_back(origin + u * (float(i) / cells) + v * (float(j) / cells));
      const auto shade = static_cast<uint8_t>(120 + 60 * ((i + j) % 2));
      mesh.vertices.colours.push_back({shade, shade, shade});
      mesh.vertices.labels.push_back(id(label));
      mesh.vertices.instances.push_back(0);
    }
  }
  const auto at = [&](int i, int j) { return base + static_cast<uint32_t>(j * (cells + 1) + i); };
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
}

nlohmann::json object_entry(int object_id, Label label, const Eigen::Vector3f& centre, const Eigen::Vector3f& extent,
                            float yaw_rad, int point_count) {
  const Eigen::Matrix3f r = Eigen::AngleAxisf(yaw_rad, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const std::string name(class_name(id(label)));
  return {{"id", object_id}, {"class", name}, {"class_id", id(label)},
          {"class_distribution", {{name, 0.85}, {"other", 0.15}}}, {"n", 12}, {"association_count", 30},
          {"centroid", {centre.x(), centre.y(), centre.z()}},
          {"obb", {{"center", {centre.x(), centre.y(), centre.z()}}, {"extent", {extent.x(), extent.y(), extent.z()}},
                   {"rotation", {r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)}}}},
          {"point_count", point_count}, {"points_file", "objects/" + std::to_string(object_id) + ".ply"},
          {"first_seen", 0}, {"last_seen", 39}, {"state", "stable"}};
}

// A small room: floor, two walls, a chair and a table, their object boxes and a camera circle.
void write_small_output(const fs::path& dir) {
  TriangleMesh mesh;
  add_plane(mesh, {-2, -2, 0}, {4, 0, 0}, {0, 4, 0}, 16, Label::kFloor);
  add_plane(mesh, {-2, -2, 0}, {4, 0, 0}, {0, 0, 2.4f}, 8, Label::kWall);
  add_plane(mesh, {-2, -2, 0}, {0, 4, 0}, {0, 0, 2.4f}, 8, Label::kWall);
  const Eigen::Vector3f chair_centre(0.9f, 0.6f, 0.45f), chair_extent(0.5f, 0.5f, 0.9f);
  const Eigen::Vector3f table_centre(-0.7f, -0.5f, 0.375f), table_extent(1.4f, 0.8f, 0.75f);
  const float chair_yaw = static_cast<float>(kPi / 6);
  add_box(mesh, chair_centre, chair_extent, chair_yaw, class_colour(id(Label::kChair)), Label::kChair, 1);
  add_box(mesh, table_centre, table_extent, 0.0f, class_colour(id(Label::kTable)), Label::kTable, 2);
  write_ply(dir / "mesh.ply", mesh);

  nlohmann::json objects;
  objects["objects"] = {object_entry(1, Label::kChair, chair_centre, chair_extent * 1.08f, chair_yaw, 812),
                        object_entry(2, Label::kTable, table_centre, table_extent * 1.08f, 0.0f, 2304)};
  write_text(dir / "objects.json", objects.dump(2));

  // Camera (T_world_camera, optical frame: z forward, y down) circling and looking at the room.
  std::ostringstream trajectory;
  trajectory << "# timestamp tx ty tz qx qy qz qw\n";
  for (int i = 0; i < 40; ++i) {
    const double angle = kPi * 0.1 + kPi * 0.4 * i / 39.0;
    const Eigen::Vector3d position(1.8 * std::cos(angle), 1.8 * std::sin(angle), 1.4);
    const Eigen::Vector3d forward = (Eigen::Vector3d(0, 0, 0.5) - position).normalized();
    const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Eigen::Matrix3d rotation;
    rotation << right, down, forward;
    const Eigen::Quaterniond q(rotation);
    trajectory << std::fixed << 0.1 * i << ' ' << position.x() << ' ' << position.y() << ' ' << position.z() << ' '
               << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  write_text(dir / "trajectory.txt", trajectory.str());
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

bool command_exists(const std::string& name) {
  return run_command("command -v " + shell_quote(name) + " >/dev/null").exit_code == 0;
}

// Share of pixels of a screenshot that differ from the viewer's clear colour.
double foreground_fraction(const fs::path& png) {
  const cv::Mat image = cv::imread(png.string(), cv::IMREAD_COLOR);
  if (image.empty()) return -1.0;
  size_t differing = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b p = image.at<cv::Vec3b>(y, x);
      int d = 0;
      for (int c = 0; c < 3; ++c) d += std::abs(int(p[c]) - int(kClearColourBgr[c]));
      if (d > 24) ++differing;
    }
  }
  return double(differing) / double(image.total());
}

// `semap view` running in the background, stopped with SIGINT (as Ctrl-C would).
class BackgroundServer {
 public:
  BackgroundServer(const std::string& command, const fs::path& log) {
    pid_ = fork();
    if (pid_ == 0) {
      setpgid(0, 0);
      execl("/bin/sh", "sh", "-c", ("exec " + command + " >" + shell_quote(log.string()) + " 2>&1").c_str(),
            static_cast<char*>(nullptr));
      _exit(127);
    }
  }
  ~BackgroundServer() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  bool started() const { return pid_ > 0; }
  /// Sends SIGINT and waits up to `timeout`; the exit code, or -1 when it did not stop.
  int interrupt_and_wait(std::chrono::seconds timeout) {
    if (running()) kill(pid_, SIGINT);
    return wait(timeout);
  }
  /// Waits up to `timeout` for the process to end; its exit code, or -1.
  int wait(std::chrono::seconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (running() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    return exited_ ? exit_code_ : -1;
  }
  bool running() {
    int status = 0;
    if (!exited_ && waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    return !exited_;
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
};

/// The viewer URL a background semap prints into `log` ("" when it ends or prints none in 10 s).
std::string wait_for_url(BackgroundServer& server, const fs::path& log) {
  const std::regex url_pattern(R"((http://127\.0\.0\.1:\d+/viewer/index\.html))");
  for (int attempt = 0; attempt < 200; ++attempt) {
    std::smatch match;
    const std::string text = read_file(log);
    if (std::regex_search(text, match, url_pattern)) return match[1];
    if (!server.running()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return {};
}

TEST(Viewer, RejectsMissingFolderAndFolderWithoutMesh) {
  TempDir temp("semap_viewer_bad");
  const std::string semap = shell_quote(semap_executable().string());
  const auto missing = run_command(semap + " view " + shell_quote((temp / "nope").string()) + " --no-serve");
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_NE(missing.output.find("nope"), std::string::npos) << missing.output;

  const auto no_mesh = run_command(semap + " view " + shell_quote(temp.path().string()) + " --no-serve");
  EXPECT_EQ(no_mesh.exit_code, 1) << no_mesh.output;
  EXPECT_NE(no_mesh.output.find("mesh.ply"), std::string::npos) << no_mesh.output;
}

TEST(Viewer, NoServeWritesPageClassesAndManifest) {
  TempDir temp("semap_viewer_static");
  write_small_output(temp.path());
  fs::remove(temp / "trajectory.txt");
  {  // issue 43: the run's up estimate (report.json gravity.up) reaches the page
    std::ofstream report(temp / "report.json");
    report << R"({"gravity": {"up": [0.0, -0.6, 0.8]}})";
  }
  const auto result = run_command(shell_quote(semap_executable().string()) + " view " +
                                  shell_quote(temp.path().string()) + " --no-serve");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const fs::path page = temp / "viewer";
  EXPECT_TRUE(fs::is_regular_file(page / "index.html"));
  ASSERT_TRUE(fs::is_regular_file(page / "viewer.js"));
  EXPECT_GT(fs::file_size(page / "viewer.js"), 100000u) << "the bundle should contain three.js";

  const auto classes = nlohmann::json::parse(read_file(page / "classes.json"));
  ASSERT_EQ(classes.size(), static_cast<size_t>(kNumClasses));
  for (int c = 0; c < kNumClasses; ++c) {
    EXPECT_EQ(classes[c]["name"].get<std::string>(), class_name(static_cast<ClassId>(c)));
    EXPECT_EQ(classes[c]["colour"][0].get<int>(), class_colour(static_cast<ClassId>(c)).r);
  }
  const auto manifest = nlohmann::json::parse(read_file(page / "viewer.json"));
  EXPECT_EQ(manifest["files"]["mesh"], "../mesh.ply");
  EXPECT_EQ(manifest["files"]["objects"], "../objects.json");
  EXPECT_TRUE(manifest["files"]["trajectory"].is_null()) << "absent files must not be listed (no 404s)";
  ASSERT_TRUE(manifest.contains("up")) << manifest.dump();
  EXPECT_DOUBLE_EQ(manifest["up"][1].get<double>(), -0.6);
}

// Skips (with the reason) when the browser tool chain is absent; otherwise empty.
std::string browser_missing(const fs::path& viewer_dir, const std::string& chromium) {
  if (!command_exists("node")) return "node not found: install nodejs (scripts/install-viewer-deps.sh)";
  if (!fs::exists(chromium)) return chromium + " not found: run scripts/install-viewer-deps.sh (Debian package chromium)";
  return "";
}

std::string chromium_path() {
  return std::getenv("SEMAP_CHROMIUM") ? std::getenv("SEMAP_CHROMIUM") : "/usr/bin/chromium";
}

// Serves `output` with `semap view`, drives headless Chromium through viewer/test/screenshot.mjs
// into `shots`, checks the screenshots (mesh covers the canvas, class toggles hide it, no console
// errors) and returns the script's result.json.
nlohmann::json check_in_browser(const fs::path& output, const fs::path& shots, const TempDir& temp) {
  const fs::path viewer_dir = SEMAP_VIEWER_SOURCE_DIR;
  const std::string chromium = chromium_path();
  EXPECT_TRUE(fs::exists(viewer_dir / "node_modules/playwright-core/package.json"))
      << "playwright-core missing: run `npm ci` in " << viewer_dir << " (the build does it)";
  fs::remove_all(shots);
  fs::create_directories(shots);
  const fs::path log = temp / "semap_view.log";
  BackgroundServer server(shell_quote(semap_executable().string()) + " view " + shell_quote(output.string()) +
                              " --port 0",
                          log);
  EXPECT_TRUE(server.started());

  const std::string url = wait_for_url(server, log);
  if (url.empty()) {
    ADD_FAILURE() << "semap view printed no URL:\n" << read_file(log);
    return nlohmann::json::object();
  }

  const auto browser = run_command("cd " + shell_quote(viewer_dir.string()) + " && timeout 180 node test/screenshot.mjs --url " +
                                   shell_quote(url) + " --out " + shell_quote(shots.string()) + " --chromium " +
                                   shell_quote(chromium) + " --min-fraction 0.05");
  EXPECT_EQ(browser.exit_code, 0) << browser.output;
  EXPECT_EQ(server.interrupt_and_wait(std::chrono::seconds(10)), 0) << "semap view should stop on Ctrl-C:\n"
                                                                      << read_file(log);

  // The screenshots, checked independently of the node script.
  const double with_mesh = foreground_fraction(shots / "canvas.png");
  const double classes_off = foreground_fraction(shots / "classes_off.png");
  EXPECT_GT(with_mesh, 0.05) << "the mesh should cover more than 5% of the canvas";
  EXPECT_GE(classes_off, 0.0);
  EXPECT_LT(classes_off, 0.5 * with_mesh) << "switching every class off should hide the mesh";
  EXPECT_TRUE(fs::is_regular_file(shots / "viewer.png"));

  if (!fs::exists(shots / "result.json")) {
    ADD_FAILURE() << "screenshot.mjs wrote no result.json";
    return nlohmann::json::object();
  }
  const auto result = nlohmann::json::parse(read_file(shots / "result.json"));
  EXPECT_TRUE(result["console_errors"].empty()) << result["console_errors"].dump();
  return result;
}

// Screenshots stay in the build folder for people to look at.
fs::path screenshot_dir(const std::string& name) { return semap_executable().parent_path() / "test_output" / name; }

TEST(Viewer, HeadlessChromiumRendersMeshBoxesAndToggles) {
  if (const std::string why = browser_missing(SEMAP_VIEWER_SOURCE_DIR, chromium_path()); !why.empty()) SEMAP_SKIP_OR_FAIL(why);
  TempDir temp("semap_viewer_browser");
  fs::path output = temp.path();
  if (const char* given = std::getenv("SEMAP_VIEWER_TEST_DIR")) output = given;
  else write_small_output(output);

  const auto result = check_in_browser(output, screenshot_dir("viewer"), temp);
  if (!std::getenv("SEMAP_VIEWER_TEST_DIR") && !result.empty()) {
    EXPECT_EQ(result["objects"].get<int>(), 2);
    EXPECT_NE(result["object_panel"].get<std::string>().find("812"), std::string::npos)
        << "the first object's panel should show its point count";
  }
}

// The issue's check: the page loads a real `semap demo` output (a short loop, same pipeline:
// tracking, noisy segmentation, TSDF, objects) and shows its mesh and object boxes.
TEST(Viewer, HeadlessChromiumRendersADemoOutput) {
  if (const std::string why = browser_missing(SEMAP_VIEWER_SOURCE_DIR, chromium_path()); !why.empty()) SEMAP_SKIP_OR_FAIL(why);
  TempDir temp("semap_viewer_demo");
  const fs::path output = temp / "demo";
  const auto demo = run_command(shell_quote(semap_executable().string()) + " demo --frames 40 --out " +
                                shell_quote(output.string()) + " 2>&1");
  ASSERT_EQ(demo.exit_code, 0) << demo.output;
  ASSERT_TRUE(fs::is_regular_file(output / "mesh.ply"));
  const auto objects = nlohmann::json::parse(read_file(output / "objects.json"));
  const size_t object_count = objects["objects"].size();
  ASSERT_GT(object_count, 0u) << "a demo output should hold objects";

  const auto result = check_in_browser(output, screenshot_dir("viewer_demo"), temp);
  if (!result.empty()) EXPECT_EQ(result["objects"].get<size_t>(), object_count) << "every object gets a box";
}

// Issue 18: `semap run --view` serves the growing map while it is built. Two screenshots some
// seconds apart (each after a new snapshot) show a larger mesh; Ctrl-C then ends the run, which
// maps the frames read so far and publishes its outputs. The recording: redkitchen (4 m of travel,
// the map grows all along) fed by --realtime at its 30 Hz (17 s), as the camera would: mapping
// as fast as it can, the whole map was built before the browser had started.
TEST(Viewer, LiveViewShowsTheMapGrowingDuringSemapRun) {
  SEMAP_REQUIRE_DATA(kitchen, "7scenes_redkitchen");
  if (const std::string why = browser_missing(SEMAP_VIEWER_SOURCE_DIR, chromium_path()); !why.empty()) SEMAP_SKIP_OR_FAIL(why);
  TempDir temp("semap_viewer_live");
  const fs::path out = temp / "out", log = temp / "run.log", shots = screenshot_dir("viewer_live");
  fs::remove_all(shots);
  fs::create_directories(shots);
  BackgroundServer run(shell_quote(semap_executable().string()) + " run " + shell_quote(kitchen.string()) + " --out " +
                           shell_quote(out.string()) + " --view --port 0 --view-refresh-ms 500 --view-keep-s 300 --threads 2 --no-eval --realtime --segmenter none",
                       log);
  const std::string url = wait_for_url(run, log);
  ASSERT_FALSE(url.empty()) << "semap run --view printed no URL:\n" << read_file(log);
  const auto browser = run_command("cd " + shell_quote(std::string(SEMAP_VIEWER_SOURCE_DIR)) +
                                   " && timeout 180 node test/screenshot.mjs --url " + shell_quote(url) + " --out " +
                                   shell_quote(shots.string()) + " --chromium " + shell_quote(chromium_path()) +
                                   " --live-gap-ms 2000");
  EXPECT_EQ(browser.exit_code, 0) << browser.output;
  // --view-keep-s holds the finished map up until the page is done with it (a slow browser
  // start must not find the server gone); Ctrl-C ends the wait, or the run if still mapping.
  EXPECT_EQ(run.interrupt_and_wait(std::chrono::seconds(120)), 0) << read_file(log);
  EXPECT_TRUE(fs::is_regular_file(out / "mesh.ply")) << "the run publishes its outputs as without --view";
  const auto result = nlohmann::json::parse(read_file(shots / "result.json"), nullptr, false);
  ASSERT_TRUE(result.is_object() && result.contains("live_second")) << browser.output;
  std::printf("[live view] vertices %d -> %d, canvas %.3f -> %.3f\n", result["live_first"]["vertices"].get<int>(),
              result["live_second"]["vertices"].get<int>(), result["live_first"]["foreground_fraction"].get<double>(),
              result["live_second"]["foreground_fraction"].get<double>());
  EXPECT_GT(result["live_second"]["vertices"].get<int>(), result["live_first"]["vertices"].get<int>());
  EXPECT_GT(foreground_fraction(shots / "live_2.png"), 0.02) << "the second screenshot shows the mesh";
}

}  // namespace
}  // namespace semap::test
