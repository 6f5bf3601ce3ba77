// The low-light sensor model of sim/low_light.h, bound thinly: one Python name per C++ name.
#include <pybind11/stl.h>

#include "bindings.h"
#include "convert.h"
#include "noctua/sim/low_light.h"

namespace noctua::python {

void BindSim(py::module_& m) {
  py::class_<sim::SensorModel>(m, "SensorModel",
                               "Gamma, full well and read noise of the simulated camera "
                               "(sim/low_light.h).")
      .def(py::init([](double gamma, double full_well, double read_noise) {
             sim::SensorModel model;
             model.gamma = gamma;
             model.full_well_electrons = full_well;
             model.read_noise_electrons = read_noise;
             model.Check();
             return model;
           }),
           py::arg("gamma") = sim::SensorModel().gamma,
           py::arg("full_well_electrons") = sim::SensorModel().full_well_electrons,
           py::arg("read_noise_electrons") = sim::SensorModel().read_noise_electrons)
      .def_readwrite("gamma", &sim::SensorModel::gamma)
      .def_readwrite("full_well_electrons", &sim::SensorModel::full_well_electrons)
      .def_readwrite("read_noise_electrons", &sim::SensorModel::read_noise_electrons)
      .def_readonly("name", &sim::SensorModel::name)
      .def_readonly("description", &sim::SensorModel::description)
      .def("check", &sim::SensorModel::Check);

  m.def(
      "sensor_models",
      [] {
        std::vector<std::string> names;
        for (const sim::SensorModel& model : sim::SensorModels()) names.push_back(model.name);
        return names;
      },
      "Names of the family of sensor models (sim/sensor_model.h).");
  m.def("sensor_model", &sim::SensorModelByName, py::arg("name"), py::return_value_policy::copy,
        "The named sensor model; noctua.Error for unknown names.");
  m.def(
      "darken",
      [](const py::object& image, double level, const std::string& sensor, std::uint64_t seed) {
        return ArrayFromMat(sim::DarkenToLevel(ImageArgument(image, "image"), level,
                                               sim::SensorModelByName(sensor), seed));
      },
      py::arg("image"), py::arg("level"), py::arg("sensor") = sim::kDefaultSensorModel,
      py::arg("seed") = 1,
      "The image darkened to `level` times its mean grey by the named sensor model (level 0.15 "
      "is the README's 15%), as noctua's demo, tests and `slam --brightness` do.");

  py::class_<sim::LowLightSimulator>(m, "LowLightSimulator",
                                     "One darker exposure: brightness is the factor on the "
                                     "collected light, in (0, 1].")
      .def(py::init<const sim::SensorModel&, double>(), py::arg("model"), py::arg("brightness"))
      .def(
          "apply",
          [](const sim::LowLightSimulator& simulator, const py::object& image, std::uint64_t seed) {
            const cv::Mat input = ImageArgument(image, "image");
            cv::RNG rng(seed);
            return ArrayFromMat(simulator.Apply(input, rng));
          },
          py::arg("image"), py::arg("seed") = 0,
          "The darkened uint8 image; the same seed gives the same noise.")
      .def(
          "expected_output",
          [](const sim::LowLightSimulator& simulator, int value) {
            const auto moments = simulator.ExpectedOutput(value);
            return py::make_tuple(moments.mean, moments.variance);
          },
          py::arg("value"), "(mean, variance) of the 8-bit output for an original value")
      .def_property_readonly("brightness", &sim::LowLightSimulator::brightness)
      .def_property_readonly("model", &sim::LowLightSimulator::model);

  m.def(
      "brightness_for_mean_ratio",
      [](const py::object& reference, double mean_ratio, const sim::SensorModel& model) {
        return sim::BrightnessForMeanRatio(ImageArgument(reference, "reference"), mean_ratio,
                                           model);
      },
      py::arg("reference"), py::arg("mean_ratio"), py::arg("model") = sim::SensorModel(),
      "The light factor whose output has mean_ratio times the reference's mean grey (a level "
      "of 0.15 is the README's 15%).");
}

}  // namespace noctua::python
