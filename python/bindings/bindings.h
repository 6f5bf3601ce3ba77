#pragma once

#include <pybind11/pybind11.h>

// One Bind* per binding file, each adding its part of the API to the module.
namespace noctua::python {

void BindFeatures(pybind11::module_& m);
void BindEdges(pybind11::module_& m);
void BindDynamic(pybind11::module_& m);
void BindSim(pybind11::module_& m);
void BindSlam(pybind11::module_& m);
void BindEval(pybind11::module_& m);
void BindFrames(pybind11::module_& m);

}  // namespace noctua::python
