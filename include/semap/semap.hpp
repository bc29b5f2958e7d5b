#pragma once
// semap: RGB-D frames -> camera trajectory, dense semantic TSDF mesh and object map.
// The one header an application includes (link semap::semap):
//
//   #include <semap/semap.hpp>
//   auto dataset = semap::open_dataset("rgbd_dataset_freiburg1_desk");
//   semap::Mapper mapper(semap::SemapConfig{}, dataset->camera());
//   for (size_t i = 0; i < dataset->size(); ++i) mapper.add_frame(dataset->load(i));
//   mapper.finish();
//   semap::write_map_outputs(mapper, "out");
#include "semap/core/camera.hpp"
#include "semap/core/error.hpp"
#include "semap/core/frame.hpp"
#include "semap/core/gravity.hpp"
#include "semap/core/labels.hpp"
#include "semap/core/point_cloud.hpp"
#include "semap/core/pose.hpp"
#include "semap/eval/consistency_metrics.hpp"
#include "semap/eval/trajectory_metrics.hpp"
#include "semap/io/config_loader.hpp"
#include "semap/io/dataset.hpp"
#include "semap/io/frame_source.hpp"
#include "semap/io/ply_io.hpp"
#include "semap/io/trajectory_io.hpp"
#include "semap/mapper.hpp"
#include "semap/pipeline/evaluation.hpp"
#include "semap/pipeline/outputs.hpp"
#include "semap/pipeline/run_pipeline.hpp"
#include "semap/pipeline/semap_config.hpp"
#include "semap/segmentation/segmenter_factory.hpp"
