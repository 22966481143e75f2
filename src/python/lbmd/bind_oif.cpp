// Object-in-fluid support for the oif package: bulk exclusions and vectorised
// per-cell analysis of the OIF bonds (surface, volume, energies per term,
// forces per modulus), all without per-particle Python.
#include "bindings.hpp"

#include "interactions/membrane/bending.hpp"
#include "interactions/membrane/membrane_model.hpp"
#include "system/system.hpp"
#include "utils/errors.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <string>
#include <type_traits>
#include <vector>

namespace py = pybind11;

namespace pyoif::python {

namespace {

using IdArray = py::array_t<int, py::array::c_style | py::array::forcecast>;
using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

template <class T> py::array_t<T> to_array(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

/** Checks that bond_id is a registered interaction of one of the Kinds
 *  (`what`: how the message names them, default their names). */
template <class... Kinds>
void check_kind(const System& s, const char* caller, int bond_id, std::string what = "") {
  if (bond_id < 0 || bond_id >= static_cast<int>(s.bonded.size()))
    throw InputError("bond_id: bonded interaction " + std::to_string(bond_id) +
                     " is not registered");
  if (!(std::holds_alternative<Kinds>(s.bonded[bond_id].interaction) || ...)) {
    if (what.empty())
      ((what += (what.empty() ? "" : " or ") + std::string(Kinds::name)), ...);
    throw InputError(std::string(caller) + ": bonded interaction " + std::to_string(bond_id) +
                     " is not " + what);
  }
}

/** One interaction's bonds (with mol_id >= 0 that cell's only, at the cost
 *  of that cell), one term's moduli (term >= 0). */
membrane::Selection selection(int bond_id, int mol_id, int term) {
  if (mol_id < -1)
    throw InputError("mol_id: a cell's mol_id (>= 0), or -1 for all cells, got " +
                     std::to_string(mol_id));
  membrane::Selection select;
  select.bond_id = bond_id;
  select.mol_id = mol_id;
  select.term = term;
  return select;
}

/** The analysis of the selected bonds, compiled and evaluated by the
 *  membrane component's driver, the time step's. */
std::vector<membrane::CellReport> analyse(System& s, const membrane::Selection& select) {
  collective_entry("a cell analysis");
  s.synchronize(); // spread over ranks: every copy current (collective)
  return membrane::analyse(s.bonded, select, s.particles, s.box, s.time, nullptr);
}

py::tuple cell_sums(System& s, int bond_id) {
  collective_entry("a cell analysis");
  s.synchronize(); // spread over ranks: every copy current (collective)
  check_kind<OifGlobalForces, OifOutDirection>(
      s, "oif_cell_sums", bond_id, "a triangle bond (OifGlobalForces or OifOutDirection)");
  const auto reports = analyse(s, selection(bond_id, -1, -1));
  std::vector<int> mols;
  std::vector<double> areas, volumes;
  for (const auto& r : reports) {
    mols.push_back(r.mol_id);
    areas.push_back(r.area);
    volumes.push_back(std::abs(r.volume));
  }
  return py::make_tuple(to_array(mols), to_array(areas), to_array(volumes));
}

py::dict energies(System& s, int bond_id, int mol_id) {
  collective_entry("a cell analysis");
  s.synchronize(); // spread over ranks: every copy current (collective)
  check_kind<OifLocalForces, OifGlobalForces>(s, "oif_energies", bond_id);
  const auto reports = analyse(s, selection(bond_id, mol_id, -1));
  const bool local = std::holds_alternative<OifLocalForces>(s.bonded[bond_id].interaction);
  const std::vector<int> terms =
      local ? std::vector<int>{membrane::stretching, membrane::bending, membrane::local_area}
            : std::vector<int>{membrane::global_area, membrane::volume};
  std::vector<int> mols;
  for (const auto& r : reports)
    mols.push_back(r.mol_id);
  py::dict out;
  for (const int term : terms) {
    std::vector<double> values;
    for (const auto& r : reports)
      values.push_back(r.energy[term]);
    out[py::str(membrane::term_name(term))] = py::make_tuple(to_array(mols), to_array(values));
  }
  return out;
}

py::tuple forces(System& s, int bond_id, const std::string& term, int mol_id) {
  collective_entry("a cell analysis");
  s.synchronize(); // spread over ranks: every copy current (collective)
  check_kind<OifLocalForces, OifGlobalForces>(s, "oif_forces", bond_id);
  const int which = membrane::term_of(term);
  const bool local_term = which == membrane::stretching || which == membrane::bending ||
                          which == membrane::local_area || which == membrane::viscosity;
  if (std::holds_alternative<OifGlobalForces>(s.bonded[bond_id].interaction) && local_term)
    throw InputError("term: OifGlobalForces has the terms 'global_area' and 'volume', got '" +
                     term + "'");
  if (std::holds_alternative<OifLocalForces>(s.bonded[bond_id].interaction) && !local_term)
    throw InputError("term: OifLocalForces has the terms 'stretching', 'bending', 'local_area' "
                     "and 'visc', got '" +
                     term + "'");
  std::vector<Vec3> f(s.particles.n_local(), Vec3::Zero());
  std::vector<std::pair<int, int>> nodes; // of the selected cells, in id order
  // the viscosity as the time step applies it (implicit over one step)
  membrane::analyse(s.bonded, selection(bond_id, mol_id, which), s.particles, s.box, s.time,
                    f.data(), &nodes, s.time_step());
  IdArray out_ids(static_cast<py::ssize_t>(nodes.size()));
  RealArray out({static_cast<py::ssize_t>(nodes.size()), py::ssize_t{3}});
  auto w = out.mutable_unchecked<2>();
  for (std::size_t n = 0; n < nodes.size(); ++n) {
    out_ids.mutable_data()[n] = nodes[n].first;
    for (int d = 0; d < 3; ++d)
      w(n, d) = f[nodes[n].second][d];
  }
  return py::make_tuple(out_ids, out);
}

py::array_t<double> angles(const RealArray& nodes, const IdArray& rows) {
  if (nodes.ndim() != 2 || nodes.shape(1) != 3)
    throw InputError("membrane_angles: nodes must be an N×3 array");
  if (rows.ndim() != 2 || rows.shape(1) != 4)
    throw InputError("membrane_angles: angles must be an M×4 array of node indices (A, B, C, D)");
  auto x = nodes.unchecked<2>();
  auto r = rows.unchecked<2>();
  py::array_t<double> out(r.shape(0));
  auto node = [&](py::ssize_t k, int j) {
    const int i = r(k, j);
    if (i < 0 || i >= x.shape(0))
      throw InputError("membrane_angles: node index " + std::to_string(i) + " out of range");
    return Vec3(x(i, 0), x(i, 1), x(i, 2));
  };
  for (py::ssize_t k = 0; k < r.shape(0); ++k) {
    const Vec3 a = node(k, 0), b = node(k, 1), c = node(k, 2), d = node(k, 3);
    const double e[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]};
    const double u[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    const double w[3] = {d[0] - b[0], d[1] - b[1], d[2] - b[2]};
    const membrane::Wings<double> wings(e, u, w);
    if (!(e[0] * e[0] + e[1] * e[1] + e[2] * e[2] > 0.0) || !(wings.n1_2 > 0.0) ||
        !(wings.n2_2 > 0.0))
      throw InputError("membrane_angles: angle " + std::to_string(k) + " (nodes " +
                       std::to_string(r(k, 0)) + ", " + std::to_string(r(k, 1)) + ", " +
                       std::to_string(r(k, 2)) + ", " + std::to_string(r(k, 3)) +
                       ") is degenerate: its edge or one of its triangles has no extent");
    out.mutable_data()[k] = membrane::dihedral_angle(a, b, c, d);
  }
  return out;
}

void add_exclusions(System& s, const IdArray& pairs) {
  if (pairs.ndim() != 2 || pairs.shape(1) != 2)
    throw InputError("add_exclusions: expected an M×2 array of particle ids");
  auto r = pairs.unchecked<2>();
  for (py::ssize_t k = 0; k < r.shape(0); ++k) {
    if (r(k, 0) == r(k, 1))
      throw InputError("add_exclusions: a particle cannot be excluded from itself (id " +
                       std::to_string(r(k, 0)) + ")");
    s.checked_index(r(k, 0));
    s.checked_index(r(k, 1));
  }
  // System::add_exclusion invalidates the pair list and the forces; doing it
  // M times only sets flags, so the rebuild happens once at the next force
  // calculation
  for (py::ssize_t k = 0; k < r.shape(0); ++k)
    s.add_exclusion(r(k, 0), r(k, 1));
}

} // namespace

void bind_oif(py::module_& m) {
  auto sys = py::reinterpret_borrow<py::class_<System, std::shared_ptr<System>>>(m.attr("System"));
  sys.def("add_exclusions", &add_exclusions, py::arg("pairs"),
          "Exclude M pairs of particles (an M×2 id array) from the non-bonded interactions.")
      .def("oif_cell_sums", &cell_sums, py::arg("bond_id"),
           "(mol_ids, areas, volumes) of the cells of a triangle bond group, current positions.")
      .def("oif_energies", &energies, py::arg("bond_id"), py::arg("mol_id") = -1,
           "dict term -> (mol_ids, energies) of an OifLocalForces or OifGlobalForces group "
           "(mol_id >= 0: of that cell's bonds only).")
      .def("oif_forces", &forces, py::arg("bond_id"), py::arg("term"), py::arg("mol_id") = -1,
           "(ids, N×3 forces) of one modulus of an OIF bond group (mol_id >= 0: of that cell's "
           "bonds only); particle forces untouched.")
      .def_property(
          "membrane_lanes", [](const System& s) { return s.membranes.lanes; },
          [](System& s, bool lanes) { s.membranes.lanes = lanes; },
          "The membrane pass evaluates four cells of a type at once, one per vector lane "
          "(default); False: every cell alone (the same forces bit for bit).")
      .def(
          "membrane_counts",
          [](const System& s) {
            const membrane::PassCounts& c = s.membranes.counts;
            py::dict d;
            d["compiles"] = c.compiles;
            d["lane_batches"] = c.lane_batches;
            d["padded_lanes"] = c.padded_lanes;
            d["plain_cells"] = c.plain_cells;
            d["viscous_solves"] = c.viscous_solves;
            d["viscous_iterations"] = c.viscous_iterations;
            d["viscous_max_iterations"] = c.viscous_max_iterations;
            return d;
          },
          "How often the membrane pass compiled its tables and evaluated cells in vector "
          "lanes (batches of four) or alone, and how many implicit membrane-viscosity "
          "solves it made with how many conjugate-gradient iterations (summed, and the "
          "most of one), since the System was made.")
      .def(
          "membrane_invalidate", [](System& s) { s.membranes.invalidate(); },
          "Drop the compiled membrane tables (the next force calculation compiles anew).");
  m.def("membrane_angles", &angles, py::arg("nodes"), py::arg("angles"),
        "PyOIF's angle between the triangles (A, B, C) and (B, C, D) for rows (A, B, C, D) of "
        "node indices: the reference angles phi0 of a relaxed mesh, by the membrane "
        "component's own function.");
}

} // namespace pyoif::python
