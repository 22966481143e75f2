// The membrane component's compile step (membrane_model.hpp): the OIF bonds
// of a System become cells, topologies and groups; and the cache of the
// compiled model that the time step uses.
#include "interactions/membrane/membrane_model.hpp"

#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <utility>

namespace pyoif::membrane {

namespace {

constexpr const char* kTermNames[n_terms] = {"stretching",  "bending", "local_area",
                                             "global_area", "volume",  "visc"};

/** A cell's membrane bonds while compiling: (bonded id, bond index) by kind. */
struct CellBonds {
  int mol_id = 0;
  std::vector<std::pair<int, std::size_t>> local, closed, normals;
};

[[noreturn]] void missing_particle(const char* name, int bond_id, int pid) {
  throw SimulationInstability(std::string(name) + " bond (bonded interaction " +
                              std::to_string(bond_id) + ") refers to particle " +
                              std::to_string(pid) + ", which does not exist");
}

/** A triangle's key independent of its orientation: its three cell-local
 *  nodes sorted, 21 bits each. */
std::uint64_t triangle_key(int a, int b, int c) {
  const int lo = std::min({a, b, c}), hi = std::max({a, b, c}), mid = a + b + c - lo - hi;
  return static_cast<std::uint64_t>(lo) | (static_cast<std::uint64_t>(mid) << 21) |
         (static_cast<std::uint64_t>(hi) << 42);
}
constexpr int kMaxCellNodes = 1 << 21;

/** Calls f(table) for every table of a topology (comparison and hashing). */
template <class F> void for_each_table(const Topology& t, F&& f) {
  for (const auto* v :
       {&t.tri_v0, &t.tri_v1, &t.tri_v2, &t.edge_b, &t.edge_a, &t.edge_c, &t.edge_d})
    f(*v);
  for (const auto* v : {&t.closed_weight, &t.normal_weight})
    f(*v);
  f(t.local_area);
  f(t.stretching);
  f(t.bending);
  f(t.viscosity);
  f(t.has_normal);
}

bool same_tables(const Topology& a, const Topology& b) {
  if (a.n_nodes != b.n_nodes || a.origin != b.origin)
    return false;
  std::vector<std::pair<const void*, std::size_t>> left, right;
  auto collect = [](auto& out) {
    return [&out](const auto& v) { out.emplace_back(v.data(), v.size() * sizeof(v[0])); };
  };
  for_each_table(a, collect(left));
  for_each_table(b, collect(right));
  for (std::size_t k = 0; k < left.size(); ++k)
    if (left[k].second != right[k].second ||
        (left[k].second && std::memcmp(left[k].first, right[k].first, left[k].second) != 0))
      return false;
  return true;
}

std::uint64_t hash_tables(const Topology& t) {
  std::uint64_t h = 1469598103934665603ULL ^ static_cast<std::uint64_t>(t.n_nodes);
  for_each_table(t, [&h](const auto& v) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(v.data());
    for (std::size_t k = 0; k < v.size() * sizeof(v[0]); ++k)
      h = (h ^ bytes[k]) * 1099511628211ULL; // FNV-1a
  });
  return h;
}

/** The moduli of a term selection: x where the term is selected (or all are). */
double keep(int selected, int term, double x) {
  return selected < 0 || selected == term ? x : 0.0;
}

/** The tables of one cell (its topology), its nodes' particle ids and its
 *  record. */
void build_cell(const std::vector<BondedEntry>& bonded, const CellBonds& bonds, int term,
                Topology& t, std::vector<int>& node_ids, Cell& cell) {
  cell.mol_id = bonds.mol_id;
  // nodes: the cell's particles in increasing id order (the cells of an
  // OifCellType are blocks of consecutive ids: the same numbers for all)
  node_ids.clear();
  auto add_ids = [&](const std::vector<std::pair<int, std::size_t>>& list) {
    for (const auto& [bond_id, b] : list) {
      const BondGroup& g = bonded[bond_id].bonds;
      node_ids.insert(node_ids.end(), g.bond(b), g.bond(b) + g.n_particles);
    }
  };
  add_ids(bonds.closed);
  add_ids(bonds.normals);
  add_ids(bonds.local);
  std::sort(node_ids.begin(), node_ids.end());
  node_ids.erase(std::unique(node_ids.begin(), node_ids.end()), node_ids.end());
  if (node_ids.size() >= static_cast<std::size_t>(kMaxCellNodes))
    throw InputError("membrane of the cell with mol_id " + std::to_string(cell.mol_id) + ": " +
                     std::to_string(node_ids.size()) + " nodes, more than the " +
                     std::to_string(kMaxCellNodes) + " a cell may have");
  t.n_nodes = static_cast<int>(node_ids.size());
  auto node = [&](int pid) {
    return static_cast<int>(std::lower_bound(node_ids.begin(), node_ids.end(), pid) -
                            node_ids.begin());
  };
  std::unordered_map<std::uint64_t, int> triangle_of;
  auto triangle = [&](int a, int b, int c) {
    const auto [it, inserted] =
        triangle_of.try_emplace(triangle_key(a, b, c), static_cast<int>(t.tri_v0.size()));
    if (inserted) {
      t.tri_v0.push_back(a);
      t.tri_v1.push_back(b);
      t.tri_v2.push_back(c);
      t.local_area.push_back(LocalAreaParams{});
      t.closed_weight.push_back(0.0);
      t.normal_weight.push_back(0.0);
    }
    return it->second;
  };
  // the closed surface first (the volume's reference point is the first node
  // of its first triangle: the volume of an open mesh depends on it)
  for (const auto& [bond_id, b] : bonds.closed) {
    if (cell.global_bond_id >= 0 && cell.global_bond_id != bond_id)
      throw InputError(
          "mol_id " + std::to_string(cell.mol_id) +
          " has triangles of two OifGlobalForces interactions (bonded ids " +
          std::to_string(cell.global_bond_id) + " and " + std::to_string(bond_id) +
          "): a cell is the mol_id of its particles, and its surface and volume come from one "
          "interaction; give each cell's particles a mol_id of their own");
    cell.global_bond_id = bond_id;
    const auto& ia = std::get<OifGlobalForces>(bonded[bond_id].interaction);
    cell.global_area = {keep(term, global_area, ia.ka_g), ia.A0_g > 0.0 ? ia.A0_g : 1.0};
    cell.volume = {keep(term, volume, ia.kv), ia.V0 > 0.0 ? ia.V0 : 1.0};
    const int* ids = bonded[bond_id].bonds.bond(b);
    const int q = triangle(node(ids[0]), node(ids[1]), node(ids[2]));
    if (t.closed_weight[q] != 0.0)
      throw InputError("OifGlobalForces (bonded interaction " + std::to_string(bond_id) +
                       "): the triangle of particles " + std::to_string(ids[0]) + ", " +
                       std::to_string(ids[1]) + ", " + std::to_string(ids[2]) +
                       " is bonded twice in the cell with mol_id " + std::to_string(cell.mol_id));
    t.closed_weight[q] = 1.0;
  }
  for (const auto& [bond_id, b] : bonds.normals) {
    const int* ids = bonded[bond_id].bonds.bond(b);
    t.normal_weight[triangle(node(ids[0]), node(ids[1]), node(ids[2]))] = 1.0;
  }
  // without OifGlobalForces the normals' triangles give the orientation
  if (bonds.closed.empty())
    t.closed_weight = t.normal_weight;
  for (const auto& [bond_id, b] : bonds.local) {
    const auto& ia = std::get<OifLocalForces>(bonded[bond_id].interaction);
    if (cell.local_bond_id < 0)
      cell.local_bond_id = bond_id;
    const int* ids = bonded[bond_id].bonds.bond(b);         // (B, A, C, D)
    const double* ref = bonded[bond_id].bonds.reference(b); // r0, phi0, A01, A02
    const int nb = node(ids[0]), na = node(ids[1]), nc = node(ids[2]), nd = node(ids[3]);
    t.edge_b.push_back(nb);
    t.edge_a.push_back(na);
    t.edge_c.push_back(nc);
    t.edge_d.push_back(nd);
    t.stretching.push_back(
        {keep(term, stretching, ia.ks), keep(term, stretching, ia.kslin), ref[0], 1.0 / ref[0]});
    t.bending.push_back(BendingParams::of(keep(term, bending, ia.kb), ref[1]));
    t.viscosity.push_back({keep(term, viscosity, ia.kvisc)});
    const double kal = keep(term, local_area, ia.kal);
    if (kal != 0.0) { // a third of the local area term on each of the bond's triangles
      LocalAreaParams& abc = t.local_area[triangle(na, nb, nc)];
      abc.kal_weight += kal / 3.0;
      abc.kal_area0 += kal * ref[2] / 3.0;
      LocalAreaParams& bcd = t.local_area[triangle(nb, nc, nd)];
      bcd.kal_weight += kal / 3.0;
      bcd.kal_area0 += kal * ref[3] / 3.0;
    }
  }
  auto any = [](const auto& v, auto value) {
    return std::any_of(v.begin(), v.end(), [&](const auto& x) { return value(x) != 0.0; });
  };
  t.neo = any(t.stretching, [](const StretchingParams& x) { return x.ks; });
  t.visc = any(t.viscosity, [](const ViscosityParams& x) { return x.kvisc; });
  t.bend = any(t.bending, [](const BendingParams& x) { return x.kb; });
  if (t.visc) {
    std::vector<double> node_kvisc(t.n_nodes, 0.0);
    for (std::size_t k = 0; k < t.edge_b.size(); ++k) {
      node_kvisc[t.edge_b[k]] += t.viscosity[k].kvisc;
      node_kvisc[t.edge_c[k]] += t.viscosity[k].kvisc;
    }
    t.kvisc_node_max = *std::max_element(node_kvisc.begin(), node_kvisc.end());
  }
  t.edges = t.neo || t.visc || t.bend ||
            any(t.stretching, [](const StretchingParams& x) { return x.kslin; });
  if (!t.edges) {
    for (auto* v : {&t.edge_b, &t.edge_a, &t.edge_c, &t.edge_d})
      v->clear();
    t.stretching.clear();
    t.bending.clear();
    t.viscosity.clear();
  }
  auto itself = [](double x) { return x; };
  t.has_local_area = any(t.local_area, [](const LocalAreaParams& x) { return x.kal_weight; });
  t.closed = any(t.closed_weight, itself);
  t.normals = any(t.normal_weight, itself);
  t.separate_sums = t.normals && t.closed_weight != t.normal_weight;
  const auto first_closed = std::find_if(t.closed_weight.begin(), t.closed_weight.end(),
                                         [](double w) { return w != 0.0; });
  t.origin = first_closed == t.closed_weight.end()
                 ? 0
                 : t.tri_v0[static_cast<std::size_t>(first_closed - t.closed_weight.begin())];
  t.has_normal.assign(static_cast<std::size_t>(t.n_nodes), 0);
  for (std::size_t q = 0; q < t.tri_v0.size(); ++q)
    if (t.normal_weight[q] != 0.0)
      for (const int v : {t.tri_v0[q], t.tri_v1[q], t.tri_v2[q]})
        t.has_normal[v] = 1;
  if (!t.has_local_area && !t.closed) {
    for (auto* v : {&t.tri_v0, &t.tri_v1, &t.tri_v2})
      v->clear();
    t.local_area.clear();
    t.closed_weight.clear();
    t.normal_weight.clear();
  }
}

} // namespace

const char* term_name(int term) {
  return term >= 0 && term < n_terms ? kTermNames[term] : "all";
}

int term_of(const std::string& name) {
  for (int k = 0; k < n_terms; ++k)
    if (name == kTermNames[k])
      return k;
  throw InputError("term: the membrane terms are 'stretching', 'bending', 'local_area', "
                   "'global_area', 'volume' and 'visc', got '" +
                   name + "'");
}

void Model::compile(const std::vector<BondedEntry>& bonded, const Selection& select,
                    const ParticleStore& p) {
  m_topologies.clear();
  m_cells.clear();
  m_groups.clear();
  m_node_index.clear();
  m_normal_nodes.clear();
  // 1. the bonds by cell: the mol_id of each bond's first particle; cells in
  //    the order they first appear
  std::unordered_map<int, int> cell_of_mol;
  std::vector<CellBonds> by_cell;
  for (std::size_t bond_id = 0; bond_id < bonded.size(); ++bond_id) {
    if (select.bond_id >= 0 && static_cast<int>(bond_id) != select.bond_id)
      continue;
    const BondGroup& g = bonded[bond_id].bonds;
    std::visit(
        [&](const auto& ia) {
          using IA = std::decay_t<decltype(ia)>;
          if constexpr (is_membrane_bond<IA>) {
            for (std::size_t b = 0; b < g.size(); ++b) {
              const int* ids = g.bond(b);
              for (int k = 0; k < IA::n_particles; ++k)
                if (p.index(ids[k]) < 0)
                  missing_particle(IA::name, static_cast<int>(bond_id), ids[k]);
              const int mol = p.mol_id[p.index(ids[0])];
              if (select.mol_id >= 0 && mol != select.mol_id)
                continue;
              if (select.owned && !select.owned[p.index(ids[0])])
                continue; // another rank's cell
              const auto [it, inserted] =
                  cell_of_mol.try_emplace(mol, static_cast<int>(by_cell.size()));
              if (inserted)
                by_cell.push_back(CellBonds{mol, {}, {}, {}});
              CellBonds& cell = by_cell[it->second];
              auto& list = std::is_same_v<IA, OifLocalForces>    ? cell.local
                           : std::is_same_v<IA, OifGlobalForces> ? cell.closed
                                                                 : cell.normals;
              list.emplace_back(static_cast<int>(bond_id), b);
            }
          }
        },
        bonded[bond_id].interaction);
  }
  // 2. each cell's tables; cells with the same tables share one copy
  std::unordered_map<std::uint64_t, std::vector<int>> topologies_of_hash;
  std::vector<int> node_ids;
  for (const CellBonds& bonds : by_cell) {
    Topology t;
    Cell cell;
    build_cell(bonded, bonds, select.term, t, node_ids, cell);
    cell.node_begin = static_cast<int>(m_node_index.size());
    for (const int pid : node_ids)
      m_node_index.push_back(p.index(pid));
    auto& candidates = topologies_of_hash[hash_tables(t)];
    const auto same = std::find_if(candidates.begin(), candidates.end(),
                                   [&](int k) { return same_tables(m_topologies[k], t); });
    if (same != candidates.end()) {
      cell.topology = *same;
    } else {
      cell.topology = static_cast<int>(m_topologies.size());
      candidates.push_back(cell.topology);
      m_topologies.push_back(std::move(t));
    }
    m_cells.push_back(cell);
  }
  // 3. groups: the cells of a topology four at a time (one per vector lane),
  //    in order; of the last n mod 4, two or three go as one group whose
  //    unused lanes repeat its first cell, a lone one alone
  std::vector<std::vector<int>> cells_of(m_topologies.size());
  for (std::size_t c = 0; c < m_cells.size(); ++c)
    cells_of[m_cells[c].topology].push_back(static_cast<int>(c));
  constexpr int kLanes = lanes_of<Lanes>;
  for (const auto& cells : cells_of) {
    std::size_t k = 0;
    for (; select.lanes && k + 2 <= cells.size(); k += kLanes) {
      Group g;
      g.lanes = kLanes;
      g.n_cells = static_cast<int>(std::min<std::size_t>(kLanes, cells.size() - k));
      for (int j = 0; j < kLanes; ++j)
        g.cell[j] = cells[k + (j < g.n_cells ? j : 0)];
      m_groups.push_back(g);
    }
    for (; k < cells.size(); ++k) {
      Group g;
      g.cell[0] = cells[k];
      m_groups.push_back(g);
    }
  }
  // 4. nodes of two cells (bonds across cells): their normals are summed over
  //    the cells, then normalised; the nodes that get a normal
  std::vector<int> sorted = m_node_index;
  std::sort(sorted.begin(), sorted.end());
  m_shared_nodes = std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
  for (const Cell& cell : m_cells) {
    const Topology& t = m_topologies[cell.topology];
    for (int k = 0; k < t.n_nodes; ++k)
      if (t.has_normal[k])
        m_normal_nodes.push_back(m_node_index[cell.node_begin + k]);
  }
  std::sort(m_normal_nodes.begin(), m_normal_nodes.end());
  m_normal_nodes.erase(std::unique(m_normal_nodes.begin(), m_normal_nodes.end()),
                       m_normal_nodes.end());
}

std::vector<std::pair<int, int>> Model::nodes_by_id(const ParticleStore& p) const {
  std::vector<std::pair<int, int>> nodes;
  nodes.reserve(m_node_index.size());
  for (const int i : m_node_index)
    nodes.emplace_back(p.id[i], i);
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

void Membranes::add_forces(const std::vector<BondedEntry>& bonded, std::uint64_t bonds_version,
                           ParticleStore& p, const BoxGeometry& box, double time,
                           const std::uint8_t* owned, std::uint64_t owners_version) {
  const Key key{p.layout_version,           p.mol_version, bonds_version,
                owned ? owners_version : 0, lanes,         true};
  if (!(key == m_key)) {
    Selection all;
    all.lanes = lanes;
    all.owned = owned;
    m_key = Key{}; // a compile that throws leaves no stale model behind
    m_model.compile(bonded, all, p);
    ++counts.compiles;
    m_key = key;
  }
  m_model.shape_checks = shape_checks;
  m_model.drift_tolerance = drift_tolerance;
  m_model.step = step;
  m_model.time_step = time_step;
  m_model.defer_implicit_viscosity = defer_implicit_viscosity;
  if (!m_model.empty())
    m_model.evaluate(p, box, time, p.force.data(), p.normal.data(), nullptr, counts);
  take_viscous_counts();
}

void Membranes::take_viscous_counts() {
  counts.viscous_solves += std::exchange(m_model.viscous_solves, 0);
  counts.viscous_iterations += std::exchange(m_model.viscous_iterations, 0);
  counts.viscous_max_iterations =
      std::max(counts.viscous_max_iterations, std::exchange(m_model.viscous_max_iterations, 0));
}

void Membranes::add_deferred_viscosity(ParticleStore& p, const BoxGeometry& box) {
  m_model.add_deferred_viscosity(p, box, p.force.data());
  take_viscous_counts();
}

std::vector<CellReport> analyse(const std::vector<BondedEntry>& bonded, const Selection& select,
                                const ParticleStore& p, const BoxGeometry& box, double time,
                                Vec3* force, std::vector<std::pair<int, int>>* nodes,
                                double time_step) {
  Model model;
  model.time_step = time_step;
  PassCounts counts;
  std::vector<CellReport> reports;
  if (select.term == viscosity && time_step > 0.0) {
    // the time step's viscous force works against all the cells' membrane
    // forces (viscosity.hpp): the selected cells compiled whole, only their
    // viscous forces kept
    Selection whole = select;
    whole.term = -1;
    whole.bond_id = -1;
    model.compile(bonded, whole, p);
    model.viscous_force = force;
    model.evaluate(p, box, time, nullptr, nullptr, &reports, counts);
  } else {
    model.compile(bonded, select, p);
    model.evaluate(p, box, time, force, nullptr, &reports, counts);
  }
  if (nodes)
    *nodes = model.nodes_by_id(p);
  return reports;
}

} // namespace pyoif::membrane
