// The _lbmd extension module: exception translation and the binders.
#include "bindings.hpp"

#include "utils/errors.hpp"

#include <cmath>

namespace py = pybind11;

PYBIND11_MODULE(_lbmd, m) {
  m.doc() = "PyOIF engine core (C++); use the lbmd package, not this module";
  static py::exception<pyoif::SimulationInstability> instability(m, "SimulationInstability",
                                                                 PyExc_RuntimeError);
  // what a program reads instead of parsing the message (see errors.hpp);
  // class attributes are the defaults of an instability raised from Python
  instability.doc() =
      "The simulation became unphysical. Attributes: cause (a short name, see doc/engine.md), "
      "step and time (MD), particle and cell (ids, None where not one), node (lattice node "
      "(x, y, z) or None), value (the offending number or None).";
  for (const char* name : {"cause", "step", "time", "particle", "cell", "node", "value"})
    instability.attr(name) = py::none();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p)
        std::rethrow_exception(p);
    } catch (const pyoif::InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const pyoif::SimulationInstability& e) {
      auto id_or_none = [](long long id) -> py::object {
        return id >= 0 ? py::object(py::int_(id)) : py::none();
      };
      auto number_or_none = [](double x) -> py::object {
        return std::isnan(x) ? py::none() : py::object(py::float_(x));
      };
      py::object error = py::reinterpret_borrow<py::object>(instability.ptr())(e.what());
      error.attr("cause") = e.cause;
      error.attr("step") = id_or_none(e.step);
      error.attr("time") = number_or_none(e.time);
      error.attr("particle") = id_or_none(e.particle);
      error.attr("cell") = id_or_none(e.cell);
      error.attr("node") =
          e.node[0] >= 0 ? py::object(py::make_tuple(e.node[0], e.node[1], e.node[2])) : py::none();
      error.attr("value") = number_or_none(e.value);
      PyErr_SetObject(instability.ptr(), error.ptr());
    }
  });
  pyoif::python::bind_system(m);
  pyoif::python::bind_interactions(m);
  pyoif::python::bind_shapes(m);
  pyoif::python::bind_lb(m);
  pyoif::python::bind_oif(m);
  pyoif::python::bind_checkpoint(m);
  pyoif::python::bind_packing(m);
}
