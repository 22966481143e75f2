// Object-in-fluid support for the oif package: bulk exclusions and vectorised
// per-cell analysis of the OIF bonds (surface, volume, energies per term,
// forces per modulus), all without per-particle Python.
#include "bindings.hpp"

#include "interactions/bonded/bond_loop.hpp"
#include "system/system.hpp"
#include "utils/errors.hpp"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

namespace py = pybind11;

namespace pyoif::python {

namespace {

using IdArray = py::array_t<int, py::array::c_style | py::array::forcecast>;
using RealArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

template <class IA> constexpr bool is_oif_analysable() {
  return std::is_same_v<IA, OifLocalForces> || std::is_same_v<IA, OifGlobalForces>;
}

BondedEntry& entry_of(System& s, int bond_id) {
  if (bond_id < 0 || bond_id >= static_cast<int>(s.bonded.size()))
    throw InputError("bond_id: bonded interaction " + std::to_string(bond_id) +
                     " is not registered");
  return s.bonded[bond_id];
}

template <class T> py::array_t<T> to_array(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

/** The bonds of one cell (mol_id of a bond's first particle; bonds whose
 *  first particle is missing stay, so that the bond loop names them), so
 *  that the analysis of one cell costs that cell's bonds, not its type's. */
BondGroup bonds_of_cell(const BondGroup& group, const ParticleStore& p, int mol_id) {
  BondGroup out;
  out.n_particles = group.n_particles;
  out.per_bond_stride = group.per_bond_stride;
  for (std::size_t b = 0; b < group.size(); ++b) {
    const int i = p.index(group.bond(b)[0]);
    if (i >= 0 && p.mol_id[i] != mol_id)
      continue;
    out.ids.insert(out.ids.end(), group.bond(b), group.bond(b) + group.n_particles);
    if (group.per_bond_stride)
      out.per_bond.insert(out.per_bond.end(), group.reference(b),
                          group.reference(b) + group.per_bond_stride);
  }
  return out;
}

/** The group's bonds, or with mol_id >= 0 those of that cell only. */
const BondGroup& selected_bonds(const BondedEntry& entry, const ParticleStore& p, int mol_id,
                                BondGroup& storage) {
  if (mol_id < 0)
    return entry.bonds;
  storage = bonds_of_cell(entry.bonds, p, mol_id);
  return storage;
}

/** Sum of the bonds' energies per cell (mol_id of each bond's first particle). */
template <class IA>
std::map<int, double> energy_per_cell(System& s, IA ia, const BondGroup& group) {
  prepare_bonds(ia, group, s.particles, s.box, s.comm);
  std::map<int, double> e;
  for_each_bond(
      ia, group, s.particles, s.box, s.time,
      [&](const auto&, const auto&, double energy, const auto& in) { e[in.mol_id] += energy; });
  return e;
}

py::tuple cell_sums(System& s, int bond_id) {
  BondedEntry& entry = entry_of(s, bond_id);
  if (entry.bonds.n_particles != 3 || std::holds_alternative<HarmonicBond>(entry.interaction))
    throw InputError("oif_cell_sums: bonded interaction " + std::to_string(bond_id) +
                     " is not a triangle bond (OifGlobalForces or OifOutDirection)");
  oif::CellSums sums;
  sums.compute(entry.bonds, s.particles, s.box, s.comm);
  std::vector<double> volume(sums.volume.size());
  std::transform(sums.volume.begin(), sums.volume.end(), volume.begin(),
                 [](double v) { return std::abs(v); });
  return py::make_tuple(to_array(sums.mol_ids), to_array(sums.area), to_array(volume));
}

py::dict energies(System& s, int bond_id, int mol_id) {
  BondedEntry& entry = entry_of(s, bond_id);
  BondGroup storage;
  const BondGroup& bonds = selected_bonds(entry, s.particles, mol_id, storage);
  py::dict out;
  std::visit(
      [&](const auto& ia) {
        using IA = std::decay_t<decltype(ia)>;
        if constexpr (is_oif_analysable<IA>()) {
          for (const std::string& term : IA::energy_terms()) {
            const auto e = energy_per_cell(s, ia.only(term), bonds);
            std::vector<int> mols;
            std::vector<double> values;
            for (const auto& [mol, value] : e) {
              mols.push_back(mol);
              values.push_back(value);
            }
            out[py::str(term)] = py::make_tuple(to_array(mols), to_array(values));
          }
        } else {
          throw InputError("oif_energies: bonded interaction " + std::to_string(bond_id) + " (" +
                           IA::name + ") is not OifLocalForces or OifGlobalForces");
        }
      },
      entry.interaction);
  return out;
}

py::tuple forces(System& s, int bond_id, const std::string& term, int mol_id) {
  BondedEntry& entry = entry_of(s, bond_id);
  BondGroup storage;
  const BondGroup& bonds = selected_bonds(entry, s.particles, mol_id, storage);
  const ParticleStore& p = s.particles;
  std::vector<Vec3> f(p.n_local(), Vec3::Zero());
  std::vector<char> touched(p.n_local(), 0);
  std::visit(
      [&](const auto& ia) {
        using IA = std::decay_t<decltype(ia)>;
        if constexpr (is_oif_analysable<IA>()) {
          IA one = ia.only(term);
          prepare_bonds(one, bonds, s.particles, s.box, s.comm);
          for_each_bond(one, bonds, p, s.box, s.time,
                        [&](const auto& idx, const auto& fb, double, const auto&) {
                          for (std::size_t k = 0; k < idx.size(); ++k) {
                            f[idx[k]] += fb[k];
                            touched[idx[k]] = 1;
                          }
                        });
        } else {
          throw InputError("oif_forces: bonded interaction " + std::to_string(bond_id) + " (" +
                           IA::name + ") is not OifLocalForces or OifGlobalForces");
        }
      },
      entry.interaction);
  std::vector<std::pair<int, int>> order; // (id, local index)
  for (std::size_t i = 0; i < touched.size(); ++i)
    if (touched[i])
      order.emplace_back(p.id[i], static_cast<int>(i));
  std::sort(order.begin(), order.end());
  IdArray ids(static_cast<py::ssize_t>(order.size()));
  RealArray out({static_cast<py::ssize_t>(order.size()), py::ssize_t{3}});
  auto w = out.mutable_unchecked<2>();
  for (std::size_t n = 0; n < order.size(); ++n) {
    ids.mutable_data()[n] = order[n].first;
    for (int d = 0; d < 3; ++d)
      w(n, d) = f[order[n].second][d];
  }
  return py::make_tuple(ids, out);
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
           "bonds only); particle forces untouched.");
}

} // namespace pyoif::python
