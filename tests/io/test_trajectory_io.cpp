#include <cmath>
#include <random>

#include "io/association.hpp"
#include "semap/io/trajectory_io.hpp"
#include "io_test_util.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

using test::throws_naming;

Trajectory random_trajectory(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-10, 10);
  Trajectory t;
  double stamp = 1305031229.528748;
  for (size_t i = 0; i < n; ++i) {
    stamp += 0.01 + std::abs(u(rng)) * 0.01;
    Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
    t.push_back({stamp, pose_from_tq({u(rng), u(rng), u(rng)}, q.normalized())});
  }
  return t;
}

TEST(TrajectoryIo, RoundTripIsExact) {
  test::TempDir dir;
  const Trajectory original = random_trajectory(500, 7);
  write_tum_trajectory(dir / "t.txt", original);
  const Trajectory back = read_tum_trajectory(dir / "t.txt");
  ASSERT_EQ(back.size(), original.size());
  double max_err = 0;
  for (size_t i = 0; i < back.size(); ++i) {
    max_err = std::max(max_err, std::abs(back[i].timestamp - original[i].timestamp));
    max_err = std::max(max_err, (back[i].T_world_camera.matrix() - original[i].T_world_camera.matrix()).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(max_err, 1e-9);
}

TEST(TrajectoryIo, ParsesCommentsBlankLinesAndNormalisesNearUnitQuaternions) {
  const Trajectory t = parse_tum_trajectory("# header\n\n1.0 1 2 3 0 0 0 1\r\n2.0,1,2,3,0,0,0.0002,1.0003\n", "mem");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[1].T_world_camera.translation(), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(is_valid_pose(t[1].T_world_camera, 1e-12));
}

TEST(TrajectoryIo, BadLinesNameFileAndLine) {
  const std::string good = "# c\n1.0 0 0 0 0 0 0 1\n";
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "2.0 0 0 0 0 0 1\n", "f.txt"); }, "f.txt:3"));
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "2.0 0 x 0 0 0 0 1\n", "f.txt"); }, "f.txt:3"));
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "2.0 nan 0 0 0 0 0 1\n", "f.txt"); }, "NaN"));
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "2.0 0 inf 0 0 0 0 1\n", "f.txt"); }, "f.txt:3"));
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "2.0 0 0 0 0 0 0 2\n", "f.txt"); }, "not unit"));
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "2.0 0 0 0 0 0 0 0\n", "f.txt"); }, "f.txt:3"));
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "1.0 0 0 0 0 0 0 1\n", "f.txt"); }, "duplicate"));
  EXPECT_TRUE(throws_naming([&] { parse_tum_trajectory(good + "0.5 0 0 0 0 0 0 1\n", "f.txt"); }, "f.txt:3"));
  test::TempDir dir;
  EXPECT_TRUE(throws_naming([&] { read_tum_trajectory(dir / "missing.txt"); }, "missing.txt"));
  test::write_text(dir / "nan.txt", good + "2.0 0 0 0 NaN 0 0 1\n");
  EXPECT_TRUE(throws_naming([&] { read_tum_trajectory(dir / "nan.txt"); }, "nan.txt:3"));
}

TEST(Association, OneToOneNearestWithinMaxDifference) {
  // b[1] is nearest to both a[0] and a[1]: the closer pair wins, a[0] takes b[0].
  const std::vector<double> a = {1.000, 1.012, 2.000, 3.000};
  const std::vector<double> b = {0.990, 1.011, 2.030, 2.995, 3.001};
  const auto m = associate_timestamps(a, b, 0.02);
  const std::vector<std::pair<size_t, size_t>> expected = {{0, 0}, {1, 1}, {3, 4}};
  EXPECT_EQ(m, expected);  // a[2] has nothing within 0.02 s
}

TEST(Association, OffsetAndUnsortedInputMatchBruteForce) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 5);
  std::vector<double> a(300), b(280);
  for (auto& x : a) x = u(rng);
  for (auto& x : b) x = u(rng);
  const double offset = 0.1, max_diff = 0.02;
  // Brute force exactly as associate.py.
  std::vector<std::tuple<double, size_t, size_t>> pairs;
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (std::abs(a[i] - (b[j] + offset)) < max_diff) pairs.emplace_back(std::abs(a[i] - (b[j] + offset)), i, j);
  std::sort(pairs.begin(), pairs.end());
  std::vector<char> ua(a.size()), ub(b.size());
  std::vector<std::pair<size_t, size_t>> expected;
  for (auto [d, i, j] : pairs)
    if (!ua[i] && !ub[j]) ua[i] = ub[j] = 1, expected.emplace_back(i, j);
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(associate_timestamps(a, b, max_diff, offset), expected);
  EXPECT_GT(expected.size(), 50u);
}

}  // namespace
}  // namespace semap
