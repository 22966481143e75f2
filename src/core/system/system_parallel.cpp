// The particles over the ranks of a decomposed lattice (System::particles_spread):
// owners, the copies other ranks keep current, agreement on errors.
//
// Every rank stores every particle at the same local index (they are added
// and removed on all ranks alike by the SPMD script), so no index ever needs
// translating; what is spread is the work. The owner of a particle
// integrates it and computes its forces (membrane, bonds, contacts, walls,
// Langevin); the coupling is computed where the lattice is and its force
// sent to the owner. A rank that needs another rank's particle (its coupling
// stencil reaches the rank's subdomain, a pair contact or a bond with one of
// its particles) gets its position and velocity every step, and its normal
// after the membrane phase. At a re-sort of the cell system the owners send
// their particles to the ranks within reach (resort_spread), every rank
// builds its pairs on the grid of the full list, and the lists follow from
// what both sides of a pair see alike, so no rank has to tell another what
// it needs. Before queries, and after the particles, bonds or cuts changed,
// all copies are made current (one allgather of each rank's particles).
#include "communication/neighbour_exchange.hpp"
#include "system/system.hpp"

#include "utils/errors.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

namespace pyoif {

namespace {
/** A particle's whole state as 15 numbers: position, image, velocity,
 *  force, normal (what a rank needs to take a particle over). */
constexpr int state_numbers = 15;
void pack_state(const ParticleStore& p, std::size_t i, std::vector<double>& out) {
  const Vec3 img = p.image[i].cast<double>();
  const Vec3* fields[5] = {&p.pos[i], &img, &p.vel[i], &p.force[i], &p.normal[i]};
  for (const Vec3* v : fields)
    out.insert(out.end(), {(*v)[0], (*v)[1], (*v)[2]});
}
void unpack_state(ParticleStore& p, std::size_t i, const double* v) {
  p.pos[i] = Vec3(v[0], v[1], v[2]);
  p.image[i] = Vec3i(static_cast<int>(v[3]), static_cast<int>(v[4]), static_cast<int>(v[5]));
  p.vel[i] = Vec3(v[6], v[7], v[8]);
  p.force[i] = Vec3(v[9], v[10], v[11]);
  p.normal[i] = Vec3(v[12], v[13], v[14]);
}
} // namespace

void System::update_spread() {
  const bool spread = m_lb && m_lb->distributed();
  if (spread == m_spread.active)
    return;
  if (m_spread.active)
    synchronize(); // every copy current before the ranks go separate ways no more
  m_spread = Spread{};
  m_spread.active = spread;
  if (spread)
    m_spread.comm = Communicator(m_lb->domain().comm());
  cells.invalidate();
  membranes.invalidate();
  invalidate_forces();
}

void System::synchronize() {
  if (!m_spread.active || !m_spread.stale)
    return;
  if (owned_mask()) // (particles added or removed since: all copies current)
    gather_all_particles();
  m_spread.stale = false;
}

void System::gather_all_particles() {
  // every particle's state (pack_state) in local-index order from its
  // owner; particles without an owner (added since) are current everywhere
  // already
  constexpr int per = state_numbers;
  const int size = m_spread.comm.size(), me = m_spread.comm.rank();
  auto& p = particles;
  const std::size_t n = p.n_local();
  m_spread.owner.resize(n, -1);
  std::vector<int> counts(size, 0), displs(size, 0);
  std::vector<double> mine;
  for (std::size_t i = 0; i < n; ++i) {
    const int o = m_spread.owner[i];
    if (o < 0)
      continue;
    counts[o] += per;
    if (o == me)
      pack_state(p, i, mine);
  }
  for (int r = 1; r < size; ++r)
    displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<double> all(static_cast<std::size_t>(displs[size - 1] + counts[size - 1]));
  MPI_Allgatherv(mine.data(), static_cast<int>(mine.size()), MPI_DOUBLE, all.data(), counts.data(),
                 displs.data(), MPI_DOUBLE, m_spread.comm.comm());
  for (std::size_t i = 0; i < n; ++i) {
    const int o = m_spread.owner[i];
    if (o < 0)
      continue;
    unpack_state(p, i, all.data() + displs[o]);
    displs[o] += per;
  }
}

void System::update_topology() {
  auto& p = particles;
  if (m_spread.topology_layout == p.layout_version && m_spread.topology_mol == p.mol_version &&
      m_spread.topology_bonds == m_bonds_version)
    return;
  // The reference particle of each particle: a membrane cell's nodes go with
  // the first particle of the cell's first membrane bond (the cells are
  // keyed by the mol_id of a bond's first particle); others with themselves.
  // And the bonds whose particles can have two owners: every generic bond,
  // and the membrane bonds that join two cells (mol_ids).
  const std::size_t n = p.n_local();
  std::unordered_map<int, int> first_node_of_mol;
  m_spread.cross_bonds.clear();
  for (const BondedEntry& entry : bonded)
    std::visit(
        [&](const auto& ia) {
          using IA = std::decay_t<decltype(ia)>;
          const BondGroup& g = entry.bonds;
          for (std::size_t b = 0; b < g.size(); ++b) {
            const int* ids = g.bond(b);
            const int first = p.index(ids[0]);
            bool cross = !is_membrane_bond<IA>;
            if constexpr (is_membrane_bond<IA>)
              if (first >= 0) {
                first_node_of_mol.try_emplace(p.mol_id[first], first);
                for (int k = 1; k < g.n_particles; ++k) {
                  const int i = p.index(ids[k]);
                  cross |= i >= 0 && p.mol_id[i] != p.mol_id[first];
                }
              }
            if (!cross)
              continue;
            m_spread.cross_bonds.push_back(g.n_particles);
            for (int k = 0; k < g.n_particles; ++k)
              m_spread.cross_bonds.push_back(std::max(0, p.index(ids[k])));
          }
        },
        entry.interaction);
  m_spread.reference.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto it = first_node_of_mol.find(p.mol_id[i]);
    m_spread.reference[i] = it != first_node_of_mol.end() ? it->second : static_cast<int>(i);
  }
  m_spread.topology_layout = p.layout_version;
  m_spread.topology_mol = p.mol_version;
  m_spread.topology_bonds = m_bonds_version;
}

int System::rank_of_position(const Vec3& x) const {
  // the rank whose subdomain holds the lattice node of x (folded)
  const Vec3 f = box.folded(x);
  const Vec3i nodes = m_lb->grid();
  Vec3i g;
  for (int d = 0; d < 3; ++d)
    g[d] = std::min(std::max(static_cast<int>(std::floor(f[d] / m_lb->agrid())), 0), nodes[d] - 1);
  return m_lb->domain().owner_of(g);
}

void System::assign_owners() {
  auto& p = particles;
  const std::size_t n = p.n_local();
  const DomainGrid& grid = m_lb->domain();
  update_topology();
  m_spread.owner.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    // a cell's nodes follow its reference, looked up once per cell (the
    // reference is its own reference, and comes first in its cell)
    const int ref = m_spread.reference[i];
    m_spread.owner[i] =
        static_cast<std::size_t>(ref) < i ? m_spread.owner[ref] : rank_of_position(p.pos[ref]);
  }
  set_owned();
  m_spread.layout = p.layout_version;
  m_spread.mol = p.mol_version;
  m_spread.bonds = m_bonds_version;
  m_spread.cuts = grid.cuts();
}

const std::vector<std::pair<std::size_t, std::size_t>>& System::owned_runs() const {
  if (owned_mask())
    return m_spread.owned_runs;
  const std::size_t n = particles.n_local();
  if (n == 0)
    m_all_particles_run.clear();
  else if (m_all_particles_run.size() != 1 || m_all_particles_run[0].second != n)
    m_all_particles_run.assign(1, {0, n});
  return m_all_particles_run;
}

void System::set_owned() {
  const std::size_t n = particles.n_local();
  const int me = m_spread.comm.rank();
  std::vector<std::uint8_t>& owned = m_spread.owned;
  const std::vector<std::uint8_t> before = owned;
  owned.resize(n);
  m_spread.owned_runs.clear();
  for (std::size_t i = 0; i < n; ++i) {
    owned[i] = m_spread.owner[i] == me;
    if (!owned[i])
      continue;
    if (!m_spread.owned_runs.empty() && m_spread.owned_runs.back().second == i)
      ++m_spread.owned_runs.back().second;
    else
      m_spread.owned_runs.emplace_back(i, i + 1);
  }
  // the membranes compile this rank's cells anew only when they changed
  if (owned != before)
    ++m_spread.version;
}

void System::build_exchange_lists() {
  auto& p = particles;
  const std::size_t n = p.n_local();
  const DomainGrid& grid = m_lb->domain();
  const int me = m_spread.comm.rank(), size = m_spread.comm.size();
  const double agrid = m_lb->agrid();
  const Vec3i nodes = m_lb->grid();
  // who needs whom, from the state every rank has alike: only the lists
  // this rank sends and receives are kept (per rank, then sorted)
  std::vector<std::vector<int>> send(size), recv(size);
  auto needs = [&](int rank, int i) {
    const int o = m_spread.owner[i];
    if (o == rank)
      return;
    if (rank == me)
      recv[o].push_back(i);
    else if (o == me)
      send[rank].push_back(i);
  };
  // (1) coupling: the ranks whose subdomain the stencil can reach before
  // the next re-sort (a particle moves at most skin / 2 until then)
  const double reach = 0.5 * cells.skin;
  const auto& cuts = grid.cuts();
  std::array<std::vector<int>, 3> coords; // grid coordinates the stencil reaches, per axis
  for (std::size_t i = 0; i < n; ++i) {
    if (!m_spread.binned.empty() && !m_spread.binned[i])
      continue; // no current position here: neither this rank's nor needed by it
    for (int d = 0; d < 3; ++d) {
      coords[d].clear();
      if (grid.dims()[d] == 1) {
        coords[d].push_back(0);
        continue;
      }
      const int lo = static_cast<int>(std::floor((p.pos[i][d] - reach) / agrid - 0.5));
      const int hi = static_cast<int>(std::floor((p.pos[i][d] + reach) / agrid - 0.5)) + 1;
      for (int g = lo; g <= hi; ++g) {
        const int w = ((g % nodes[d]) + nodes[d]) % nodes[d];
        const int c = static_cast<int>(std::upper_bound(cuts[d].begin(), cuts[d].end(), w) -
                                       cuts[d].begin()) -
                      1;
        if (std::find(coords[d].begin(), coords[d].end(), c) == coords[d].end())
          coords[d].push_back(c);
      }
    }
    for (const int x : coords[0])
      for (const int y : coords[1])
        for (const int z : coords[2])
          needs(grid.rank_of(Vec3i(x, y, z)), static_cast<int>(i));
  }
  // (2) pair contacts (the pair list, built from the current state, holds
  // every pair with a particle of this rank within range + skin until the
  // next re-sort)
  for (const auto& pair : cells.pairs()) {
    const int a = pair[0], b = p.owner(static_cast<std::size_t>(pair[1]));
    needs(m_spread.owner[a], b);
    needs(m_spread.owner[b], a);
  }
  // (3) bonds that can join particles of two owners (each owner evaluates
  // the bond for its own particles)
  for (std::size_t start = 0; start < m_spread.cross_bonds.size();) {
    const int k = m_spread.cross_bonds[start];
    const int* idx = m_spread.cross_bonds.data() + start + 1;
    for (int a = 0; a < k; ++a)
      for (int b = 0; b < k; ++b)
        if (a != b && m_spread.owner[idx[a]] != m_spread.owner[idx[b]])
          needs(m_spread.owner[idx[a]], idx[b]);
    start += 1 + static_cast<std::size_t>(k);
  }
  m_spread.peers.clear();
  m_spread.current = m_spread.owned;
  for (int r = 0; r < size; ++r) {
    for (auto* list : {&send[r], &recv[r]}) {
      std::sort(list->begin(), list->end());
      list->erase(std::unique(list->begin(), list->end()), list->end());
    }
    if (send[r].empty() && recv[r].empty())
      continue;
    for (const int i : recv[r])
      m_spread.current[i] = 1;
    m_spread.peers.push_back({r, std::move(send[r]), std::move(recv[r]), {}, {}});
  }
}

void System::resort_spread() {
  // A re-sort without the gather of all particles: the owners decide, from
  // their own particles' current state, (1) the new owners (shared in one
  // allgather of the changes only), (2) the moves of particles to their new
  // owners, (3) which ranks hold each particle within reach: the rank's
  // lattice box widened by the largest cell's extent, the pair range and
  // the skin (every particle a rank's particles can meet before the next
  // re-sort, and every particle whose coupling stencil can reach its
  // subdomain). Each rank then bins what it holds current, builds its pairs
  // and lists from that, and the lists' copies are refreshed once.
  auto& p = particles;
  const std::size_t n = p.n_local();
  const DomainGrid& grid = m_lb->domain();
  const int me = m_spread.comm.rank(), size = m_spread.comm.size();
  const MPI_Comm comm = m_spread.comm.comm();
  const double agrid = m_lb->agrid();
  constexpr int per = state_numbers;
  auto pack = [&](std::vector<double>& out, std::size_t i) { pack_state(p, i, out); };
  auto unpack = [&](const double* v, std::size_t i) { unpack_state(p, i, v); };
  // (1) new owners of this rank's particles (a cell follows its reference,
  // which this rank owns too), the changes to every rank
  std::vector<int> changes; // pairs (index, new owner)
  double extent2 = 0.0;     // the largest squared distance of a node from its reference
  for (std::size_t i = 0; i < n; ++i) {
    if (!m_spread.owned[i])
      continue;
    const int ref = m_spread.reference[i];
    const int new_owner = rank_of_position(p.pos[ref]);
    extent2 = std::max(extent2, box.minimum_image(p.pos[i], p.pos[ref]).squaredNorm());
    if (new_owner != me)
      changes.insert(changes.end(), {static_cast<int>(i), new_owner});
  }
  std::vector<int> counts(size), displs(size, 0);
  const int mine = static_cast<int>(changes.size());
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (int r = 1; r < size; ++r)
    displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<int> all_changes(static_cast<std::size_t>(displs[size - 1] + counts[size - 1]));
  MPI_Allgatherv(changes.data(), mine, MPI_INT, all_changes.data(), counts.data(), displs.data(),
                 MPI_INT, comm);
  // (2) the moving particles' state to their new owners, in the order of
  // the list (both sides know it)
  std::vector<std::vector<double>> to(size), from(size);
  std::vector<std::vector<int>> arriving(size);
  for (int r = 0; r < size; ++r)
    for (int k = displs[r]; k < displs[r] + counts[r]; k += 2) {
      const int i = all_changes[k], dest = all_changes[k + 1];
      if (r == me)
        pack(to[dest], static_cast<std::size_t>(i));
      if (dest == me)
        arriving[r].push_back(i);
    }
  {
    NeighbourExchange round(comm, 83);
    for (int r = 0; r < size; ++r) {
      if (arriving[r].empty())
        continue;
      from[r].resize(per * arriving[r].size());
      round.receive(r, from[r].data(), from[r].size());
    }
    for (int r = 0; r < size; ++r)
      if (!to[r].empty())
        round.send(r, to[r].data(), to[r].size());
    round.wait();
  }
  for (int r = 0; r < size; ++r)
    for (std::size_t k = 0; k < arriving[r].size(); ++k)
      unpack(from[r].data() + per * k, static_cast<std::size_t>(arriving[r][k]));
  for (std::size_t k = 0; k < all_changes.size(); k += 2)
    m_spread.owner[all_changes[k]] = all_changes[k + 1];
  set_owned();
  // (3) each owned particle to the ranks whose widened box holds it
  double extent = std::sqrt(extent2);
  MPI_Allreduce(MPI_IN_PLACE, &extent, 1, MPI_DOUBLE, MPI_MAX, comm);
  const double margin = extent + nonbonded.max_range() + cells.skin + 2.0 * agrid;
  const Vec3& L = box.length();
  const auto& cuts = grid.cuts();
  std::array<std::vector<int>, 3> coords;
  std::vector<std::vector<double>> out(size);
  std::vector<std::vector<int>> out_index(size);
  for (std::size_t i = 0; i < n; ++i) {
    if (!m_spread.owned[i])
      continue;
    const Vec3 x = box.folded(p.pos[i]);
    for (int d = 0; d < 3; ++d) {
      coords[d].clear();
      for (int c = 0; c < grid.dims()[d]; ++c) {
        if (grid.dims()[d] == 1) {
          coords[d].push_back(c);
          break;
        }
        const double a = cuts[d][c] * agrid - margin, b = cuts[d][c + 1] * agrid + margin;
        if ((x[d] >= a && x[d] < b) || (x[d] + L[d] >= a && x[d] + L[d] < b) ||
            (x[d] - L[d] >= a && x[d] - L[d] < b))
          coords[d].push_back(c);
      }
    }
    for (const int cx : coords[0])
      for (const int cy : coords[1])
        for (const int cz : coords[2]) {
          const int r = grid.rank_of(Vec3i(cx, cy, cz));
          if (r == me)
            continue;
          out_index[r].push_back(static_cast<int>(i));
          pack(out[r], i);
        }
  }
  std::vector<int> send_counts(size), recv_counts(size);
  for (int r = 0; r < size; ++r)
    send_counts[r] = static_cast<int>(out_index[r].size());
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, comm);
  std::vector<std::vector<int>> in_index(size);
  std::vector<std::vector<double>> in(size);
  {
    // indices and states in two rounds of their own tags, in flight together
    NeighbourExchange indices(comm, 84), states(comm, 85);
    for (int r = 0; r < size; ++r) {
      if (!recv_counts[r])
        continue;
      in_index[r].resize(recv_counts[r]);
      in[r].resize(static_cast<std::size_t>(per) * recv_counts[r]);
      indices.receive(r, in_index[r].data(), in_index[r].size());
      states.receive(r, in[r].data(), in[r].size());
    }
    for (int r = 0; r < size; ++r) {
      if (!send_counts[r])
        continue;
      indices.send(r, out_index[r].data(), out_index[r].size());
      states.send(r, out[r].data(), out[r].size());
    }
    indices.wait();
    states.wait();
  }
  m_spread.binned = m_spread.owned;
  for (int r = 0; r < size; ++r)
    for (std::size_t k = 0; k < in_index[r].size(); ++k) {
      const std::size_t i = static_cast<std::size_t>(in_index[r][k]);
      unpack(in[r].data() + per * k, i);
      m_spread.binned[i] = 1;
    }
  // (4) the pairs among what this rank holds, on the cell grid of the full
  // list (the bounding box of all particles and their periodic images, and
  // their count: the same pair orientations, so the same forces and each
  // pair's energy counted once), the lists, the copies once
  const double range = nonbonded.max_range() > 0.0 ? nonbonded.max_range() + cells.skin : 0.0;
  if (range > 0.0) {
    double extremes[6];
    for (int d = 0; d < 3; ++d) {
      extremes[d] = HUGE_VAL;      // -lo, by MAX
      extremes[3 + d] = -HUGE_VAL; // hi
    }
    double images = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!m_spread.owned[i])
        continue;
      const Vec3 x = box.folded(p.pos[i]);
      double copies = 1.0;
      for (int d = 0; d < 3; ++d) {
        double lo = x[d], hi = x[d];
        int per_axis = 1;
        if (box.periodic()[d]) {
          if (x[d] < range) {
            hi = std::max(hi, x[d] + L[d]);
            ++per_axis;
          }
          if (x[d] >= L[d] - range) {
            lo = std::min(lo, x[d] - L[d]);
            ++per_axis;
          }
        }
        extremes[d] = std::min(extremes[d], lo);
        extremes[3 + d] = std::max(extremes[3 + d], hi);
        copies *= per_axis;
      }
      images += copies - 1.0;
    }
    for (int d = 0; d < 3; ++d)
      extremes[d] = -extremes[d];
    MPI_Allreduce(MPI_IN_PLACE, extremes, 6, MPI_DOUBLE, MPI_MAX, comm);
    double total = images + static_cast<double>(n);
    MPI_Allreduce(MPI_IN_PLACE, &total, 1, MPI_DOUBLE, MPI_SUM, comm);
    // (every particle is owned by exactly one rank: n counted once, as the
    // sum of the owned ones; images summed over their owners)
    total -= static_cast<double>(n) * (size - 1);
    cells.set_grid_hint({Vec3(-extremes[0], -extremes[1], -extremes[2]),
                         Vec3(extremes[3], extremes[4], extremes[5]),
                         static_cast<std::size_t>(total)});
  }
  cells.rebuild(p, box, nonbonded.max_range(), m_spread.owned.data(), m_spread.binned.data());
  build_exchange_lists();
  exchange_current(false);
}

void System::exchange_current(bool normals) {
  auto& p = particles;
  const int per = normals ? 3 : 6;
  NeighbourExchange round(m_spread.comm.comm(), 81);
  for (auto& peer : m_spread.peers) {
    peer.recv_buffer.resize(per * peer.recv.size());
    round.receive(peer.rank, peer.recv_buffer.data(), peer.recv_buffer.size());
  }
  for (auto& peer : m_spread.peers) {
    peer.send_buffer.clear();
    for (const int i : peer.send) {
      if (normals) {
        peer.send_buffer.insert(peer.send_buffer.end(),
                                {p.normal[i][0], p.normal[i][1], p.normal[i][2]});
      } else {
        peer.send_buffer.insert(peer.send_buffer.end(), {p.pos[i][0], p.pos[i][1], p.pos[i][2],
                                                         p.vel[i][0], p.vel[i][1], p.vel[i][2]});
      }
    }
    round.send(peer.rank, peer.send_buffer.data(), peer.send_buffer.size());
  }
  round.wait();
  for (auto& peer : m_spread.peers)
    for (std::size_t k = 0; k < peer.recv.size(); ++k) {
      const double* v = peer.recv_buffer.data() + per * k;
      const int i = peer.recv[k];
      if (normals) {
        p.normal[i] = Vec3(v[0], v[1], v[2]);
      } else {
        p.pos[i] = Vec3(v[0], v[1], v[2]);
        p.vel[i] = Vec3(v[3], v[4], v[5]);
      }
    }
}

void System::share_coupling_forces(std::vector<Vec3>& force, const std::vector<int>& giver,
                                   const std::vector<std::uint32_t>* listed) {
  // Each rank sends, for every particle of the peer that it keeps current,
  // the force it computed (zero where it did not); the owner takes the value
  // of the particle's giver: a copy, no sum. Fixed sizes (the lists), so a
  // rank whose computation failed still sends its share.
  const int me = m_spread.comm.rank();
  NeighbourExchange round(m_spread.comm.comm(), 82);
  for (auto& peer : m_spread.peers) {
    peer.recv_buffer.resize(3 * peer.send.size());
    round.receive(peer.rank, peer.recv_buffer.data(), peer.recv_buffer.size());
  }
  for (auto& peer : m_spread.peers) {
    peer.send_buffer.clear();
    for (const int i : peer.recv)
      peer.send_buffer.insert(peer.send_buffer.end(), {force[i][0], force[i][1], force[i][2]});
    round.send(peer.rank, peer.send_buffer.data(), peer.send_buffer.size());
  }
  round.wait();
  const std::vector<std::uint8_t>& owned = m_spread.owned;
  auto keep_own = [&](std::size_t i) {
    if (!owned[i] || giver[i] != me)
      force[i].setZero();
  };
  if (listed) // the others' forces are zero already
    for (const std::uint32_t i : *listed)
      keep_own(i);
  else
    for (std::size_t i = 0; i < force.size(); ++i)
      keep_own(i);
  for (auto& peer : m_spread.peers)
    for (std::size_t k = 0; k < peer.send.size(); ++k) {
      const int i = peer.send[k];
      if (giver[i] == peer.rank)
        force[i] =
            Vec3(peer.recv_buffer[3 * k], peer.recv_buffer[3 * k + 1], peer.recv_buffer[3 * k + 2]);
    }
}

int System::agree(int code) const {
  if (!m_spread.active)
    return code;
  MPI_Allreduce(MPI_IN_PLACE, &code, 1, MPI_INT, MPI_MAX, m_spread.comm.comm());
  return code;
}

void System::raise_agreed(const std::exception_ptr& local) const {
  // with no particles every phase's input is the same on every rank (the
  // fluid is read only at particles): a phase fails on all ranks or on none
  if (!m_spread.active || particles.n_local() == 0) {
    if (local)
      std::rethrow_exception(local);
    return;
  }
  int failing = local ? m_spread.comm.rank() : m_spread.comm.size();
  MPI_Allreduce(MPI_IN_PLACE, &failing, 1, MPI_INT, MPI_MIN, m_spread.comm.comm());
  if (failing == m_spread.comm.size())
    return;
  // the lowest failing rank's message and kind, raised on every rank
  std::string message;
  int kind = 0; // 0 SimulationInstability, 1 InputError, 2 other
  if (failing == m_spread.comm.rank()) {
    try {
      std::rethrow_exception(local);
    } catch (const SimulationInstability& e) {
      message = e.pack();
    } catch (const InputError& e) {
      message = e.what();
      kind = 1;
    } catch (const std::exception& e) {
      message = e.what();
      kind = 2;
    }
  }
  int length = static_cast<int>(message.size());
  MPI_Bcast(&kind, 1, MPI_INT, failing, m_spread.comm.comm());
  MPI_Bcast(&length, 1, MPI_INT, failing, m_spread.comm.comm());
  message.resize(static_cast<std::size_t>(length));
  MPI_Bcast(message.data(), length, MPI_CHAR, failing, m_spread.comm.comm());
  if (kind == 0)
    throw SimulationInstability::unpack(message);
  if (kind == 1)
    throw InputError(message);
  throw std::runtime_error(message);
}

} // namespace pyoif
