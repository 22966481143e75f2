// Shapes: every shape's C++ class is bound here (the base class Shape, with
// calc_dist and is_inside, is bound in bind_interactions.cpp). Keyword names
// are ESPResSo 4.2's; the Python wrappers in lbmd/shapes.py validate first.
#include "bindings.hpp"

#include "shapes/cylinder.hpp"
#include "shapes/extrusion.hpp"
#include "shapes/rhomboid.hpp"
#include "shapes/simple_pore.hpp"
#include "shapes/sphere.hpp"
#include "shapes/union.hpp"
#include "shapes/wall.hpp"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

namespace py = pybind11;

namespace pyoif::python {

void bind_shapes(py::module_& m) {
  using namespace shapes;
  py::class_<Wall, Shape, std::shared_ptr<Wall>>(m, "Wall").def(py::init<const Vec3&, double>(),
                                                                py::arg("normal"), py::arg("dist"));

  py::class_<Sphere, Shape, std::shared_ptr<Sphere>>(m, "Sphere")
      .def(py::init<const Vec3&, double, int>(), py::arg("center"), py::arg("radius"),
           py::arg("direction") = 1);

  py::class_<Cylinder, Shape, std::shared_ptr<Cylinder>>(m, "Cylinder")
      .def(py::init<const Vec3&, const Vec3&, double, double, int, bool>(), py::arg("center"),
           py::arg("axis"), py::arg("radius"), py::arg("length"), py::arg("direction") = 1,
           py::arg("open") = false);

  py::class_<Rhomboid, Shape, std::shared_ptr<Rhomboid>>(m, "Rhomboid")
      .def(py::init<const Vec3&, const Vec3&, const Vec3&, const Vec3&, int>(), py::arg("corner"),
           py::arg("a"), py::arg("b"), py::arg("c"), py::arg("direction") = 1);

  py::class_<SimplePore, Shape, std::shared_ptr<SimplePore>>(m, "SimplePore")
      .def(py::init<const Vec3&, const Vec3&, double, double, double>(), py::arg("center"),
           py::arg("axis"), py::arg("length"), py::arg("radius"), py::arg("smoothing_radius"));

  py::class_<Extrusion, Shape, std::shared_ptr<Extrusion>>(m, "Extrusion")
      .def(py::init<const std::vector<Extrusion::Polygon>&, double, double, int,
                    const std::vector<std::string>&>(),
           py::arg("polygons"), py::arg("z0"), py::arg("z1"), py::arg("direction") = 1,
           py::arg("names") = std::vector<std::string>{})
      .def("num_edges", &Extrusion::num_edges)
      // distances and normals of an (n, 3) array of points in one call (tests, timings)
      .def(
          "calc_dists",
          [](const Extrusion& shape,
             const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>&
                 pos) {
            Eigen::VectorXd dist(pos.rows());
            Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> normal(pos.rows(), 3);
            {
              py::gil_scoped_release release;
              for (Eigen::Index i = 0; i < pos.rows(); ++i) {
                Vec3 n;
                shape.calc_dist(pos.row(i).transpose(), dist[i], n);
                normal.row(i) = n.transpose();
              }
            }
            return py::make_tuple(dist, normal);
          },
          py::arg("pos"));

  py::class_<Union, Shape, std::shared_ptr<Union>>(m, "Union")
      .def(py::init<>())
      .def("add", &Union::add, py::arg("shape"))
      .def("remove", &Union::remove, py::arg("shape"))
      .def("clear", &Union::clear)
      .def("size", &Union::size);
}

} // namespace pyoif::python
