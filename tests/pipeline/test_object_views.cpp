// Issue 43: each object's best view (objects/best_views.hpp) is kept in map.semap, so that a
// saved, resumed or merged map's report cards keep their camera thumbnails. A map written before
// the views were saved still loads; a corrupt view section is one error naming the file.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <nlohmann/json.hpp>

#include "core/archive.hpp"
#include "core/progress.hpp"
#include "objects/best_views.hpp"
#include "pipeline/report_svg.hpp"
#include "pipeline/resume_support.hpp"
#include "semap/core/error.hpp"
#include "semap/io/dataset.hpp"
#include "semap/mapper.hpp"
#include "semap/pipeline/map_merge.hpp"
#include "semap/pipeline/outputs.hpp"
#include "synthetic_room.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::file_bytes;

using Views = std::map<uint32_t, std::string>;  ///< object id -> its best view (JPEG)

Views views_of(const std::vector<ObjectSummary>& objects) {
  Views out;
  for (const ObjectSummary& o : objects)
    if (!o.best_view_jpeg.empty()) out[o.id] = o.best_view_jpeg;
  return out;
}

/// The views of the map saved at `path` (read without a segmenter).
Views saved_views(const fs::path& path) {
  SemapConfig config;
  config.segmentation.segmenter = "none";
  return views_of(Mapper::load(path, config)->objects());
}

std::string load_error(const fs::path& path) {
  try {
    Mapper::load(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "loaded";
}

class ObjectViewsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    Progress::set_mode(-1);
    test::copy_small_synthetic_room(tmp_ / "room");  // 90 frames, 10 objects, 320x240
  }
  /// `semap run` over the room's first `frames` frames, tracked, with `segmenter`.
  RunResult map_room(const std::string& out, size_t frames, const std::string& segmenter,
                     const fs::path& resume = {}) const {
    RunOptions o;
    o.dataset = tmp_ / "room";
    o.out_dir = tmp_ / out;
    o.segmenter = segmenter;
    o.max_frames = frames;
    o.evaluate = false;
    o.show_progress = false;
    o.resume_from = resume;
    SemapConfig config;
    config.pipeline.threads = 2;
    config.tsdf.voxel_size = 0.04;
    return run_pipeline(o, config);
  }
  test::TempDir tmp_{"semap_object_views"};
};

// A map saved and loaded keeps every view byte for byte; saving it again gives the same file;
// a map without the section (written before issue 43) loads with no views; a corrupt section
// is one error naming the file.
TEST_F(ObjectViewsTest, SavedMapKeepsEveryViewAndOlderMapsStillLoad) {
  const auto dataset = open_dataset(tmp_ / "room");
  SemapConfig config;
  config.pipeline.threads = 1;
  config.tsdf.voxel_size = 0.04;
  Mapper mapper(config, dataset->camera());
  test::map_with_ground_truth_hints(mapper, *dataset, 30);
  const Views views = views_of(mapper.objects());
  ASSERT_GE(views.size(), 3u);
  mapper.save(tmp_ / "a.semap");
  const auto loaded = Mapper::load(tmp_ / "a.semap");
  EXPECT_TRUE(views_of(loaded->objects()) == views) << "every view comes back byte-identical";
  loaded->save(tmp_ / "b.semap");
  const std::string a = file_bytes(tmp_ / "a.semap");
  EXPECT_TRUE(file_bytes(tmp_ / "b.semap") == a) << "load + save changed the file";
  ArchiveSections sections = read_map_archive(tmp_ / "a.semap");
  size_t view_bytes = 0;
  for (const auto& [id, jpeg] : views) view_bytes += jpeg.size();
  std::printf("[object views] %zu of %zu objects with a view, %zu B of JPEG (%.0f B per view); section %zu B of "
              "%zu B map.semap\n",
              views.size(), mapper.objects().size(), view_bytes, double(view_bytes) / views.size(),
              sections.at(kObjectViewsSection).size(), a.size());

  sections.erase(kObjectViewsSection);  // as semap wrote maps before issue 43
  write_map_archive(tmp_ / "old.semap", sections);
  const auto old = Mapper::load(tmp_ / "old.semap");
  EXPECT_EQ(old->objects().size(), mapper.objects().size());
  EXPECT_TRUE(views_of(old->objects()).empty());

  sections[kObjectViewsSection] = read_map_archive(tmp_ / "a.semap").at(kObjectViewsSection);
  sections[kObjectViewsSection].resize(sections[kObjectViewsSection].size() - 5);
  write_map_archive(tmp_ / "cut_views.semap", sections);
  const std::string e = load_error(tmp_ / "cut_views.semap");
  EXPECT_NE(e.find("cut_views.semap"), std::string::npos) << e;
  EXPECT_NE(e.find(kObjectViewsSection), std::string::npos) << e;
  // The CLI: one line naming the file, exit 1, nothing written.
  const auto cli = test::run_command(test::shell_quote(test::semap_executable().string()) + " run " +
                                     test::shell_quote((tmp_ / "room").string()) + " --out " +
                                     test::shell_quote((tmp_ / "cli").string()) + " --segmenter none --resume " +
                                     test::shell_quote((tmp_ / "cut_views.semap").string()) + " 2>&1");
  EXPECT_EQ(cli.exit_code, 1) << cli.output;
  std::vector<std::string> errors;
  std::istringstream lines(cli.output);
  for (std::string line; std::getline(lines, line);)
    if (line.starts_with("semap: error:")) errors.push_back(line);
  ASSERT_EQ(errors.size(), 1u) << cli.output;
  EXPECT_NE(errors[0].find("cut_views.semap"), std::string::npos) << cli.output;
  EXPECT_NE(errors[0].find(kObjectViewsSection), std::string::npos) << cli.output;
  EXPECT_FALSE(fs::exists(tmp_ / "cli" / "map.semap"));
}

// A resumed run keeps the saved objects' views: its report's cards show them as camera crops
// even where no new frame segmented the object (here: the resumed run has no segmenter).
// `semap merge` keeps them too, following the objects' new ids.
TEST_F(ObjectViewsTest, ResumedAndMergedMapsKeepTheirViews) {
  map_room("first", 30, "groundtruth");
  const Views first = saved_views(tmp_ / "first" / "map.semap");
  ASSERT_GE(first.size(), 3u);

  const RunResult resumed = map_room("resumed", 10, "none", tmp_ / "first");
  ASSERT_FALSE(resumed.not_merged) << "the same room relocalises";
  const Views kept = saved_views(tmp_ / "resumed" / "map.semap");
  const std::string html = file_bytes(tmp_ / "resumed" / "report.html");
  size_t shown = 0;
  for (const auto& [id, jpeg] : kept) {
    const auto before = first.find(id);
    ASSERT_TRUE(before != first.end()) << "object " << id << " has a view no frame of the resumed run made";
    EXPECT_TRUE(jpeg == before->second) << "object " << id;
    shown += html.find("data:image/jpeg;base64," + report::base64(jpeg)) != std::string::npos;
  }
  const size_t objects = resumed.mapper.objects;
  std::printf("[object views] resumed: %zu objects, %zu with their saved view, %zu shown in report.html\n", objects,
              kept.size(), shown);
  EXPECT_GE(kept.size(), objects * 8 / 10) << "the saved views survive the resumed run";
  EXPECT_EQ(shown, kept.size()) << "every kept view is a card's thumbnail";
  EXPECT_NE(html.find("Continued a saved map of "), std::string::npos) << "the summary says it was resumed";

  // Merged: A has no objects (no segmenter), B's objects join it with A's ids and B's views.
  map_room("bare", 30, "none");
  const MapMergeResult merged = merge_maps(tmp_ / "bare", tmp_ / "first", tmp_ / "merged");
  ASSERT_TRUE(merged.merged) << merged.reason;
  std::multiset<std::string> b_views, merged_views;
  for (const auto& [id, jpeg] : first) b_views.insert(jpeg);
  for (const auto& [id, jpeg] : saved_views(tmp_ / "merged" / "map.semap")) merged_views.insert(jpeg);
  EXPECT_EQ(merged.objects, merged.objects_b);
  EXPECT_TRUE(merged_views == b_views) << merged_views.size() << " views after the merge, " << b_views.size() << " before";
}

}  // namespace
}  // namespace semap
