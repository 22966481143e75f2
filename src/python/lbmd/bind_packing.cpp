// The rigid packer of oif.pack_cells (packing/rigid_packer.hpp): cell types
// as arrays, boundaries as the shapes' C++ objects, the bodies in and out as
// arrays; the packing itself runs without the GIL.
#include "bindings.hpp"

#include "packing/mesh_check.hpp"
#include "packing/rigid_packer.hpp"
#include "utils/errors.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

namespace py = pybind11;

namespace pyoif::python {

namespace {

using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<int, py::array::c_style | py::array::forcecast>;

std::vector<Vec3> rows3(const RealArray& a, const char* name) {
  require(a.ndim() == 2 && a.shape(1) == 3, std::string("pack_cells: ") + name + " must be (n, 3)");
  std::vector<Vec3> out(a.shape(0));
  auto v = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    out[i] = Vec3(v(i, 0), v(i, 1), v(i, 2));
  return out;
}

packing::PackerSettings settings_from(const py::dict& d) {
  packing::PackerSettings s;
  auto vec = [](const py::handle& h) {
    auto v = h.cast<std::vector<double>>();
    require(v.size() == 3, "pack_cells: a box or region corner needs 3 numbers");
    return Vec3(v[0], v[1], v[2]);
  };
  for (auto item : d) {
    const auto key = item.first.cast<std::string>();
    const py::handle v = item.second;
    if (key == "box")
      s.box = vec(v);
    else if (key == "periodic") {
      auto p = v.cast<std::vector<bool>>();
      require(p.size() == 3, "pack_cells: periodic needs 3 flags");
      s.periodic = {p[0], p[1], p[2]};
    } else if (key == "clearance")
      s.clearance = v.cast<double>();
    else if (key == "wall_clearance")
      s.wall_clearance = v.cast<double>();
    else if (key == "region") {
      auto corners = v.cast<std::vector<py::object>>();
      require(corners.size() == 2, "pack_cells: region needs two corners");
      s.region_lo = vec(corners[0]);
      s.region_hi = vec(corners[1]);
      s.has_region = true;
    } else if (key == "start_scale")
      s.start_scale = v.cast<double>();
    else if (key == "final_scale")
      s.final_scale = v.cast<double>();
    else if (key == "growth")
      s.growth = v.cast<double>();
    else if (key == "grow_tolerance")
      s.grow_tolerance = v.cast<double>();
    else if (key == "final_tolerance")
      s.final_tolerance = v.cast<double>();
    else if (key == "seed")
      s.seed = v.cast<std::uint64_t>();
    else if (key == "momentum")
      s.momentum = v.cast<double>();
    else if (key == "step")
      s.step = v.cast<double>();
    else if (key == "max_iterations")
      s.max_iterations = v.cast<int>();
    else if (key == "stall_iterations")
      s.stall_iterations = v.cast<int>();
    else if (key == "stall_overlap_drop")
      s.stall_overlap_drop = v.cast<double>();
    else
      throw InputError("pack_cells: unknown packer setting '" + key + "'");
  }
  return s;
}

py::dict check_dict(const packing::PackingCheck& c) {
  py::dict out;
  out["nodes_inside_cells"] = c.nodes_inside_cells;
  out["min_node_distance"] = c.min_node_distance;
  out["min_wall_distance"] = c.min_wall_distance;
  out["pairs_tested"] = c.pairs_tested;
  return out;
}

} // namespace

void bind_packing(py::module_& m) {
  // the deformable stage's exact check: cells as they are (mesh_check.hpp)
  m.def(
      "check_meshes",
      [](const RealArray& nodes, const std::vector<std::size_t>& first_node,
         const std::vector<int>& types, const std::vector<IntArray>& triangles,
         const std::vector<std::shared_ptr<const shapes::Shape>>& boundaries,
         const py::dict& settings, double search) {
        packing::MeshSet cells;
        cells.nodes = rows3(nodes, "nodes");
        cells.first_node = first_node;
        cells.type = types;
        for (const auto& t : triangles) {
          require(t.ndim() == 2 && t.shape(1) == 3, "pack_cells: triangles must be (m, 3)");
          auto v = t.unchecked<2>();
          std::vector<std::array<int, 3>> tris(t.shape(0));
          for (py::ssize_t r = 0; r < t.shape(0); ++r)
            tris[r] = {v(r, 0), v(r, 1), v(r, 2)};
          cells.triangles.push_back(std::move(tris));
        }
        const auto s = settings_from(settings);
        packing::PackingCheck c;
        {
          py::gil_scoped_release release;
          c = packing::check_meshes(cells, boundaries, s, search);
        }
        return check_dict(c);
      },
      py::arg("nodes"), py::arg("first_node"), py::arg("types"), py::arg("triangles"),
      py::arg("boundaries"), py::arg("settings"), py::arg("search"));

  using packing::RigidPacker;
  py::class_<RigidPacker>(m, "RigidPacker")
      .def(py::init<>())
      .def(
          "add_type",
          [](RigidPacker& p, const RealArray& nodes, const IntArray& triangles, double spacing) {
            require(triangles.ndim() == 2 && triangles.shape(1) == 3,
                    "pack_cells: triangles must be (m, 3)");
            std::vector<std::array<int, 3>> tris(triangles.shape(0));
            auto t = triangles.unchecked<2>();
            const auto n = static_cast<int>(nodes.shape(0));
            for (py::ssize_t i = 0; i < triangles.shape(0); ++i)
              for (int k = 0; k < 3; ++k) {
                tris[i][k] = t(i, k);
                require(tris[i][k] >= 0 && tris[i][k] < n,
                        "pack_cells: triangle node out of range");
              }
            auto pts = rows3(nodes, "nodes");
            py::gil_scoped_release release;
            return p.add_type(pts, tris, spacing);
          },
          py::arg("nodes"), py::arg("triangles"), py::arg("spacing"))
      .def("add_boundary", &RigidPacker::add_boundary, py::arg("shape"))
      .def(
          "set_bodies",
          [](RigidPacker& p, const IntArray& types, const RealArray& centres,
             const RealArray& quaternions) {
            require(quaternions.ndim() == 2 && quaternions.shape(1) == 4,
                    "pack_cells: quaternions must be (n, 4)");
            std::vector<Eigen::Quaterniond> q(quaternions.shape(0));
            auto v = quaternions.unchecked<2>();
            for (py::ssize_t i = 0; i < quaternions.shape(0); ++i)
              q[i] = Eigen::Quaterniond(v(i, 0), v(i, 1), v(i, 2), v(i, 3));
            std::vector<int> t(types.data(), types.data() + types.size());
            p.set_bodies(t, rows3(centres, "centres"), q);
          },
          py::arg("types"), py::arg("centres"), py::arg("quaternions"))
      .def(
          "run",
          [](RigidPacker& p, const py::dict& settings) {
            const auto s = settings_from(settings);
            packing::PackerResult r;
            {
              py::gil_scoped_release release;
              r = p.run(s);
            }
            py::dict out;
            out["converged"] = r.converged;
            out["jammed"] = r.jammed;
            out["iterations"] = r.iterations;
            out["scale"] = r.scale;
            out["worst_overlap"] = r.worst_overlap;
            out["worst_wall_overlap"] = r.worst_wall_overlap;
            return out;
          },
          py::arg("settings"))
      .def(
          "check",
          [](const RigidPacker& p, const py::dict& settings) {
            const auto s = settings_from(settings);
            packing::PackingCheck c;
            {
              py::gil_scoped_release release;
              c = p.check(s);
            }
            return check_dict(c);
          },
          py::arg("settings"))
      .def("centres",
           [](const RigidPacker& p) {
             py::array_t<double> out({static_cast<py::ssize_t>(p.n_bodies()), py::ssize_t{3}});
             auto v = out.mutable_unchecked<2>();
             for (std::size_t b = 0; b < p.n_bodies(); ++b)
               for (int k = 0; k < 3; ++k)
                 v(b, k) = p.centres()[b][k];
             return out;
           })
      .def("rotations", [](const RigidPacker& p) {
        py::array_t<double> out(
            {static_cast<py::ssize_t>(p.n_bodies()), py::ssize_t{3}, py::ssize_t{3}});
        auto v = out.mutable_unchecked<3>();
        for (std::size_t b = 0; b < p.n_bodies(); ++b) {
          const Eigen::Matrix3d r = p.orientations()[b].toRotationMatrix();
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
              v(b, i, j) = r(i, j);
        }
        return out;
      });
}

} // namespace pyoif::python
