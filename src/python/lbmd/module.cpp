// The _lbmd extension module: exception translation and the binders.
#include "bindings.hpp"

#include "utils/errors.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_lbmd, m) {
  m.doc() = "PyOIF engine core (C++); use the lbmd package, not this module";
  static py::exception<pyoif::SimulationInstability> instability(m, "SimulationInstability",
                                                                 PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p)
        std::rethrow_exception(p);
    } catch (const pyoif::InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const pyoif::SimulationInstability& e) {
      PyErr_SetString(instability.ptr(), e.what());
    }
  });
  pyoif::python::bind_system(m);
  pyoif::python::bind_interactions(m);
  pyoif::python::bind_shapes(m);
  pyoif::python::bind_lb(m);
  pyoif::python::bind_oif(m);
}
