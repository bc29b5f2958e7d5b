#pragma once
// semap.Mapper(config=...): None (the defaults), a nested dict with the YAML's keys, or the
// path of a YAML file. Every form goes through the one config loader (io/config_loader), so an
// unknown key or a bad value is the CLI's error (raised as semap.Error, a ValueError).
// The defaults are the CLI's (tsdf.colour_layer on, mesh_colour rgb: mesh.colors are the
// surfaces' colours).
#include <pybind11/pybind11.h>

#include "semap/pipeline/semap_config.hpp"

namespace semap::python {

SemapConfig config_from_python(const pybind11::handle& config);

}  // namespace semap::python
