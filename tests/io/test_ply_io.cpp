#include <random>

#include "semap/io/ply_io.hpp"
#include "io_test_util.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using test::throws_naming;

TriangleMesh sample_mesh(size_t n, bool all_attributes) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-5, 5);
  TriangleMesh mesh;
  PointCloud& c = mesh.vertices;
  for (size_t i = 0; i < n; ++i) {
    c.points.emplace_back(u(rng), u(rng), u(rng));
    if (!all_attributes) continue;
    c.normals.push_back(Eigen::Vector3f(u(rng), u(rng), u(rng)).normalized());
    c.colours.push_back({uint8_t(rng()), uint8_t(rng()), uint8_t(rng())});
    c.labels.push_back(ClassId(rng() % kNumClasses));
    c.instances.push_back(uint32_t(rng()));
  }
  for (size_t i = 0; i + 2 < n; i += 3) mesh.triangles.push_back({uint32_t(i), uint32_t(i + 2), uint32_t(i + 1)});
  return mesh;
}

void expect_same(const TriangleMesh& a, const TriangleMesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  EXPECT_EQ(a.vertices.points, b.vertices.points);
  EXPECT_EQ(a.vertices.normals, b.vertices.normals);
  EXPECT_EQ(a.vertices.colours, b.vertices.colours);
  EXPECT_EQ(a.vertices.labels, b.vertices.labels);
  EXPECT_EQ(a.vertices.instances, b.vertices.instances);
  EXPECT_EQ(a.triangles, b.triangles);
}

TEST(PlyIo, BinaryRoundTripAllAttributesAndFaces) {
  test::TempDir dir;
  const TriangleMesh mesh = sample_mesh(3000, true);
  write_ply(dir / "m.ply", mesh);
  expect_same(read_ply(dir / "m.ply"), mesh);
  // Points only, no faces.
  const TriangleMesh points = sample_mesh(10, false);
  write_ply(dir / "p.ply", points.vertices);
  const TriangleMesh back = read_ply(dir / "p.ply");
  EXPECT_EQ(back.vertices.points, points.vertices.points);
  EXPECT_FALSE(back.vertices.has_colours());
  EXPECT_TRUE(back.triangles.empty());
  // Empty cloud.
  write_ply(dir / "e.ply", PointCloud{});
  EXPECT_TRUE(read_ply(dir / "e.ply").vertices.empty());
}

TEST(PlyIo, AsciiWithUnknownPropertiesAndPolygons) {
  test::TempDir dir;
  test::write_text(dir / "a.ply",
                   "ply\r\nformat ascii 1.0\r\ncomment from some tool\r\n"
                   "element vertex 4\r\n"
                   "property double x\r\nproperty float y\r\nproperty float z\r\n"
                   "property short extra\r\nproperty float nx\r\nproperty float ny\r\nproperty float nz\r\n"
                   "property uchar red\r\nproperty uchar green\r\nproperty uchar blue\r\nproperty uchar alpha\r\n"
                   "property uchar label\r\nproperty uint instance\r\nproperty list uchar int junk\r\n"
                   "element face 2\r\nproperty list uchar uint vertex_index\r\nproperty int8 flag\r\n"
                   "element edge 1\r\nproperty int a\r\nproperty int b\r\n"
                   "end_header\r\n"
                   "0 0 0 -3 0 0 1 255 0 0 255 7 70000 2 5 6\r\n"
                   "1 0 0 -3 0 0 1 0 255 0 255 7 70000 0\r\n"
                   "1 1 0 -3 0 0 1 0 0 255 255 20 1 1 9\r\n"
                   "0 1 0.5 -3 0 0 1 9 9 9 255 20 1 0\r\n"
                   "3 0 1 2 -1\r\n4 0 1 2 3 1\r\n"
                   "0 1\r\n");
  const TriangleMesh m = read_ply(dir / "a.ply");
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.vertices.points[3], Eigen::Vector3f(0, 1, 0.5f));
  EXPECT_EQ(m.vertices.normals[2], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(m.vertices.colours[2], (Rgb8{0, 0, 255}));
  EXPECT_EQ(m.vertices.labels[0], 7);
  EXPECT_EQ(m.vertices.instances[0], 70000u);
  const std::vector<std::array<uint32_t, 3>> expected = {{0, 1, 2}, {0, 1, 2}, {0, 2, 3}};  // quad fan
  EXPECT_EQ(m.triangles, expected);
}

TEST(PlyIo, BinaryWithEveryScalarTypeIsSkippedCorrectly) {
  test::TempDir dir;
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\n"
      "property char a\nproperty ushort b\nproperty float x\nproperty double c\nproperty float y\n"
      "property int16 d\nproperty float z\nproperty uint32 e\nproperty list ushort float f\nend_header\n";
  auto put = [&](auto v) { bytes.append(reinterpret_cast<const char*>(&v), sizeof v); };
  for (int i = 0; i < 2; ++i) {
    put(int8_t(-1)), put(uint16_t(7)), put(float(i)), put(double(9)), put(float(2 * i)), put(int16_t(-4));
    put(float(3 * i)), put(uint32_t(5)), put(uint16_t(2)), put(float(1)), put(float(2));
  }
  test::write_bytes(dir / "b.ply", bytes);
  const TriangleMesh m = read_ply(dir / "b.ply");
  ASSERT_EQ(m.vertices.size(), 2u);
  EXPECT_EQ(m.vertices.points[1], Eigen::Vector3f(1, 2, 3));
}

TEST(PlyIo, CorruptFilesThrowNamingTheFile) {
  test::TempDir dir;
  write_ply(dir / "ok.ply", sample_mesh(300, true));
  const std::string good = test::read_bytes(dir / "ok.ply");
  const auto path = dir / "bad.ply";
  auto expect_bad = [&](const std::string& bytes) {
    test::write_bytes(path, bytes);
    EXPECT_TRUE(throws_naming([&] { read_ply(path); }, "bad.ply")) << bytes.substr(0, 80);
  };
  expect_bad(good.substr(0, good.size() - 7));                 // truncated data
  expect_bad(good.substr(0, 40));                              // truncated header
  expect_bad("");                                              // empty
  expect_bad("not a ply\n");
  std::string lying = good;
  lying.replace(lying.find("vertex 300"), 10, "vertex 300000000000");  // absurd count
  expect_bad(lying);
  std::string bad_face = good;
  const size_t data = bad_face.find("end_header\n") + 11 + 300 * 32;
  bad_face[data + 4] = char(0x7f);  // high byte of face 0's first index -> out of range
  expect_bad(bad_face);
  expect_bad("ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float y\nend_header\n0000");
  expect_bad("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
             "end_header\n1 2 3\n4 5\n");
  expect_bad("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
             "end_header\n1 2 abc\n");
  expect_bad("ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list uint int vertex_indices\n"
             "end_header\n\xff\xff\xff\x7f");
  EXPECT_TRUE(throws_naming([&] { read_ply(dir / "absent.ply"); }, "absent.ply"));
}

// Random byte mutations of a valid file: each read either succeeds with a consistent mesh or
// throws semap::Error; never crashes (run under ASan in CI) or allocates without bound.
TEST(PlyIo, RandomMutationsNeverCrash) {
  test::TempDir dir;
  write_ply(dir / "ok.ply", sample_mesh(60, true));
  test::write_text(dir / "a.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                  "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                                  "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                  "0 0 0 1 2 3\n1 0 0 4 5 6\n0 1 0 7 8 9\n3 0 1 2\n");
  const std::string sources[2] = {test::read_bytes(dir / "ok.ply"), test::read_bytes(dir / "a.ply")};
  std::mt19937 rng(1234);
  int parsed = 0, rejected = 0;
  for (int iter = 0; iter < 1000; ++iter) {
    std::string bytes = sources[iter % 2];
    const int edits = 1 + rng() % 8;
    for (int e = 0; e < edits; ++e) {
      const size_t pos = rng() % bytes.size();
      switch (rng() % 4) {
        case 0: bytes[pos] = char(rng()); break;
        case 1: bytes[pos] = "0123456789 \n-e."[rng() % 15]; break;
        case 2: bytes.erase(pos, 1 + rng() % 16); break;
        default: bytes.insert(pos, 1, char(rng())); break;
      }
      if (bytes.empty()) bytes = "p";
    }
    try {
      const TriangleMesh m = parse_ply(bytes, "fuzz.ply");
      ASSERT_TRUE(m.vertices.consistent());
      for (const auto& t : m.triangles)
        for (uint32_t i : t) ASSERT_LT(i, m.vertices.size());
      ++parsed;
    } catch (const Error& e) {
      ASSERT_NE(std::string(e.what()).find("fuzz.ply"), std::string::npos) << e.what();
      ++rejected;
    }
  }
  EXPECT_GT(rejected, 100);  // mutations are actually detected
  EXPECT_GT(parsed, 10);     // and harmless ones (e.g. in float bytes) still parse
}

}  // namespace
}  // namespace semap
