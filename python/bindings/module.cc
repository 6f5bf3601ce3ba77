// The compiled part of the Python package noctua (python/noctua/__init__.py re-exports it).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "noctua/util/error.h"
#include "noctua/util/install_dirs.h"
#include "noctua/util/version.h"

PYBIND11_MODULE(_noctua, m) {
  m.doc() = "noctua: feature points for visual SLAM in low light and dynamic scenes";
  m.attr("__version__") = noctua::Version();
  // noctua::Error carries a message written for the user (file, line, what is wrong): Python
  // sees it unchanged, as noctua.Error (a RuntimeError).
  pybind11::register_exception<noctua::Error>(m, "Error", PyExc_RuntimeError);
  m.def(
      "config_dir",
      [](std::vector<std::filesystem::path> candidates) {
        // Last, for a build: the source tree the module was built from.
        candidates.emplace_back(NOCTUA_SOURCE_DIR "/config");
        return noctua::FindConfigDir(candidates).string();
      },
      pybind11::arg("candidates"));
  noctua::python::BindFeatures(m);
  noctua::python::BindEdges(m);
  noctua::python::BindDynamic(m);
  noctua::python::BindSim(m);
  noctua::python::BindSlam(m);
  noctua::python::BindEval(m);
  noctua::python::BindFrames(m);
}
