// Multi-session maps (issue 19): map.semap holds the whole map, loads back byte-identically, and a
// second recording resumes into it: relocalised against the saved keyframes, tracked and fused
// in the same world frame. Checked on a split of a shared sequence with ONE alignment of the
// joint trajectory against the ground truth.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/archive.hpp"
#include "core/progress.hpp"
#include "semap/core/error.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/trajectory_io.hpp"
#include "semap/mapper.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "synth/synth_config.hpp"
#include <nlohmann/json.hpp>
#include "pipeline/resume_support.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;

using test::file_bytes;
using test::map_recording;


TEST(MapArchive, SaveLoadSaveIsByteIdenticalAndOldOrForeignFilesAreErrorsNamingTheFile) {
  SEMAP_REQUIRE_DATA(tum, "tum_fr1_rpy");
  Progress::set_mode(-1);
  test::TempDir tmp("semap_map_archive");
  const auto reader = open_dataset(tum);
  SemapConfig config;
  config.pipeline.threads = 1;
  Mapper mapper(config, reader->camera());
  for (size_t i = 0; i < 30; ++i) mapper.add_frame(reader->load(i));
  mapper.finish();
  mapper.save(tmp / "a.semap");
  const auto loaded = Mapper::load(tmp / "a.semap");
  EXPECT_EQ(loaded->stats().resumed_keyframes, mapper.stats().keyframes);
  loaded->save(tmp / "b.semap");
  const std::string a = file_bytes(tmp / "a.semap"), b = file_bytes(tmp / "b.semap");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "load + save changed the file (" << a.size() << " vs " << b.size() << " bytes)";
  std::printf("[map archive] 30 TUM frames, %zu keyframes: %.1f MB\n", mapper.stats().keyframes, a.size() / 1e6);

  auto error_of = [](const fs::path& path) {
    try {
      Mapper::load(path);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  std::string v1 = a;
  v1[8] = 1;  // the version field: an older semap's TSDF-only file
  { std::ofstream(tmp / "v1.semap", std::ios::binary) << v1; }
  EXPECT_NE(error_of(tmp / "v1.semap").find("version 1"), std::string::npos) << error_of(tmp / "v1.semap");
  EXPECT_NE(error_of(tmp / "v1.semap").find("v1.semap"), std::string::npos);
  { std::ofstream(tmp / "foreign.semap", std::ios::binary) << "PK\x03\x04 a zip file"; }
  EXPECT_NE(error_of(tmp / "foreign.semap").find("not a semap map file"), std::string::npos);
  { std::ofstream(tmp / "cut.semap", std::ios::binary) << a.substr(0, a.size() / 2); }
  EXPECT_NE(error_of(tmp / "cut.semap").find("cut.semap"), std::string::npos);

  // Version 2 (uncompressed sections, the previous release) is still read: the same map.
  const ArchiveSections sections = read_map_archive(tmp / "a.semap");
  ByteWriter v2;
  v2.put_bytes("SEMAPMAP", 8);
  v2.put(uint32_t{2});
  v2.put(static_cast<uint32_t>(sections.size()));
  for (const auto& [name, payload] : sections) {
    v2.put(static_cast<uint32_t>(name.size()));
    v2.put_bytes(name.data(), name.size());
    v2.put_string(payload);
  }
  uint64_t sum = 1469598103934665603ULL;  // FNV-1a of everything after the version
  for (const char c : std::string_view(v2.bytes()).substr(12)) sum = (sum ^ static_cast<uint8_t>(c)) * 1099511628211ULL;
  v2.put(sum);
  { std::ofstream(tmp / "v2.semap", std::ios::binary) << v2.bytes(); }
  EXPECT_LT(a.size() * 3, v2.bytes().size()) << "version 3 compresses the sections";
  Mapper::load(tmp / "v2.semap")->save(tmp / "v2_again.semap");
  EXPECT_TRUE(file_bytes(tmp / "v2_again.semap") == a) << "a version 2 file loads as the same map";
}

// A recording of another place never relocalises into the saved map: it is mapped on its own,
// not merged at a guessed pose, and the report says so.
TEST(Resume, ARecordingOfAnotherPlaceIsMappedOnItsOwnNotMerged) {
  Progress::set_mode(-1);
  test::TempDir tmp("semap_resume_apart");
  test::write_two_rooms(tmp.path());
  map_recording(tmp / "room1", tmp / "out1");
  const RunResult r2 = map_recording(tmp / "room2", tmp / "out2", tmp / "out1");
  EXPECT_TRUE(r2.not_merged);
  EXPECT_EQ(r2.mapper.resumed_keyframes, 0u) << "the second map is its own";
  const auto report = nlohmann::json::parse(file_bytes(tmp / "out2" / "report.json"));
  EXPECT_EQ(report["resumed"]["merged"], false) << report.dump(2);
  const double ate = compute_ate(open_dataset(tmp / "room2")->ground_truth(),
                                 read_tum_trajectory(tmp / "out2" / "trajectory.txt")).rmse;
  EXPECT_LT(ate, 0.05) << "tracked on its own as without --resume";
}

}  // namespace
}  // namespace semap
