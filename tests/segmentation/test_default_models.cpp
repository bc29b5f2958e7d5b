// Where `semap run` finds its default segmentation models (issue 38): --models, then
// $SEMAP_MODELS_DIR, the install prefix, the source tree; explicit specs win; "none" turns it off.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "semap/core/error.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "semap/segmentation/segmenter_factory.hpp"
#include "test_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;

void touch(const fs::path& p) { std::ofstream(p) << "not really a model"; }

/// Sets an environment variable for one scope, restoring the old value after.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) setenv(name_, old_->c_str(), 1);
    else unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

struct ModelFolders : ::testing::Test {
  test::TempDir tmp{"semap_default_models"};
  fs::path both = tmp / "both", semantic_only = tmp / "semantic_only", yolo_only = tmp / "yolo_only",
           empty = tmp / "empty";
  void SetUp() override {
    for (const auto& d : {both, semantic_only, yolo_only, empty}) fs::create_directories(d);
    touch(both / kDefaultSemanticModel);
    for (const char* name : kDefaultInstanceModels) touch(both / name);
    touch(semantic_only / kDefaultSemanticModel);
    touch(yolo_only / kDefaultInstanceModels[1]);  // only the less preferred instance model
  }
};

TEST_F(ModelFolders, SearchOrderIsOptionEnvInstallSource) {
  const ScopedEnv env("SEMAP_MODELS_DIR", semantic_only.string());
  const std::vector<fs::path> path = model_search_path(both);
  ASSERT_GE(path.size(), 3u);
  EXPECT_EQ(path[0], both);
  EXPECT_EQ(path[1], semantic_only);
  EXPECT_EQ(path[path.size() - 2].filename(), "models");  // <prefix>/share/semap/models
  EXPECT_EQ(path[path.size() - 2].parent_path().filename(), "semap");
  EXPECT_EQ(path.back().filename(), "models");  // <source>/../shared/models
  EXPECT_EQ(path.back().parent_path().filename(), "shared");
  // Without the option the environment comes first; without either, the built-in folders.
  EXPECT_EQ(model_search_path({}).front(), semantic_only);
  unsetenv("SEMAP_MODELS_DIR");
  EXPECT_EQ(model_search_path({}).size(), path.size() - 2);
}

TEST_F(ModelFolders, FirstFolderWithAModelDecides) {
  const DefaultSegmenter a = find_default_segmenter({empty, both, semantic_only});
  EXPECT_EQ(a.dir, both);
  EXPECT_EQ(a.spec, "panoptic:" + (both / kDefaultSemanticModel).string() + "+" + (both / kDefaultInstanceModels[0]).string());
  const DefaultSegmenter b = find_default_segmenter({empty, semantic_only, both});
  EXPECT_EQ(b.spec, "semantic:" + (semantic_only / kDefaultSemanticModel).string());
  const DefaultSegmenter c = find_default_segmenter({yolo_only, both});
  EXPECT_EQ(c.spec, "yolo:" + (yolo_only / kDefaultInstanceModels[1]).string());
  // No model anywhere: no spec (the run maps geometry and colour and says so).
  const DefaultSegmenter none = find_default_segmenter({empty, tmp / "missing"});
  EXPECT_TRUE(none.spec.empty());
  EXPECT_TRUE(none.dir.empty());
}

TEST_F(ModelFolders, ExplicitSpecsWinAndNoneTurnsItOff) {
  const ScopedEnv env("SEMAP_MODELS_DIR", semantic_only.string());
  SemapConfig config;
  ASSERT_EQ(config.segmentation.segmenter, kDefaultSegmenterSpec);
  RunOptions options;
  fs::path from;
  EXPECT_EQ(run_segmenter_spec(options, config, &from), "semantic:" + (semantic_only / kDefaultSemanticModel).string());
  EXPECT_EQ(from, semantic_only);
  options.models_dir = both;  // --models beats the environment
  EXPECT_EQ(run_segmenter_spec(options, config, &from).rfind("panoptic:", 0), 0u);
  EXPECT_EQ(from, both);
  options.segmenter = "none";
  EXPECT_EQ(run_segmenter_spec(options, config), "none");
  options.segmenter.clear();
  config.segmentation.segmenter = "yolo:/my/model.onnx";  // the config's explicit choice
  EXPECT_EQ(run_segmenter_spec(options, config), "yolo:/my/model.onnx");
  config.segmentation.segmenter = "none";
  EXPECT_EQ(run_segmenter_spec(options, config), "none");
  // --models naming a folder without a default model is an error naming the folder.
  config.segmentation.segmenter = kDefaultSegmenterSpec;
  options.models_dir = empty;
  try {
    run_segmenter_spec(options, config);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(empty.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace semap
