#pragma once
// `semap run` as a library call: the dataset loop around a semap::Mapper. It reads the
// dataset on its own thread, feeds the Mapper, shows progress, writes the outputs, evaluates
// against ground truth when there is some, and writes the report.
#include <array>
#include <functional>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "semap/core/params.hpp"
#include "semap/io/frame_source.hpp"
#include "semap/pipeline/evaluation.hpp"
#include "semap/mapper.hpp"
#include "semap/pipeline/semap_config.hpp"

namespace semap {

enum class PoseSource {
  track,        ///< semap tracks the camera (METHODS A1-A4)
  groundtruth,  ///< the dataset's ground-truth poses (frames without one are skipped)
  given,        ///< the library caller's own poses (FrameHints); what report.json says for such a
                ///< Mapper (write_map_outputs, Python mapper.save), not a `semap run` choice
};
/// Every source, as report.json's summary.poses names it.
inline constexpr EnumNames<PoseSource, 3> kPoseSourceNames{
    {{PoseSource::track, "track"}, {PoseSource::groundtruth, "groundtruth"}, {PoseSource::given, "given"}}};
/// The sources `semap run --poses` takes (RunOptions::poses).
inline constexpr EnumNames<PoseSource, 2> kRunPoseSourceNames{
    {{PoseSource::track, "track"}, {PoseSource::groundtruth, "groundtruth"}}};

struct RunOptions {
  /// A dataset folder or file (any layout open_dataset() reads), or a camera spec
  /// ("openni2:", "openni2:URI", "openni2:FILE.oni").
  std::filesystem::path dataset;
  DatasetOptions dataset_options;  ///< e.g. the ROS bag topics
  std::filesystem::path out_dir;
  PoseSource poses = PoseSource::track;  ///< track or groundtruth (kRunPoseSourceNames)
  /// yolo:PATH | semantic:PATH | panoptic:SEM+INST | groundtruth | precomputed:DIR | none |
  /// default; empty: the config's segmentation.segmenter, whose default is "default": the
  /// default models (find_default_segmenter) when found, else none (geometry and colour only).
  std::string segmenter;
  /// Where the default models are (`--models DIR`); empty: looked up (model_search_path). Only
  /// read when the segmenter is "default"; a folder given here must hold a default model.
  std::filesystem::path models_dir;
  double seg_noise = 0.0;  ///< > 0: built-in noisy segmentation of ground-truth labels (flicker rate)
  size_t max_frames = 0;   ///< 0 = all
  bool evaluate = true;    ///< evaluation figures when ground truth exists
  bool show_progress = true;
  /// Feed the frames at the pace they were recorded (their timestamps), as the sensor delivered
  /// them: e.g. to watch a live view grow or to test online behaviour. Frames are never dropped;
  /// one that arrives late is fed at once.
  bool realtime = false;
  /// False (default): out_dir may not be nor contain the dataset (issue 44). True only for
  /// `semap demo`, which generates its dataset into out_dir/dataset itself.
  bool dataset_inside_out_dir = false;
  /// Polled between frames: when it returns true (e.g. after SIGINT), reading stops; the frames
  /// so far are mapped to the end (pose graph, refresh) and every output is written.
  std::function<bool()> stop_requested;
  /// Called with the run's Mapper once it exists and with nullptr before it is destroyed (also
  /// when the run fails): e.g. a live view reading its thread-safe accessors meanwhile.
  std::function<void(const Mapper*)> observe_mapper;
  /// Continue a saved map (issue 19): an output folder of an earlier run, or its map.semap. The
  /// recording is relocalised into it and extends it (Mapper::load); the folder is only read.
  std::filesystem::path resume_from;
};

/// What a run produced: the report.json document, typed.
struct RunResult {
  std::string dataset;
  PoseSource poses = PoseSource::track;
  MapperStats mapper;
  size_t frames_read = 0;     ///< frames handed to the Mapper
  size_t frames_skipped = 0;  ///< unreadable frames, or without a valid ground-truth pose
  size_t mesh_vertices = 0, mesh_triangles = 0;
  std::map<std::string, int> objects_per_class;
  double fps_online = 0.0;      ///< frames / time of the streaming stages
  double fps_end_to_end = 0.0;  ///< frames / whole run (final pass, refresh, outputs included)
  double wall_s = 0.0;
  double cpu_s_online = 0.0;    ///< process CPU seconds (all threads) until the streaming stages ended
  double cpu_s_online_opencv_workers = 0.0;  ///< of which OpenCV's worker threads (cv::parallel_for_)
  double peak_rss_mb = 0.0;
  int threads = 1;
  bool stopped_early = false;  ///< stop_requested() ended the input before its end
  /// false: written by write_map_outputs from a library Mapper (Python mapper.save), with no
  /// driver timing the run: wall_s, fps_* and cpu_s_* are null in report.json (issue 43).
  bool driver_measured = true;
  /// --resume given, but no frame relocalised into the saved map: the recording was mapped on
  /// its own (issue 19: never merged at a guessed pose).
  bool not_merged = false;
  /// The folder the default models came from (the segmenter "default" found them; the models
  /// themselves are named in mapper.segmenter); empty otherwise.
  std::filesystem::path default_models_dir;
  Evaluation evaluation;
  std::map<std::string, TimingSummary> timings;
  std::vector<FrameResult> frames;  ///< Mapper::frame_results(): report.json "frames" (issue 43)
  /// Mapper::stage_samples(): report.json "frames"/"stage_ms", each stage's time per frame.
  std::map<std::string, std::vector<StageSample>> stage_samples;
};
nlohmann::json to_json(const RunResult& result);

/// Runs the whole pipeline and writes every output into options.out_dir, which is consistent as
/// a whole (io/output_folder: written into a staging folder, published at the end; stale files
/// of an earlier run removed; a failed run leaves the folder as it was). Returns the result
/// (also written as report.json). Throws semap::Error on bad input.
RunResult run_pipeline(const RunOptions& options, const SemapConfig& config);

// ---- default segmentation models (issue 38) ----

/// File names of the default models: the ADE20K semantic model and, in order of preference,
/// the COCO instance models (see README "Default models").
inline constexpr const char* kDefaultSemanticModel = "deeplabv3-mnv2-ade20k32-512.onnx";
inline constexpr std::array<const char*, 2> kDefaultInstanceModels{"yolov8n-seg-320.onnx", "yolo11n-seg-640.onnx"};

/// The folders searched for the default models, in this order: `option` (--models DIR) when
/// given, $SEMAP_MODELS_DIR when set, the install prefix's share/semap/models, then the source
/// tree's ../shared/models (a source build).
std::vector<std::filesystem::path> model_search_path(const std::filesystem::path& option);

struct DefaultSegmenter {
  std::string spec;           ///< empty: no folder holds a default model
  std::filesystem::path dir;  ///< the folder the models are in
};
/// The first folder of `search_path` that holds a default model gives the spec:
/// panoptic:SEMANTIC+INSTANCE when it has both kinds, else semantic:/yolo: for the one it has.
DefaultSegmenter find_default_segmenter(const std::vector<std::filesystem::path>& search_path);

/// The spec a run uses: options.segmenter, else the config's segmentation.segmenter, with
/// "default" resolved through find_default_segmenter(model_search_path(options.models_dir))
/// ("none" when nothing is found; `default_models_dir` gets the folder when something is).
/// Throws semap::Error naming options.models_dir when it is given and holds no default model.
std::string run_segmenter_spec(const RunOptions& options, const SemapConfig& config,
                               std::filesystem::path* default_models_dir = nullptr);

/// The segmenter a run uses (nullptr: none): run_segmenter_spec(), or the built-in noisy one
/// for seg_noise > 0. Throws semap::Error for a spec the input cannot serve (ground-truth
/// labels on a dataset without label images, or a camera).
std::unique_ptr<Segmenter> make_run_segmenter(const RunOptions& options, const SemapConfig& config,
                                              const FrameSource& source);

}  // namespace semap
