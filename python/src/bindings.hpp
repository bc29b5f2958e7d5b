#pragma once
// The parts of the _semap extension module (module.cpp calls them in this order).
#include <nlohmann/json.hpp>
#include <pybind11/pybind11.h>

namespace semap::python {

void bind_types(pybind11::module_& m);    ///< Camera, FrameResult, Mesh, Object (bind_types.cpp)
void bind_mapper(pybind11::module_& m);   ///< Mapper (bind_mapper.cpp)
void bind_dataset(pybind11::module_& m);  ///< open_dataset, Dataset, DatasetFrame (bind_dataset.cpp)

/// A JSON document as Python dicts/lists (through the json module; call with the GIL held).
pybind11::object json_to_python(const nlohmann::json& j);

}  // namespace semap::python
