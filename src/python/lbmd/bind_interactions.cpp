// Non-bonded models, bonded interactions and shape-based constraints: every
// interaction's C++ side is bound here, in one place.
#include "bindings.hpp"

#include "system/system.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

namespace py = pybind11;

namespace pyoif::python {

namespace {

/** set_<model>(t1, t2, params) / get_<model>(t1, t2) on System. */
template <class Model> void bind_pair_model(py::class_<System, std::shared_ptr<System>>& sys) {
  const std::string name = Model::name;
  sys.def(("set_" + name).c_str(), [](System& s, int t1, int t2, const typename Model::Params& p) {
    s.nonbonded.at(t1, t2).template get<Model>() = p;
    s.nonbonded.commit(t1, t2);
    s.on_interactions_changed();
  });
  sys.def(("get_" + name).c_str(), [](System& s, int t1, int t2) {
    return s.nonbonded.at(t1, t2).template get<Model>();
  });
}

using IdArray = py::array_t<int, py::array::c_style | py::array::forcecast>;
using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

}  // namespace

void bind_interactions(py::module_& m) {
  auto sys = py::reinterpret_borrow<py::class_<System, std::shared_ptr<System>>>(m.attr("System"));

  // ---- non-bonded models ----------------------------------------------------
  py::class_<SoftSphere::Params>(m, "SoftSphereParams")
      .def(py::init([](double a, double n, double cutoff, double offset) {
             return SoftSphere::Params{a, n, cutoff, offset};
           }),
           py::arg("a"), py::arg("n"), py::arg("cutoff"), py::arg("offset"))
      .def_readonly("a", &SoftSphere::Params::a)
      .def_readonly("n", &SoftSphere::Params::n)
      .def_readonly("cutoff", &SoftSphere::Params::cutoff)
      .def_readonly("offset", &SoftSphere::Params::offset);
  bind_pair_model<SoftSphere>(sys);

  // ---- bonded interactions --------------------------------------------------
  py::class_<HarmonicBond>(m, "HarmonicBond")
      .def(py::init([](double k, double r_0, double r_cut) { return HarmonicBond{k, r_0, r_cut}; }),
           py::arg("k"), py::arg("r_0"), py::arg("r_cut"))
      .def_readonly("k", &HarmonicBond::k)
      .def_readonly("r_0", &HarmonicBond::r_0)
      .def_readonly("r_cut", &HarmonicBond::r_cut);

  sys.def("add_bonded_interaction", &System::add_bonded_interaction)
      .def("n_bonded_interactions", [](const System& s) { return s.bonded.size(); })
      .def("add_bonds",
           [](System& s, int bond_id, const IdArray& ids, const RealArray& per_bond) {
             std::vector<int> i(ids.data(), ids.data() + ids.size());
             std::vector<double> r(per_bond.data(), per_bond.data() + per_bond.size());
             s.add_bonds(bond_id, i, r);
           })
      .def("get_bonds",
           [](const System& s, int bond_id) {
             const BondGroup& g = s.bonded.at(bond_id).bonds;
             IdArray out({static_cast<py::ssize_t>(g.size()), static_cast<py::ssize_t>(g.n_particles)});
             std::copy(g.ids.begin(), g.ids.end(), out.mutable_data());
             return out;
           })
      .def("remove_bond",
           [](System& s, int bond_id, const std::vector<int>& ids) {
             BondGroup& g = s.bonded.at(bond_id).bonds;
             for (std::size_t b = 0; b < g.size(); ++b)
               if (std::equal(ids.begin(), ids.end(), g.bond(b))) {
                 g.ids.erase(g.ids.begin() + b * g.n_particles,
                             g.ids.begin() + (b + 1) * g.n_particles);
                 if (g.per_bond_stride)
                   g.per_bond.erase(g.per_bond.begin() + b * g.per_bond_stride,
                                    g.per_bond.begin() + (b + 1) * g.per_bond_stride);
                 s.compute_forces();
                 return true;
               }
             return false;
           });

  // ---- shapes (base) and constraints ----------------------------------------
  py::class_<shapes::Shape, std::shared_ptr<shapes::Shape>>(m, "Shape")
      .def("calc_dist",
           [](const shapes::Shape& sh, const Vec3& pos) {
             double dist;
             Vec3 normal = Vec3::Zero();
             sh.calc_dist(pos, dist, normal);
             return py::make_tuple(dist, normal);
           })
      .def("is_inside", &shapes::Shape::is_inside)
      .def_property_readonly("name", &shapes::Shape::name);

  py::class_<ShapeBasedConstraint, std::shared_ptr<ShapeBasedConstraint>>(m,
                                                                         "ShapeBasedConstraint")
      .def(py::init([](std::shared_ptr<shapes::Shape> shape, int particle_type, bool penetrable,
                       bool only_positive) {
        auto c = std::make_shared<ShapeBasedConstraint>();
        c->shape = std::move(shape);
        c->particle_type = particle_type;
        c->penetrable = penetrable;
        c->only_positive = only_positive;
        return c;
      }))
      .def_readonly("shape", &ShapeBasedConstraint::shape)
      .def_readonly("particle_type", &ShapeBasedConstraint::particle_type)
      .def_readonly("penetrable", &ShapeBasedConstraint::penetrable)
      .def_readonly("only_positive", &ShapeBasedConstraint::only_positive)
      .def_readonly("total_force", &ShapeBasedConstraint::total_force);

  sys.def("add_constraint",
          [](System& s, std::shared_ptr<ShapeBasedConstraint> c) {
            s.constraints.push_back(std::move(c));
          })
      .def("remove_constraint", [](System& s, const std::shared_ptr<ShapeBasedConstraint>& c) {
        auto& v = s.constraints;
        v.erase(std::remove(v.begin(), v.end(), c), v.end());
      });
}

}  // namespace pyoif::python
