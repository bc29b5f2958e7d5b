#include "semap/io/frame_source.hpp"

#include <atomic>

#include "semap/core/error.hpp"
#include "io/openni2_source.hpp"

namespace semap {

namespace {

constexpr const char* kOpenNI2Prefix = "openni2:";

class DatasetSource : public FrameSource {
 public:
  explicit DatasetSource(std::unique_ptr<DatasetReader> reader) : reader_(std::move(reader)) {}

  std::optional<Frame> next() override {
    if (stop_.load()) return std::nullopt;
    const size_t i = next_++;  // moves past an unreadable frame too
    if (i >= reader_->size()) return std::nullopt;
    return reader_->load(i);
  }
  const CameraModel& camera() const override { return reader_->camera(); }
  bool is_live() const override { return false; }
  void request_stop() override { stop_ = true; }
  std::string name() const override { return reader_->root().string(); }
  size_t size_hint() const override { return reader_->size(); }
  const DatasetReader* dataset() const override { return reader_.get(); }

 private:
  std::unique_ptr<DatasetReader> reader_;
  std::atomic<size_t> next_{0};
  std::atomic<bool> stop_{false};
};

}  // namespace

std::unique_ptr<FrameSource> make_dataset_source(std::unique_ptr<DatasetReader> reader) {
  if (!reader) throw Error("make_dataset_source", "no dataset");
  return std::make_unique<DatasetSource>(std::move(reader));
}

bool is_openni2_spec(const std::string& spec) { return spec.rfind(kOpenNI2Prefix, 0) == 0; }

bool have_openni2_support() { return io_detail::openni2_available(); }

std::unique_ptr<FrameSource> open_frame_source(const std::string& spec, const DatasetOptions& options) {
  if (is_openni2_spec(spec)) return io_detail::open_openni2(spec, spec.substr(std::string(kOpenNI2Prefix).size()));
  return make_dataset_source(open_dataset(spec, options));
}

}  // namespace semap
