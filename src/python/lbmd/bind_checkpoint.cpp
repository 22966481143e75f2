// The raw state a checkpoint needs beyond the public API (lbmd/checkpoint.py):
// the particles as stored (folded positions and image counters, forces and
// normals of the last step, local order), the pair list's reference
// positions, exclusions, bonds with their reference values, the integrator's
// and the coupling's counters. Collective under MPI, like every query.
#include "bindings.hpp"

#include "system/system.hpp"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <vector>

namespace py = pybind11;

namespace pyoif::python {

namespace {

using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<int, py::array::c_style | py::array::forcecast>;

template <class V> py::array rows(const std::vector<V>& v) {
  using Scalar = typename V::Scalar;
  py::array_t<Scalar> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
  auto w = out.template mutable_unchecked<2>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int d = 0; d < 3; ++d)
      w(i, d) = v[i][d];
  return std::move(out);
}

template <class V, class A> std::vector<V> from_rows(const A& a, const char* what) {
  if (a.ndim() != 2 || (a.shape(0) > 0 && a.shape(1) != 3))
    throw InputError(std::string("checkpoint: ") + what + " must have 3 columns");
  auto r = a.template unchecked<2>();
  std::vector<V> out(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    out[i] = V(r(i, 0), r(i, 1), r(i, 2));
  return out;
}

template <class T> py::array column(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return std::move(out);
}

py::dict particle_state(System& s) {
  s.synchronize();
  const auto& p = s.particles;
  py::dict d;
  d["id"] = column(p.id);
  d["folded_pos"] = rows(p.pos);
  d["image"] = rows(p.image);
  d["v"] = rows(p.vel);
  d["f"] = rows(p.force);
  d["ext_force"] = rows(p.ext_force);
  d["normal"] = rows(p.normal);
  d["mass"] = column(p.mass);
  d["type"] = column(p.type);
  d["mol_id"] = column(p.mol_id);
  d["fixed"] = column(p.fixed);
  d["rebuild_reference"] = rows(s.cells.rebuild_reference());
  const auto excl = s.cells.exclusion_pairs();
  py::array_t<int> e({static_cast<py::ssize_t>(excl.size()), py::ssize_t{2}});
  auto w = e.mutable_unchecked<2>();
  for (std::size_t i = 0; i < excl.size(); ++i)
    w(i, 0) = excl[i][0], w(i, 1) = excl[i][1];
  d["exclusions"] = e;
  return d;
}

} // namespace

void bind_checkpoint(py::module_& m) {
  auto system =
      py::reinterpret_borrow<py::class_<System, std::shared_ptr<System>>>(m.attr("System"));
  system.def("checkpoint_particles", &particle_state)
      .def_property_readonly("lb_substep", &System::lb_substep)
      .def_property_readonly("nonbonded_n_types",
                             [](const System& s) { return s.nonbonded.n_types(); })
      .def("set_step_count", [](System& s, std::uint64_t n) { s.step_count = n; })
      .def("bond_reference_values",
           [](const System& s, int bond_id) { return column(s.bonded.at(bond_id).bonds.per_bond); })
      .def(
          "restore_run_state",
          [](System& s, const RealArray& folded_pos, const IntArray& image, const RealArray& force,
             const RealArray& normal, const RealArray& reference, int lb_substep,
             bool forces_valid) {
            s.restore_run_state(
                from_rows<Vec3>(folded_pos, "folded_pos"), from_rows<Vec3i>(image, "image"),
                from_rows<Vec3>(force, "f"), from_rows<Vec3>(normal, "normal"),
                from_rows<Vec3>(reference, "rebuild_reference"), lb_substep, forces_valid);
          },
          py::arg("folded_pos"), py::arg("image"), py::arg("force"), py::arg("normal"),
          py::arg("reference"), py::arg("lb_substep"), py::arg("forces_valid") = true)
      .def_property_readonly("forces_valid", &System::forces_valid)
      .def("coupling_ledger_state",
           [](System& s) {
             // (any, step, in_flight summed over the ranks)
             const auto& l = s.lb_coupling().ledger;
             Vec3 in_flight = s.fluid() ? l.in_flight_momentum(*s.fluid()) : Vec3::Zero();
             return py::make_tuple(l.any, l.step,
                                   py::make_tuple(in_flight[0], in_flight[1], in_flight[2]));
           })
      .def("set_coupling_ledger_state",
           [](System& s, bool any, std::uint64_t step, const Vec3& in_flight) {
             if (!s.fluid())
               throw InputError("set_coupling_ledger_state: no lattice-Boltzmann fluid is active");
             lb::LBFluid& f = *s.fluid();
             f.require_flagged("the coupling's records");
             // the whole in-flight impulse on the first rank, a share elsewhere
             lb::CouplingLedger& l = s.lb_coupling_ledger();
             l = lb::CouplingLedger{};
             l.lattice_generation = f.layout_generation();
             l.any = any;
             l.step = step;
             const bool first = !f.distributed() || f.domain().rank() == 0;
             l.in_flight = first ? in_flight : Vec3::Zero();
             l.in_flight_partial = f.distributed();
             if (any)
               f.note_coupling(); // as after the run it continues
           });

  auto fluid = py::reinterpret_borrow<py::class_<lb::LBFluid, std::shared_ptr<lb::LBFluid>>>(
      m.attr("LBFluid"));
  fluid.def("set_n_updates", &lb::LBFluid::set_n_updates);
}

} // namespace pyoif::python
