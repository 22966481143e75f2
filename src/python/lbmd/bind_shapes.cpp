// Shapes: every shape's C++ class is bound here (the base class Shape, with
// calc_dist and is_inside, is bound in bind_interactions.cpp). Keyword names
// are ESPResSo 4.2's; the Python wrappers in lbmd/shapes.py validate first.
#include "bindings.hpp"

#include "shapes/cylinder.hpp"
#include "shapes/extrusion.hpp"
#include "shapes/rhomboid.hpp"
#include "shapes/simple_pore.hpp"
#include "shapes/sphere.hpp"
#include "shapes/surface_mesh.hpp"
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

  using VertexArray = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  using TriangleArray = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
  py::class_<SurfaceMesh, Shape, std::shared_ptr<SurfaceMesh>>(m, "SurfaceMesh")
      .def(py::init([](const VertexArray& vertices, const TriangleArray& triangles, int direction) {
             std::vector<Vec3> v(vertices.rows());
             for (Eigen::Index i = 0; i < vertices.rows(); ++i)
               v[i] = vertices.row(i).transpose();
             std::vector<SurfaceMesh::Triangle> t(triangles.rows());
             for (Eigen::Index i = 0; i < triangles.rows(); ++i)
               t[i] = {triangles(i, 0), triangles(i, 1), triangles(i, 2)};
             return std::make_shared<SurfaceMesh>(v, t, direction);
           }),
           py::arg("vertices"), py::arg("triangles"), py::arg("direction") = 1)
      .def_property_readonly("inverted", &SurfaceMesh::inverted)
      .def_property_readonly("volume", &SurfaceMesh::volume)
      .def_property_readonly("triangles", [](const SurfaceMesh& s) {
        TriangleArray t(static_cast<Eigen::Index>(s.triangles().size()), 3);
        for (std::size_t i = 0; i < s.triangles().size(); ++i)
          for (int k = 0; k < 3; ++k)
            t(static_cast<Eigen::Index>(i), k) = s.triangles()[i][k];
        return t;
      });
}

} // namespace pyoif::python
