// noctua.edges: the edge maps of edges::EdgeDetector.
#include <pybind11/stl.h>

#include "bindings.h"
#include "convert.h"
#include "noctua/edges/edge_detector.h"

namespace noctua::python {

void BindEdges(py::module_& m) {
  m.def("edge_methods", [] {
    std::vector<std::string> names;
    for (const auto method : edges::AllEdgeMethods()) names.push_back(edges::ToString(method));
    return names;
  });
  m.def(
      "edges",
      [](const py::object& image, const std::string& method) {
        const cv::Mat input = ImageArgument(image, "image");
        edges::EdgeDetectorOptions options;
        options.method = edges::ParseEdgeMethod(method);
        cv::Mat map;
        {
          py::gil_scoped_release release;
          map = edges::CreateEdgeDetector(options)->Detect(input);
        }
        return ArrayFromMat(map);
      },
      py::arg("image"), py::arg("method") = "pc-fast",
      "uint8 edge map (255 on edges) of a uint8 BGR/grey image; method: one of edge_methods() "
      "(pc: phasecong3, pc-fast: the paper method's real-time variant, canny, sobel, prewitt, "
      "roberts).");
}

}  // namespace noctua::python
