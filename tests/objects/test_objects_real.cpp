// The object map on real detections (issue 17): 7-Scenes redkitchen (500 frames, a kitchen with
// one table, four or five chairs and a few mugs) mapped end to end with YOLOv8n-seg, as
// `semap run DATA --segmenter yolo:MODEL` does. Checked: the counts a person sees in the
// kitchen, and no duplicate (two objects of one class whose centroids are within 0.3 m, or where
// more than half of the smaller box lies inside the other). Heavy: a few minutes on 2 cores.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "semap/pipeline/run_pipeline.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

struct MapObject {
  std::string name;
  Eigen::Vector3f centroid;
  Eigen::AlignedBox3f box;
};

std::vector<MapObject> read_objects(const std::filesystem::path& objects_json) {
  std::ifstream in(objects_json);
  const nlohmann::json doc = nlohmann::json::parse(in);
  auto vec = [](const nlohmann::json& a) { return Eigen::Vector3f(a[0].get<float>(), a[1].get<float>(), a[2].get<float>()); };
  std::vector<MapObject> out;
  for (const auto& o : doc.at("objects"))
    out.push_back({o.at("class").get<std::string>(), vec(o.at("centroid")),
                   Eigen::AlignedBox3f(vec(o.at("aabb").at("min")), vec(o.at("aabb").at("max")))});
  return out;
}

/// The share of the smaller box's volume inside the other box.
double contained_share(const Eigen::AlignedBox3f& a, const Eigen::AlignedBox3f& b) {
  const double smaller = std::min(a.volume(), b.volume());
  if (!(smaller > 0)) return 0.0;
  const Eigen::AlignedBox3f common = a.intersection(b);
  return common.isEmpty() ? 0.0 : common.volume() / smaller;
}

TEST(ObjectsReal, RedkitchenWithYoloHasTheKitchensObjectsOnce) {
  SEMAP_REQUIRE_DATA(dataset, "7scenes_redkitchen");
  SEMAP_REQUIRE_MODEL(model, "yolov8n-seg-320.onnx");
  test::TempDir dir("objects_real");
  RunOptions options;
  options.dataset = dataset;
  options.out_dir = dir / "out";
  options.segmenter = "yolo:" + model.string();
  options.show_progress = false;
  const RunResult result = run_pipeline(options, SemapConfig{});
  const std::vector<MapObject> objects = read_objects(dir / "out" / "objects.json");
  std::map<std::string, int> per_class;
  for (const MapObject& o : objects) ++per_class[o.name];
  for (const auto& [name, count] : per_class) std::printf("  %-12s %d\n", name.c_str(), count);
  EXPECT_EQ(per_class["table"], 1);
  EXPECT_GE(per_class["chair"], 3);
  EXPECT_LE(per_class["chair"], 6);
  EXPECT_GE(per_class["cup"], 1);
  EXPECT_LE(per_class["cup"], 3);
  for (size_t i = 0; i < objects.size(); ++i)
    for (size_t j = i + 1; j < objects.size(); ++j) {
      if (objects[i].name != objects[j].name) continue;
      const double distance = (objects[i].centroid - objects[j].centroid).norm();
      const double inside = contained_share(objects[i].box, objects[j].box);
      EXPECT_GE(distance, 0.3) << objects[i].name << " pair " << i << ", " << j << ": centroids " << distance << " m apart";
      EXPECT_LE(inside, 0.5) << objects[i].name << " pair " << i << ", " << j << ": " << inside
                             << " of the smaller box inside the other";
    }
  EXPECT_EQ(result.mapper.objects, objects.size());
}

}  // namespace
}  // namespace semap
