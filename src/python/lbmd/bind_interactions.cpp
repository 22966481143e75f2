// Non-bonded models, bonded interactions and shape-based constraints: every
// interaction's C++ side is bound here, in one place.
#include "bindings.hpp"

#include "system/system.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <limits>
#include <vector>

namespace py = pybind11;

namespace pyoif::python {

namespace {

/** set_<model>(t1, t2, params) / get_<model>(t1, t2) on System. */
template <class Model> void bind_pair_model(py::class_<System, std::shared_ptr<System>>& sys) {
  const std::string name = Model::name;
  sys.def(("set_" + name).c_str(), [](System& s, int t1, int t2, const typename Model::Params& p) {
    s.set_nonbonded<Model>(t1, t2, p);
  });
  sys.def(("get_" + name).c_str(), [](const System& s, int t1, int t2) {
    // reading does not grow the table: a pair never set has defaults
    return s.nonbonded.entry_or_default(t1, t2).template get<Model>();
  });
}

template <class IA, class = void> struct has_reference_check : std::false_type {};
template <class IA>
struct has_reference_check<IA, std::void_t<decltype(IA::check_reference(nullptr, 0))>>
    : std::true_type {};

using IdArray = py::array_t<int, py::array::c_style | py::array::forcecast>;
using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

} // namespace

void bind_interactions(py::module_& m) {
  auto sys = py::reinterpret_borrow<py::class_<System, std::shared_ptr<System>>>(m.attr("System"));

  // the largest particle type of the non-bonded table (Python checks keys against it)
  m.attr("MAX_PARTICLE_TYPE") = NonbondedTable::max_type;

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

  py::class_<MembraneCollision::Params>(m, "MembraneCollisionParams")
      .def(py::init([](double a, double n, double cutoff, double offset) {
             return MembraneCollision::Params{a, n, cutoff, offset};
           }),
           py::arg("a"), py::arg("n"), py::arg("cutoff"), py::arg("offset"))
      .def_readonly("a", &MembraneCollision::Params::a)
      .def_readonly("n", &MembraneCollision::Params::n)
      .def_readonly("cutoff", &MembraneCollision::Params::cutoff)
      .def_readonly("offset", &MembraneCollision::Params::offset);
  bind_pair_model<MembraneCollision>(sys);

  // the guard gap is derived at the start of every run, not a parameter
  py::class_<HardContact::Params>(m, "HardContactParams")
      .def(py::init([](double a, double n, double cutoff, double offset) {
             return HardContact::Params{a, n, cutoff, offset, 0.0};
           }),
           py::arg("a"), py::arg("n"), py::arg("cutoff"), py::arg("offset"))
      .def_readonly("a", &HardContact::Params::a)
      .def_readonly("n", &HardContact::Params::n)
      .def_readonly("cutoff", &HardContact::Params::cutoff)
      .def_readonly("offset", &HardContact::Params::offset)
      .def_readonly("guard_gap", &HardContact::Params::guard_gap);
  bind_pair_model<HardContact>(sys);

  // the energy shift (U(cutoff) = 0) is derived, not a parameter
  py::class_<Morse::Params>(m, "MorseParams")
      .def(py::init(&Morse::make), py::arg("eps"), py::arg("alpha"), py::arg("rmin"),
           py::arg("cutoff"))
      .def_readonly("eps", &Morse::Params::eps)
      .def_readonly("alpha", &Morse::Params::alpha)
      .def_readonly("rmin", &Morse::Params::rmin)
      .def_readonly("cutoff", &Morse::Params::cutoff)
      .def_readonly("shift", &Morse::Params::shift);
  bind_pair_model<Morse>(sys);

  // ---- bonded interactions --------------------------------------------------
  py::class_<HarmonicBond>(m, "HarmonicBond")
      .def(py::init([](double k, double r_0, double r_cut) {
             return HarmonicBond{k, r_0, r_cut};
           }),
           py::arg("k"), py::arg("r_0"), py::arg("r_cut"))
      .def_readonly("k", &HarmonicBond::k)
      .def_readonly("r_0", &HarmonicBond::r_0)
      .def_readonly("r_cut", &HarmonicBond::r_cut);

  // OIF membrane bonds (the per-bond reference values r0, phi0, A01, A02 of
  // OifLocalForces travel with the bonds, not with the interaction)
  py::class_<OifLocalForces>(m, "OifLocalForces")
      .def(py::init([](double ks, double kslin, double kb, double kal, double kvisc) {
             return OifLocalForces{ks, kslin, kb, kal, kvisc};
           }),
           py::arg("ks"), py::arg("kslin"), py::arg("kb"), py::arg("kal"), py::arg("kvisc"))
      .def_readonly("ks", &OifLocalForces::ks)
      .def_readonly("kslin", &OifLocalForces::kslin)
      .def_readonly("kb", &OifLocalForces::kb)
      .def_readonly("kal", &OifLocalForces::kal)
      .def_readonly("kvisc", &OifLocalForces::kvisc);
  py::class_<OifGlobalForces>(m, "OifGlobalForces")
      .def(py::init([](double A0_g, double ka_g, double V0, double kv) {
             OifGlobalForces g;
             g.A0_g = A0_g;
             g.ka_g = ka_g;
             g.V0 = V0;
             g.kv = kv;
             return g;
           }),
           py::arg("A0_g"), py::arg("ka_g"), py::arg("V0"), py::arg("kv"))
      .def_readonly("A0_g", &OifGlobalForces::A0_g)
      .def_readonly("ka_g", &OifGlobalForces::ka_g)
      .def_readonly("V0", &OifGlobalForces::V0)
      .def_readonly("kv", &OifGlobalForces::kv);
  py::class_<OifOutDirection>(m, "OifOutDirection").def(py::init<>());

  sys.def("add_bonded_interaction", &System::add_bonded_interaction)
      .def("n_bonded_interactions", [](const System& s) { return s.bonded.size(); })
      .def("add_bonds",
           [](System& s, int bond_id, const IdArray& ids, const RealArray& per_bond) {
             std::vector<int> i(ids.data(), ids.data() + ids.size());
             std::vector<double> r(per_bond.data(), per_bond.data() + per_bond.size());
             if (bond_id >= 0 && bond_id < static_cast<int>(s.bonded.size()))
               std::visit(
                   [&](const auto& ia) {
                     using IA = std::decay_t<decltype(ia)>;
                     if constexpr (IA::per_bond_stride > 0 && has_reference_check<IA>::value)
                       for (std::size_t b = 0; b < r.size() / IA::per_bond_stride; ++b)
                         IA::check_reference(r.data() + b * IA::per_bond_stride, b);
                   },
                   s.bonded[bond_id].interaction);
             s.add_bonds(bond_id, i, r);
           })
      .def("get_bonds",
           [](const System& s, int bond_id) {
             const BondGroup& g = s.bonded.at(bond_id).bonds;
             IdArray out(
                 {static_cast<py::ssize_t>(g.size()), static_cast<py::ssize_t>(g.n_particles)});
             std::copy(g.ids.begin(), g.ids.end(), out.mutable_data());
             return out;
           })
      .def("remove_bond", &System::remove_bond);

  // ---- shapes (base) and constraints ----------------------------------------
  py::class_<shapes::Shape, std::shared_ptr<shapes::Shape>>(m, "Shape")
      .def("calc_dist",
           [](const shapes::Shape& sh, const Vec3& pos) {
             double dist;
             Vec3 normal = Vec3::Zero();
             sh.calc_dist(pos, dist, normal);
             return py::make_tuple(dist, normal);
           })
      // the signed distances of an (n, 3) array of points in one call (the
      // seeding's fluid volume and clearance tests): exact where below
      // `range`, else any value >= range (Shape::signed_distances)
      .def(
          "signed_distances",
          [](const shapes::Shape& sh,
             const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>& pos,
             double range) {
            std::vector<Vec3> points(static_cast<std::size_t>(pos.rows()));
            for (Eigen::Index i = 0; i < pos.rows(); ++i)
              points[static_cast<std::size_t>(i)] = pos.row(i).transpose();
            Eigen::VectorXd dist(pos.rows());
            {
              py::gil_scoped_release release;
              sh.signed_distances(points.data(), points.size(), range, dist.data());
            }
            return dist;
          },
          py::arg("pos"), py::arg("range") = std::numeric_limits<double>::infinity())
      .def("is_inside", &shapes::Shape::is_inside)
      .def_property_readonly("name", &shapes::Shape::name);

  py::class_<ShapeBasedConstraint, std::shared_ptr<ShapeBasedConstraint>>(m, "ShapeBasedConstraint")
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

  sys.def("add_constraint", &System::add_constraint)
      .def("remove_constraint", &System::remove_constraint);
}

} // namespace pyoif::python
