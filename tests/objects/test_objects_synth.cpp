// The object map on the synthetic world (issue 6 "Measured"): exact counts and WOv with
// ground-truth masks and poses.
#include <gtest/gtest.h>

#include <chrono>
#include <iostream>

#include "objects_synth_support.hpp"
#include "test_support.hpp"

using namespace semap;

namespace {
std::string to_string(const std::map<std::string, int>& counts) {
  std::string s;
  for (const auto& [c, n] : counts) s += c + ":" + std::to_string(n) + " ";
  return s;
}
}  // namespace

TEST(ObjectsSynth, GroundTruthMasksGiveExactCountsAndHighWov) {
  test::TempDir dir("objects_synth");
  SynthConfig synth;
  synth.frames = 60;
  synth.seed = 1;
  synth.objects = 10;
  synth.width = 320;
  synth.height = 240;
  const auto t0 = std::chrono::steady_clock::now();
  generate_dataset(synth, dir.path() / "data");
  const auto t1 = std::chrono::steady_clock::now();
  ObjectsConfig config;
  config.pixel_stride = 1;
  config.optimise_every = 20;
  const auto run = test::run_object_mapper(dir.path() / "data", config, std::nullopt, 2, dir.path() / "out");
  const auto t2 = std::chrono::steady_clock::now();
  const auto gt = test::load_gt_objects(dir.path() / "data");
  const double wov = test::weighted_overlap(gt, run.instances);
  std::cout << "synth " << std::chrono::duration<double>(t1 - t0).count() << " s, mapping "
            << std::chrono::duration<double>(t2 - t1).count() << " s; seg " << run.timings.segmentation_ms / run.timings.frames
            << " ms/kf, assoc " << run.timings.association_ms / run.timings.frames << " ms/kf\n"
            << "gt:   " << to_string(test::counts_per_class(gt)) << "\nmap:  " << to_string(test::counts_per_class(run.instances))
            << "\nWOv " << wov << "\n";
  if (std::getenv("SEMAP_OBJECTS_DEBUG")) {
    ObjectMap probe(config);
    for (size_t i = 0; i < run.instances.size(); ++i) {
      const auto& a = run.instances[i];
      std::cout << "inst " << a.id << " " << class_name(a.class_id()) << " n=" << a.n << " s=" << a.total_associations
                << " pts=" << a.points.size() << " state=" << state_name(a.state) << " frames " << a.first_frame << "-"
                << a.last_frame << "\n";
      for (size_t j = 0; j < run.instances.size(); ++j) {
        const auto& b = run.instances[j];
        if (i == j || a.class_id() != b.class_id()) continue;
        std::cout << "   vs " << b.id << " overlap " << probe.overlap(a.points, b, config.overlap_distance) << " dist "
                  << (a.centroid() - b.centroid()).norm() << "\n";
      }
    }
  }
  EXPECT_EQ(test::counts_per_class(run.instances), test::counts_per_class(gt));
  // Keyframes every 2nd frame, ObjectMapper::accumulate on the others (surface IoU at 3 cm here;
  // the CLI figure of issue 6 uses 2 cm, see object_metrics.hpp). Measured 0.9998 (0.931 by
  // voxel sets).
  EXPECT_GE(wov, 0.97);

  // objects.json + objects/<id>.ply (SHARED_FORMATS.md).
  std::ifstream in(dir.path() / "out" / "objects.json");
  ASSERT_TRUE(in.good());
  const auto doc = nlohmann::json::parse(in);
  ASSERT_EQ(doc["objects"].size(), run.instances.size());
  for (const auto& o : doc["objects"]) {
    for (const char* key : {"id", "class", "class_id", "class_distribution", "n", "association_count", "centroid", "aabb",
                            "obb", "point_count", "points_file", "first_seen", "last_seen", "state"})
      EXPECT_TRUE(o.contains(key)) << key;
    const auto cloud = read_ply(dir.path() / "out" / o["points_file"].get<std::string>());
    EXPECT_EQ(cloud.vertices.size(), o["point_count"].get<size_t>());
    EXPECT_EQ(o["obb"]["rotation"].size(), 9u);
    EXPECT_NEAR(o["class_distribution"][o["class"].get<std::string>()].get<double>(), 1.0, 1e-6);
  }
}
