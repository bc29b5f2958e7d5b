#pragma once
// Row-parallel loops of tracking. cv::parallel_for_ by default; serial on a thread where a
// SerialScope is active (TrackingConfig::parallel = false): with two cores shared by reading,
// tracking and TSDF integration, serial tracking costs less CPU per frame than TBB fan-out.
#include <opencv2/core.hpp>

namespace semap::tracking_detail {

inline thread_local bool serial_on_this_thread = false;

class SerialScope {
 public:
  explicit SerialScope(bool serial) : previous_(serial_on_this_thread) { serial_on_this_thread = serial; }
  ~SerialScope() { serial_on_this_thread = previous_; }
  SerialScope(const SerialScope&) = delete;
  SerialScope& operator=(const SerialScope&) = delete;

 private:
  bool previous_;
};

template <class Body>
void parallel_rows(const cv::Range& range, const Body& body) {
  if (serial_on_this_thread) body(range);
  else cv::parallel_for_(range, body);
}

}  // namespace semap::tracking_detail
