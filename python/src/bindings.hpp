#pragma once
// The parts of the _semap extension module (module.cpp calls them in this order).
#include <pybind11/pybind11.h>

namespace semap::python {

void bind_types(pybind11::module_& m);    ///< Camera, FrameResult, Mesh, Object (bind_types.cpp)
void bind_mapper(pybind11::module_& m);   ///< Mapper (bind_mapper.cpp)
void bind_dataset(pybind11::module_& m);  ///< open_dataset, Dataset, DatasetFrame (bind_dataset.cpp)

}  // namespace semap::python
