#pragma once
// Output folders that are consistent as a whole (issue 22). A command writes everything into a
// fresh staging folder inside its output folder and publishes it at the end:
//
//   OutputFolder out(dir, {.tool = "run", .publish_last = {"report.json"}});
//   write_ply(out.staging() / "mesh.ply", mesh);          // any writer, any sub-folder
//   write_file_atomic(out.path("objects/3.ply"), bytes);  // path() creates objects/ in staging
//   out.publish();                                        // everything appears at once
//   // no publish() (an exception, Ctrl-C): the destructor removes the staging folder
//
// What it guarantees:
//  - staging: DIR/.semap-staging-PID-RANDOM, created with mkdir (exclusive: never an existing
//    folder or a planted symlink), holding a marker file of its own; staging folders of dead
//    processes are removed by the next OutputFolder on DIR;
//  - publish(): files are renamed into place one by one (each rename atomic); the sub-folders
//    on the way are opened with O_NOFOLLOW, so a symlink planted in DIR (DIR/viewer -> /etc)
//    is refused, never written through. A manifest DIR/.semap-manifest-TOOL.json lists exactly
//    the files of the last complete run; files listed in the previous manifest that this run
//    did not write (stale objects/<id>.ply) are removed. While publishing, the old manifest and
//    the old `publish_last` files are removed first and the new ones written last, so a publish
//    cut short (power loss) leaves a folder that does not look complete, and a journal
//    (.semap-manifest-TOOL.pending.json) lets the next run finish the clean-up;
//  - nothing that semap cannot prove it wrote is ever removed: only paths listed in its own
//    manifests, only regular files, never through a symlink. DIR itself is removed only when
//    this object created it and nothing was published;
//  - a folder created by semap carries the marker DIR/.semap-output; with
//    `refuse_foreign_non_empty` (semap synth) a non-empty folder without it is refused;
//  - one OutputFolder per DIR at a time (flock): a second concurrent command fails clearly;
//  - (issue 44) publish() never replaces a file semap did not write: a file already at an
//    output's place that this tool's manifest (or journal) does not list - a user's mesh.ply,
//    a recording's report.json - stops the publish before anything is moved, naming the file;
//  - (issue 44) DIR may not be, nor contain, one of the command's inputs (`inputs`: dataset,
//    recording, bag, a map to resume or merge): refused before anything is created.
//
// Interruption: InterruptGuard (below) turns the first SIGINT/SIGTERM into a flag the command
// polls (throw_if_interrupted) so it unwinds and publishes nothing; a second signal unlinks the
// live temporary files (core/paths) and ends the process. Signals are blocked during publish().
#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

namespace semap {

struct OutputFolderOptions {
  /// The command ("run", "synth", "segment", "view"): names the manifest, so commands sharing
  /// a folder (run writes DIR, view writes DIR/viewer/) never remove each other's files.
  std::string tool = "run";
  /// Refuse a non-empty DIR without semap's marker (semap synth: a dataset folder is its own).
  bool refuse_foreign_non_empty = false;
  /// Remove the files of the previous manifest that this run did not write. False: keep them
  /// and list them in the new manifest too (semap segment: outputs accumulate over calls).
  bool remove_stale = true;
  /// Relative paths published last, in this order: the files that say "complete" (report.json,
  /// dataset.yaml). The previous run's copies are removed before anything else is published.
  std::vector<std::string> publish_last;
  /// What the command reads (dataset folders or files, maps). DIR may not be one of them nor
  /// contain one (see refuse_output_over_inputs). Empty: nothing to check.
  std::vector<std::filesystem::path> inputs;
  /// Relative paths the command will publish, as far as known before its work: one that DIR
  /// already holds and this tool's manifest does not list (a user's mesh.ply) is refused when
  /// the folder is opened, not after the work (publish refuses any other such file too).
  std::vector<std::string> planned;
};

/// Throws semap::Error naming `out_dir` when it is one of `inputs` or contains one, symlinks
/// and ".." resolved (the same folder by another path is the same folder). Thread-safe.
void refuse_output_over_inputs(const std::filesystem::path& out_dir, const std::vector<std::filesystem::path>& inputs);

class OutputFolder {
 public:
  /// Opens (creating it and its parents when absent) `dir` and a fresh staging folder in it.
  /// Throws semap::Error naming `dir` when it is not a folder, not writable, in use by another
  /// semap process, or foreign and non-empty under refuse_foreign_non_empty.
  explicit OutputFolder(std::filesystem::path dir, OutputFolderOptions options = {});
  /// Calls abandon() unless publish() succeeded.
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  /// The final folder, as given.
  const std::filesystem::path& dir() const { return dir_; }
  /// Where the command writes: pass it as the output folder of every writer.
  const std::filesystem::path& staging() const { return staging_; }
  /// staging() / relative, creating the sub-folders of `relative` inside staging. `relative`
  /// must stay inside (no "..", not absolute): throws otherwise.
  std::filesystem::path path(const std::filesystem::path& relative) const;

  /// Moves every regular file of staging() into dir() (see the header comment), writes the
  /// manifest, removes stale files and the staging folder. Returns the published relative
  /// paths (sorted, publish_last at the end). Throws semap::Error naming the file on failure;
  /// the folder is then left without a manifest (it does not claim a complete run).
  std::vector<std::string> publish();
  /// Removes the staging folder (and dir() when created here and never published). No-throw.
  void abandon() noexcept;

  /// The published relative paths listed by DIR/.semap-manifest-TOOL.json (empty when absent
  /// or unreadable): what the last complete run of `tool` wrote.
  static std::vector<std::string> read_manifest(const std::filesystem::path& dir, const std::string& tool);
  /// File names of the mechanism in DIR (marker, manifests, staging, temp files): viewers and
  /// listings skip them.
  static bool is_internal_name(const std::string& filename);

 private:
  std::filesystem::path dir_, staging_;
  OutputFolderOptions options_;
  int dir_fd_ = -1;
  bool created_dir_ = false, wrote_marker_ = false, done_ = false;
};

/// SIGINT/SIGTERM handling for one command (RAII; nests). The first signal sets a flag and
/// prints one line ("stopping; Ctrl-C again quits at once"); a second one unlinks registered
/// temporary files and ends the process with the default action.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
};

/// The signal number of the first SIGINT/SIGTERM received under an InterruptGuard, else 0.
int interrupt_signal();
/// Throws semap::Interrupted when a signal was received: call it between frames / files.
void throw_if_interrupted();

}  // namespace semap
