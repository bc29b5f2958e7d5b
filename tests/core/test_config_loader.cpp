#include <gtest/gtest.h>

#include "semap/core/error.hpp"
#include "semap/io/config_loader.hpp"
#include "semap/pipeline/semap_config.hpp"

namespace semap {
namespace {

SemapConfig load(const std::string& yaml) {
  SemapConfig c;
  load_config_string(yaml, "test.yaml", [&](ParamVisitor& v) { c.visit(v); });
  c.validate();
  return c;
}

std::string error_of(const std::string& yaml) {
  try {
    load(yaml);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(ConfigLoader, OverridesDefaults) {
  const SemapConfig c = load("tsdf:\n  voxel_size: 0.05\npipeline:\n  threads: 1\n");
  EXPECT_DOUBLE_EQ(c.tsdf.voxel_size, 0.05);
  EXPECT_EQ(c.pipeline.threads, 1);
  EXPECT_EQ(c.objects.optimise_every, SemapConfig{}.objects.optimise_every);
}

TEST(ConfigLoader, UnknownKeyNamesTheKey) {
  EXPECT_NE(error_of("tsdf:\n  voxel_sise: 0.05\n").find("tsdf.voxel_sise"), std::string::npos);
  EXPECT_NE(error_of("nonsense: 1\n").find("nonsense"), std::string::npos);
}

TEST(ConfigLoader, BadValuesNameTheKey) {
  EXPECT_NE(error_of("tsdf:\n  voxel_size: abc\n").find("tsdf.voxel_size"), std::string::npos);
  EXPECT_NE(error_of("tsdf:\n  voxel_size: -1\n").find("tsdf.voxel_size"), std::string::npos);
  EXPECT_NE(error_of("pipeline:\n  threads: 1.5\n").find("pipeline.threads"), std::string::npos);
  EXPECT_NE(error_of("tsdf: [1, 2]\n").find("tsdf"), std::string::npos);
  EXPECT_NE(error_of("tsdf: {voxel_size: [0.1]}\n").find("tsdf.voxel_size"), std::string::npos);
}

// Found by fuzz_config_yaml: a YAML map used as a key ("? segmenter: x") escaped as an uncaught
// yaml-cpp exception (std::terminate) instead of a clean error.
TEST(ConfigLoader, NonScalarKeyIsACleanError) {
  EXPECT_NE(error_of("segmentation:\n ? segmenter: groundtruth\n").find("segmentation"), std::string::npos);
  EXPECT_NE(error_of("? [a, b]\n: 1\n").find("top level"), std::string::npos);
}

TEST(ConfigLoader, MalformedYamlNamesTheFile) {
  const std::string e = error_of("tsdf:\n  voxel_size: [0.1\n");
  EXPECT_NE(e.find("test.yaml"), std::string::npos);
  EXPECT_NE(e.find("malformed"), std::string::npos);
}

TEST(ConfigLoader, DumpRoundTrips) {
  SemapConfig c;
  c.tsdf.voxel_size = 0.037;
  const std::string text = dump_config([&](ParamVisitor& v) { c.visit(v); });
  const SemapConfig back = load(text);
  EXPECT_DOUBLE_EQ(back.tsdf.voxel_size, 0.037);
  EXPECT_EQ(dump_config([&](ParamVisitor& v) { SemapConfig(back).visit(v); }), text);
}

}  // namespace semap
