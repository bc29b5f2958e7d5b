#pragma once
// A stream of RGB-D frames: a dataset read in order, or a camera / recording that has no
// random access (OpenNI2). The mapping loop pulls frames with next() until it returns nullopt.
#include <memory>
#include <optional>
#include <string>

#include "semap/core/camera.hpp"
#include "semap/core/frame.hpp"
#include "semap/io/dataset.hpp"

namespace semap {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// The next frame (Frame::index counts from 0); nullopt at the end of the sequence or after
  /// request_stop(). A live source blocks until the camera delivers one. Throws semap::Error for
  /// an unreadable frame; the source has then moved past it (the next call returns the next one).
  virtual std::optional<Frame> next() = 0;
  virtual const CameraModel& camera() const = 0;
  /// True for a camera: frames come in real time, and older ones are dropped when next() is
  /// not called fast enough (dropped_frames() counts them).
  virtual bool is_live() const = 0;
  /// Makes next() return nullopt soon; callable from any thread (e.g. a SIGINT watcher).
  virtual void request_stop() = 0;
  /// The dataset path or the device spec, for messages.
  virtual std::string name() const = 0;
  /// Frames in the sequence when known in advance (dataset, recording), else 0.
  virtual size_t size_hint() const { return 0; }
  /// Frames a live source dropped because the consumer was slower than the camera.
  virtual size_t dropped_frames() const { return 0; }
  /// The random-access dataset behind the source (ground truth, re-reading frames for the final
  /// map refresh), or nullptr for cameras and recordings.
  virtual const DatasetReader* dataset() const { return nullptr; }
};

/// Any DatasetReader as a FrameSource: frames 0..size()-1 in order.
std::unique_ptr<FrameSource> make_dataset_source(std::unique_ptr<DatasetReader> reader);

/// "openni2:" (the first OpenNI2 device), "openni2:URI" (a device by URI, e.g. from
/// `lsusb`-style OpenNI2 URIs), "openni2:FILE.oni" (a recording); anything else is opened with
/// open_dataset(). Throws semap::Error naming the device when none is found (within seconds).
std::unique_ptr<FrameSource> open_frame_source(const std::string& spec, const DatasetOptions& options = {});

/// True for the "openni2:" specs above.
bool is_openni2_spec(const std::string& spec);
/// False when semap was built without OpenNI2 (PCL's io module); openni2: specs then fail saying so.
bool have_openni2_support();

}  // namespace semap
