// The output-folder mechanism of issue 22 ("Data loss and writes where they must not go"), at the
// library level: staging + publish, manifests and stale files, markers, planted symlinks,
// interrupted publishes, leftovers of killed processes, one writer at a time.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "semap/core/error.hpp"
#include "core/paths.hpp"
#include "io/output_folder.hpp"
#include "reliability/reliability_support.hpp"

namespace semap {
namespace {

namespace fs = std::filesystem;
using test::slurp;
using test::spit;
using test::tree;

std::vector<std::string> visible(const fs::path& dir) {
  const auto files = test::visible(dir);
  return {files.begin(), files.end()};
}

void publish_run(const fs::path& dir, const std::vector<std::pair<std::string, std::string>>& files,
                 const std::string& tool = "run") {
  OutputFolder out(dir, {.tool = tool, .refuse_foreign_non_empty = false, .remove_stale = true,
                         .publish_last = {"report.json"}, .inputs = {}});
  for (const auto& [name, bytes] : files) write_file_atomic(out.path(name), bytes);
  out.publish();
}

TEST(OutputFolder, PublishesEverythingAtOnceAndRemovesStaleFilesOfTheLastRun) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out";
  publish_run(dir, {{"mesh.ply", "m1"}, {"objects/1.ply", "o1"}, {"objects/2.ply", "o2"}, {"report.json", "r1"}});
  EXPECT_EQ(visible(dir), (std::vector<std::string>{"mesh.ply", "objects/1.ply", "objects/2.ply", "report.json"}));
  EXPECT_EQ(OutputFolder::read_manifest(dir, "run").size(), 4u);
  spit(dir / "notes.txt", "the user's own file");
  spit(dir / "objects" / "mine.ply", "the user's own file in a semap folder");

  // Second run: object 2 is gone, object 3 is new; the user's files stay.
  publish_run(dir, {{"mesh.ply", "m2"}, {"objects/1.ply", "o1b"}, {"objects/3.ply", "o3"}, {"report.json", "r2"}});
  EXPECT_EQ(visible(dir), (std::vector<std::string>{"mesh.ply", "notes.txt", "objects/1.ply", "objects/3.ply",
                                                    "objects/mine.ply", "report.json"}));
  EXPECT_EQ(slurp(dir / "mesh.ply"), "m2");
  EXPECT_EQ(slurp(dir / "objects" / "mine.ply"), "the user's own file in a semap folder");
  const auto manifest = OutputFolder::read_manifest(dir, "run");
  EXPECT_EQ(manifest, (std::vector<std::string>{"mesh.ply", "objects/1.ply", "objects/3.ply", "report.json"}));
  // No staging folder, temp file or journal is left.
  for (const auto& f : tree(dir)) EXPECT_EQ(f.find("staging"), std::string::npos) << f;
  EXPECT_FALSE(fs::exists(dir / ".semap-manifest-run.pending.json"));
}

TEST(OutputFolder, AFailedRunLeavesThePreviousRunUntouched) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out";
  publish_run(dir, {{"mesh.ply", "m1"}, {"trajectory.txt", "t1"}, {"report.json", "r1"}});
  const auto before = tree(dir);
  try {
    OutputFolder out(dir, {.tool = "run", .refuse_foreign_non_empty = false, .remove_stale = true, .publish_last = {}, .inputs = {}});
    write_file_atomic(out.path("trajectory.txt"), "t2");
    write_file_atomic(out.path("mesh.ply"), "m2");
    throw Error("test", "the run fails midway");
  } catch (const Error&) {
  }
  EXPECT_EQ(tree(dir), before);
  EXPECT_EQ(slurp(dir / "trajectory.txt"), "t1");
  EXPECT_EQ(slurp(dir / "mesh.ply"), "m1");
  // A folder this object created is removed again when nothing was published.
  { OutputFolder out(tmp / "fresh", {}); write_file_atomic(out.path("a.txt"), "x"); }
  EXPECT_FALSE(fs::exists(tmp / "fresh"));
}

TEST(OutputFolder, ToolsSharingAFolderKeepEachOthersFiles) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out";
  publish_run(dir, {{"mesh.ply", "m"}, {"report.json", "r"}});
  publish_run(dir, {{"viewer/index.html", "v"}}, "view");
  publish_run(dir, {{"viewer/index.html", "v2"}}, "view");
  EXPECT_EQ(visible(dir), (std::vector<std::string>{"mesh.ply", "report.json", "viewer/index.html"}));
}

TEST(OutputFolder, RefusesForeignNonEmptyFoldersWhenAsked) {
  test::TempDir tmp("semap_outfolder");
  const fs::path data = tmp / "tum";
  fs::create_directories(data / "rgb");
  spit(data / "dataset.yaml", "format: tum\n");
  spit(data / "rgb" / "1.png", "precious");
  const auto before = tree(data);
  const OutputFolderOptions refuse{.tool = "synth", .refuse_foreign_non_empty = true, .remove_stale = true,
                                   .publish_last = {}, .inputs = {}};
  EXPECT_THROW(OutputFolder(data, refuse), Error);
  EXPECT_EQ(tree(data), before);
  // A marker that is not a regular file (a symlink to one elsewhere) does not count.
  spit(tmp / "elsewhere", "x");
  fs::create_symlink(tmp / "elsewhere", data / ".semap-output");
  EXPECT_THROW(OutputFolder(data, refuse), Error);
  // Without the flag, a foreign folder is written beside its files and they are never removed.
  fs::remove(data / ".semap-output");
  publish_run(data, {{"mesh.ply", "m"}});
  publish_run(data, {{"other.ply", "o"}});
  EXPECT_EQ(slurp(data / "rgb" / "1.png"), "precious");
  EXPECT_TRUE(fs::exists(data / "dataset.yaml"));
  EXPECT_FALSE(fs::exists(data / "mesh.ply"));  // ours, stale: removed
  EXPECT_FALSE(fs::exists(data / ".semap-output")) << "a foreign folder is not claimed";
}

TEST(OutputFolder, APlantedSymlinkIsNeverWrittenThrough) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out", outside = tmp / "outside";
  fs::create_directories(outside);
  publish_run(dir, {{"mesh.ply", "m"}});
  // DIR/viewer -> outside: publishing viewer/* is refused, nothing lands outside.
  fs::create_directory_symlink(outside, dir / "viewer");
  EXPECT_THROW(publish_run(dir, {{"viewer/index.html", "v"}}, "view"), Error);
  EXPECT_TRUE(fs::is_empty(outside));
  // A symlink at a file's own name is not semap's (issue 44): the publish is refused, the link
  // and its target untouched.
  spit(outside / "victim", "keep");
  fs::create_symlink(outside / "victim", dir / "report.json");
  EXPECT_THROW(publish_run(dir, {{"mesh.ply", "m"}, {"report.json", "r"}}), Error);
  EXPECT_EQ(slurp(outside / "victim"), "keep");
  EXPECT_TRUE(fs::is_symlink(dir / "report.json"));
  EXPECT_EQ(slurp(dir / "mesh.ply"), "m");
  // A manifest edited to point outside (or through the symlink) removes nothing there.
  spit(outside / "victim2", "keep");
  nlohmann::json hostile{{"files", {"../outside/victim2", "/etc/hostname", "viewer/victim", "report.json"}},
                         {"dirs", {"viewer"}}};
  spit(outside / "victim", "keep");
  spit(dir / ".semap-manifest-run.json", hostile.dump());
  publish_run(dir, {{"other.ply", "o"}});
  EXPECT_EQ(slurp(outside / "victim2"), "keep");
  EXPECT_EQ(slurp(outside / "victim"), "keep");
  EXPECT_TRUE(fs::is_symlink(dir / "viewer"));
}

TEST(OutputFolder, WriteFileAtomicIgnoresPlantedTempNames) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out", outside = tmp / "outside";
  fs::create_directories(dir);
  fs::create_directories(outside);
  // The old fixed temporary names, each a symlink to a file outside.
  for (const char* name : {"report.json.tmp", ".report.json.tmp", "report.json.partial"}) {
    spit(outside / name, "keep");
    fs::create_symlink(outside / name, dir / name);
  }
  write_file_atomic(dir / "report.json", "new");
  write_atomic_with(dir / "mesh.ply", [](const fs::path& t) { spit(t, "mesh"); });
  EXPECT_EQ(slurp(dir / "report.json"), "new");
  EXPECT_EQ(slurp(dir / "mesh.ply"), "mesh");
  for (const char* name : {"report.json.tmp", ".report.json.tmp", "report.json.partial"})
    EXPECT_EQ(slurp(outside / name), "keep") << name;
  size_t temps = 0;
  for (const auto& f : tree(dir)) temps += is_semap_temp_name(f);
  EXPECT_EQ(temps, 0u);
}

TEST(OutputFolder, InterruptedPublishesAndKilledProcessesAreCleanedUpNextTime) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out";
  publish_run(dir, {{"mesh.ply", "m1"}, {"objects/7.ply", "o7"}, {"report.json", "r1"}});
  // A publish cut short by power loss: the journal lists the old and new files, objects/9.ply
  // was renamed in, and the manifest was already removed. The next run removes both stale
  // objects (and may replace the journal's files: they are semap's).
  spit(dir / "objects" / "9.ply", "o9");
  spit(dir / ".semap-manifest-run.pending.json",
       R"({"files": ["objects/9.ply", "objects/7.ply", "mesh.ply", "report.json"], "dirs": []})");
  fs::remove(dir / ".semap-manifest-run.json");
  // A killed process' staging folder (pid 2^22 + 7 is above Linux's pid_max) and temp file.
  const fs::path dead = dir / ".semap-staging-4194311-00000000000000aa";
  fs::create_directories(dead / "objects");
  spit(dead / ".semap-staging", "marker");
  spit(dead / "objects" / "1.ply", "half");
  spit(dir / ".mesh.ply.semap-tmp-4194311-1234", "half");
  // A folder that merely looks like one (no marker inside) is not semap's: kept.
  fs::create_directories(dir / ".semap-staging-4194311-00000000000000bb");
  publish_run(dir, {{"mesh.ply", "m2"}, {"report.json", "r2"}});
  EXPECT_FALSE(fs::exists(dir / "objects" / "9.ply"));
  EXPECT_FALSE(fs::exists(dir / "objects" / "7.ply"));
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_FALSE(fs::exists(dir / ".mesh.ply.semap-tmp-4194311-1234"));
  EXPECT_TRUE(fs::exists(dir / ".semap-staging-4194311-00000000000000bb"));
  EXPECT_FALSE(fs::exists(dir / ".semap-manifest-run.pending.json"));
  EXPECT_EQ(OutputFolder::read_manifest(dir, "run"), (std::vector<std::string>{"mesh.ply", "report.json"}));
}

TEST(OutputFolder, OneWriterAtATimeAndNamesStayInside) {
  test::TempDir tmp("semap_outfolder");
  OutputFolder first(tmp / "out", {});
  EXPECT_THROW(OutputFolder(tmp / "out", {}), Error);
  EXPECT_THROW(first.path("../escape.txt"), Error);
  EXPECT_THROW(first.path("/etc/passwd"), Error);
  spit(tmp / "file", "x");
  EXPECT_THROW(OutputFolder(tmp / "file", {}), Error);
}

// Issue 44 class 4: a file at an output's place that semap did not write stops the publish
// before anything moves; the tool's own earlier files are replaced as before.
TEST(OutputFolder, PublishNeverReplacesAFileSemapDidNotWrite) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out";
  fs::create_directories(dir / "objects");
  spit(dir / "mesh.ply", "the user's mesh");
  spit(dir / "objects" / "3.ply", "the user's object");
  const auto before = tree(dir);
  for (const std::string user_file : {"mesh.ply", "objects/3.ply"}) {
    try {
      publish_run(dir, {{"report.json", "{}"}, {user_file, "semap's"}});
      ADD_FAILURE() << user_file << " was replaced";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(user_file), std::string::npos) << e.what();
    }
    EXPECT_EQ(tree(dir), before) << "nothing of the refused run may appear";
  }
  EXPECT_EQ(slurp(dir / "mesh.ply"), "the user's mesh");
  // Another tool's files are not this tool's: `view` may not replace what `run` wrote.
  publish_run(dir, {{"report.json", "run 1"}});
  publish_run(dir, {{"report.json", "run 2"}});  // its own file: replaced
  EXPECT_EQ(slurp(dir / "report.json"), "run 2");
  EXPECT_THROW(publish_run(dir, {{"report.json", "view"}}, "view"), Error);
  EXPECT_EQ(slurp(dir / "report.json"), "run 2");
}

// Issue 44: the outputs a command knows it will publish are checked when the folder is opened,
// before the command's work, not only at publish; its own earlier outputs are no conflict.
TEST(OutputFolder, PlannedOutputsAreCheckedWhenTheFolderIsOpened) {
  test::TempDir tmp("semap_outfolder");
  const fs::path dir = tmp / "out";
  fs::create_directories(dir);
  spit(dir / "mesh.ply", "the user's mesh");
  spit(dir / "notes.txt", "the user's notes");
  const auto before = tree(dir);
  try {
    OutputFolder out(dir, {.tool = "run", .inputs = {}, .planned = {"trajectory.txt", "mesh.ply"}});
    ADD_FAILURE() << "opened a folder holding the user's mesh.ply";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("mesh.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not written by semap"), std::string::npos) << e.what();
  }
  EXPECT_EQ(tree(dir), before) << "a refused open leaves the folder as it was";
  // Files the command will not write are the user's business; what semap wrote is its own.
  fs::remove(dir / "mesh.ply");
  publish_run(dir, {{"report.json", "{}"}, {"mesh.ply", "semap's"}});
  OutputFolder again(dir, {.tool = "run", .inputs = {}, .planned = {"mesh.ply", "report.json"}});
  EXPECT_EQ(slurp(dir / "notes.txt"), "the user's notes");
}

// Issue 44 class 4: DIR may not be an input nor hold one, by any path (symlink, "..").
TEST(OutputFolder, RefusesAnOutputFolderThatIsOrContainsAnInput) {
  test::TempDir scratch("semap_outfolder");
  const fs::path tmp = scratch.path();
  const fs::path data = tmp / "rec";
  fs::create_directories(data / "rgb");
  spit(data / "report.json", "the recording's own report");
  fs::create_directory_symlink(data, tmp / "alias");
  spit(tmp / "map.semap", "map");
  const auto before = tree(tmp);
  const auto with_inputs = [](std::vector<fs::path> inputs) {
    return OutputFolderOptions{.tool = "run", .publish_last = {"report.json"}, .inputs = std::move(inputs)};
  };
  for (const fs::path& out : {data, tmp / "alias", data / "rgb" / "..", tmp}) {
    try {
      OutputFolder folder(out, with_inputs({data}));
      ADD_FAILURE() << out << " accepted as the output of input " << data;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(data.string()), std::string::npos) << e.what();
    }
  }
  // A file input (a bag, a map) inside DIR counts too.
  EXPECT_THROW(OutputFolder(tmp, with_inputs({tmp / "map.semap"})), Error);
  EXPECT_EQ(tree(tmp), before);
  // Beside the input, or inside it: accepted.
  EXPECT_NO_THROW(OutputFolder(tmp / "beside", with_inputs({data})));
  EXPECT_NO_THROW(OutputFolder(data / "outputs", with_inputs({data})));
}

}  // namespace
}  // namespace semap
