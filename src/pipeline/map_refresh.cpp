#include "pipeline/map_refresh.hpp"

#include <tbb/parallel_pipeline.h>

namespace semap {

SemanticTsdf rebuild_tsdf(SemanticTsdf tsdf, size_t frame_count, int threads,
                          const std::function<std::optional<IntegrationInput>(size_t)>& input_of) {
  size_t next = 0;
  tbb::parallel_pipeline(
      static_cast<size_t>(2 * std::max(threads, 1)),
      tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                     [&](tbb::flow_control& fc) -> size_t {
                                       if (next >= frame_count) fc.stop();
                                       return next++;
                                     }) &
          tbb::make_filter<size_t, std::optional<IntegrationInput>>(tbb::filter_mode::parallel, input_of) &
          tbb::make_filter<std::optional<IntegrationInput>, void>(
              tbb::filter_mode::serial_in_order, [&](const std::optional<IntegrationInput>& input) {
                if (input) tsdf.integrate(*input);
              }));
  return tsdf;
}

double surface_displacement_m(const Pose& before, const Pose& after, double range_m) {
  const Pose correction = after * before.inverse();
  return (after.translation() - before.translation()).norm() +
         Eigen::AngleAxisd(correction.linear()).angle() * range_m;
}

}  // namespace semap
