// Shapes: every shape's C++ class is bound here.
#include "bindings.hpp"

#include "shapes/wall.hpp"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

namespace py = pybind11;

namespace pyoif::python {

void bind_shapes(py::module_& m) {
  using namespace shapes;
  py::class_<Wall, Shape, std::shared_ptr<Wall>>(m, "Wall")
      .def(py::init<const Vec3&, double>(), py::arg("normal"), py::arg("dist"));
}

}  // namespace pyoif::python
