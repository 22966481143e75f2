#include "lb/lb_coupling.hpp"

#include "utils/errors.hpp"
#include "utils/random.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>

namespace pyoif::lb {

namespace {

/** i folded into [0, n): one add or subtract for the usual case (positions
 *  are folded at every re-sort and move less than the skin in between). */
inline int wrap_node(int i, int n) {
  if (i < 0)
    i += n;
  else if (i >= n)
    i -= n;
  if (static_cast<unsigned>(i) >= static_cast<unsigned>(n)) // far outside the box
    i = ((i % n) + n) % n;
  return i;
}

using CompactStencil = CouplingStencil;

[[noreturn]] __attribute__((noinline, cold)) void throw_bad_position(const Vec3& pos) {
  throw SimulationInstability(
      "particle_nan", "lattice-Boltzmann coupling: particle position (" + std::to_string(pos[0]) +
                          ", " + std::to_string(pos[1]) + ", " + std::to_string(pos[2]) +
                          ") is not finite or far outside the box");
}

/** Where this rank's subdomain lies, for the stencils: on an axis the
 *  decomposition does not split, the stencil wraps round the box onto this
 *  rank's own nodes (as on one rank); on a split axis it is placed in this
 *  rank's padded coordinates, where a stencil that touches the subdomain
 *  lies within the ghost layer. */
struct StencilFrame {
  int lower[3], local[3], global[3];
  bool split[3];
  bool any_split;
  explicit StencilFrame(const LBFluid& fluid) {
    any_split = false;
    for (int d = 0; d < 3; ++d) {
      lower[d] = fluid.local_origin()[d];
      local[d] = fluid.local_grid()[d];
      global[d] = fluid.grid()[d];
      split[d] = local[d] != global[d];
      any_split |= split[d];
    }
  }
};

/** A stencil's key when no node of it is this rank's (another rank couples
 *  that particle): this bit and the global index of the first node (so that
 *  the key still changes when the stencil moves). */
constexpr std::uint64_t not_here_bit = std::uint64_t{1} << 63;
inline bool not_here(const CompactStencil& s) {
  return (s.key & not_here_bit) != 0;
}

/** s = the stencil of pos; base_owned: its first node is this rank's (this
 *  rank gives the particle its force); base: that node's global coordinates.
 *  (Written in place: a stencil built aside and copied into the ledger is
 *  read back as one 32-byte load of four fresh 8-byte stores, a store-
 *  forwarding stall per particle.) */
inline void compact_stencil(const LBFluid& fluid, const StencilFrame& frame, const Vec3& pos,
                            bool& base_owned, Vec3i& base, CompactStencil& s) {
  const double inv_agrid = 1.0 / fluid.agrid();
  int lo[3];
  std::uint64_t wraps = 0;
  base_owned = true;
  for (int d = 0; d < 3; ++d) {
    const double x = pos[d] * inv_agrid - 0.5;
    if (!(std::abs(x) < 1e9)) // NaN or flown away: no index to compute
      throw_bad_position(pos);
    const double fl = std::floor(x);
    s.frac[d] = x - fl;
    const int n = frame.global[d];
    base[d] = wrap_node(static_cast<int>(fl), n);
    if (!frame.split[d]) {
      lo[d] = base[d];
      wraps |= std::uint64_t{lo[d] + 1 >= n} << d;
      continue;
    }
    // local coordinate of the first node, periodically in [-1, n - 1)
    const int l = wrap_node(base[d] - frame.lower[d] + 1, n) - 1;
    base_owned &= l >= 0 && l <= frame.local[d] - 1;
    lo[d] = l;
  }
  for (int d = 0; d < 3; ++d)
    if (lo[d] > frame.local[d] - 1) { // no node of the stencil is this rank's
      s.key = not_here_bit |
              ((static_cast<std::uint64_t>(base[2]) * frame.global[1] + base[1]) * frame.global[0] +
               base[0]);
      return;
    }
  s.key = (std::uint64_t{fluid.padded_index_in_box(lo[0], lo[1], lo[2])} << 3) | wraps;
}

} // namespace

Vec3 interpolated_velocity(LBFluid& fluid, const BoxGeometry& box, const Vec3& pos) {
  // the 8 nodes around pos and their trilinear weights; node (i, j, k) sits
  // at ((i, j, k) + 1/2) agrid. Decomposed: computed by the rank of the
  // first node, summed over the ranks (collective).
  fluid.refresh_ghost_velocities(); // (requires the lattice flagged)
  const StencilFrame frame(fluid);
  bool base_owned = false;
  Vec3i base;
  CompactStencil s;
  compact_stencil(fluid, frame, box.folded(pos), base_owned, base, s);
  Vec3 u = Vec3::Zero();
  if (base_owned) {
    const auto steps = fluid.stencil_steps();
    for (int m = 0; m < 8; ++m)
      u += s.weight(m) * fluid.coupling_velocity(steps.node(s, m));
  }
  if (fluid.distributed())
    MPI_Allreduce(MPI_IN_PLACE, u.data(), 3, MPI_DOUBLE, MPI_SUM, fluid.domain().comm());
  return u;
}

[[noreturn]] __attribute__((noinline, cold)) void throw_outside(const ParticleStore& p,
                                                                const BoxGeometry& box) {
  for (std::size_t i = 0; i < p.n_local(); ++i)
    for (int d = 0; d < 3; ++d)
      if (!box.periodic()[d] && !(p.pos[i][d] >= 0.0 && p.pos[i][d] <= box.length()[d]))
        throw SimulationInstability(
            "outside_lattice",
            "lattice-Boltzmann coupling: particle " + std::to_string(p.id[i]) + " at " +
                format_number(p.pos[i][d]) + " along the non-periodic axis " + std::to_string(d) +
                " left the box [0, " + format_number(box.length()[d]) +
                "]; the fluid has no nodes there (it would couple to the far side). Walls "
                "(constraints) keep particles inside; check the node-wall interaction and the "
                "time step")
            .at_particle(p.id[i])
            .with_value(p.pos[i][d]);
  throw std::logic_error("throw_outside: no particle outside");
}

namespace {

/** The indices of the particles marked in `current` (the particles this rank
 *  keeps current on a decomposed lattice), ascending, kept in the ledger
 *  while the mask stays (it changes at re-sorts). True when the list was
 *  made anew: then couple_on_this_rank clears the entries of the particles
 *  not listed, once, so that its passes need to look at the listed ones
 *  only. */
bool list_current(CouplingLedger& ledger, const std::uint8_t* current, std::size_t n) {
  if (ledger.current_mask.size() == n &&
      std::equal(current, current + n, ledger.current_mask.begin()))
    return false;
  ledger.current_mask.assign(current, current + n);
  ledger.current_list.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (current[i])
      ledger.current_list.push_back(static_cast<std::uint32_t>(i));
  return true;
}

/** The coupling of the particles this rank computes (all, on one rank):
 *  their forces into the ledger's coupling_force (zero where not computed),
 *  their deposits into the fluid's force field. */
void couple_on_this_rank(LBFluid& fluid, CouplingLedger& ledger, ParticleStore& particles,
                         const BoxGeometry& box, const CouplingParams& params, std::uint64_t step,
                         double time_step, const StencilFrame& frame,
                         const std::vector<std::uint32_t>* listed, bool list_changed) {

  // see CouplingLedger: a new MD step deposits F dt; a first or a
  // repeated computation for the same step deposits F dt / 2 after taking
  // back the in-flight half of the previous computation of this step
  auto& p = particles;
  const std::size_t n = p.n_local();
  // the particles to look at: all, or (decomposed) those this rank keeps
  // current, which is the cheaper pass at 2 ranks already (the others'
  // entries were cleared when the list was made)
  const std::size_t n_looked = listed ? listed->size() : n;
  const std::uint32_t* const looked = listed ? listed->data() : nullptr;
  auto particle = [looked](std::size_t k) -> std::size_t { return looked ? looked[k] : k; };
  // On a non-periodic axis the lattice ends at the box: a particle outside
  // it would take its stencil from the far side (wrapped indices). Checked
  // before anything changes, so that the particle can be moved back and the
  // run go on (a pass cut short would leave the ledger half updated).
  if (!box.periodic()[0] || !box.periodic()[1] || !box.periodic()[2]) {
    const Vec3 lower(box.periodic()[0] ? -HUGE_VAL : 0.0, box.periodic()[1] ? -HUGE_VAL : 0.0,
                     box.periodic()[2] ? -HUGE_VAL : 0.0);
    const Vec3 upper(box.periodic()[0] ? HUGE_VAL : box.length()[0],
                     box.periodic()[1] ? HUGE_VAL : box.length()[1],
                     box.periodic()[2] ? HUGE_VAL : box.length()[2]);
    bool outside = false;
    for (std::size_t k = 0; k < n_looked; ++k) {
      const std::size_t i = particle(k);
      outside |=
          !((p.pos[i].array() >= lower.array()).all() && (p.pos[i].array() <= upper.array()).all());
    }
    if (outside)
      throw_outside(p, box);
  }
  const bool split = frame.any_split;
  auto mine = [&](std::size_t node) { return !split || !fluid.is_stencil_ghost(node); };
  const bool same_step = ledger.any && ledger.step == step;
  const double fraction = (ledger.any && !same_step) ? 1.0 : 0.5;
  // the force field is switched on (and read by the next update) only when
  // something is deposited: a fluid without particles keeps the plain kernel
  if (n > 0 || (same_step && !ledger.last_impulse.empty()))
    fluid.open_impulse_field();
  const double scale = fluid.impulse_scale();
  const auto steps = fluid.stencil_steps();
  if (same_step) // the last pass's stencils are still in the ledger
    for (std::size_t i = 0; i < ledger.last_impulse.size(); ++i) {
      const CompactStencil& s = ledger.stencils[i];
      if (not_here(s))
        continue;
      const Vec3 retract = -0.5 * scale * ledger.last_impulse[i];
      for (int m = 0; m < 8; ++m) {
        const std::size_t node = steps.node(s, m);
        if (mine(node))
          fluid.add_field_impulse(node, s.weight(m) * retract);
      }
    }
  ledger.any = true;
  ledger.step = step;
  ledger.last_impulse.resize(n);
  // Four passes: (1) stencils, numbering the lattice nodes they need in the
  // order the particles first touch them; (2) those nodes' velocities; (3)
  // per particle the force, its impulse spread over the nodes' compact
  // entries; (4) the impulses into the fluid's force field. The numbering
  // keeps the entries a cell's nodes use together (a cell's particles are
  // contiguous), so pass 3 runs from L1 instead of jumping through
  // lattice-ordered arrays. It is kept from step to step: a particle whose
  // stencil did not move (most, as they move a small fraction of agrid per
  // step) keeps its entries, one that moved looks up or appends its nodes.
  // The set is rebuilt from scratch (dropping nodes no longer used, nodes
  // listed in memory order again) every `renumber_interval` steps and when
  // the particles change. Every entry accumulates the same deposits in the
  // same particle order either way, so the results do not depend on it.
  constexpr std::uint64_t renumber_interval = 64;
  const std::size_t n_words = (fluid.n_padded_slots() + 63) / 64;
  if (ledger.needed.size() != n_words) {
    ledger.needed.assign(n_words, 0);
    ledger.compact.assign(fluid.n_padded_slots(), 0);
    ledger.n_nodes = 0;
    ledger.stencils.clear();
  }
  std::uint64_t* const needed = ledger.needed.data();
  std::uint32_t* const compact = ledger.compact.data();
  const bool renumber = ledger.stencils.size() != n || ledger.layout_version != p.layout_version ||
                        step < ledger.numbered_step ||
                        step - ledger.numbered_step >= renumber_interval;
  if (renumber) {
    for (std::size_t j = 0; j < ledger.n_nodes; ++j)
      needed[ledger.node[j] >> 6] = 0;
    ledger.n_nodes = 0;
    ledger.stencils.resize(n);
    ledger.stencil_entries.resize(8 * n);
    ledger.layout_version = p.layout_version;
    ledger.numbered_step = step;
  }
  // The particles not listed: no stencil here, no giver, no force, nothing
  // deposited. Set when the list changes (after the retract pass above,
  // which takes back the last computation's deposits with its stencils) and
  // when the stencils were made anew; the passes below skip them.
  ledger.coupling_force.resize(n);
  if (split && ledger.giver.size() != n)
    ledger.giver.assign(n, -1);
  if (looked && (list_changed || renumber))
    for (std::size_t i = 0; i < n; ++i)
      if (!ledger.current_mask[i]) {
        ledger.stencils[i].key = not_here_bit;
        if (split)
          ledger.giver[i] = -1;
        ledger.coupling_force[i].setZero();
        ledger.last_impulse[i].setZero();
      }
  CompactStencil* const stencils = ledger.stencils.data();
  std::uint32_t* const entries = ledger.stencil_entries.data();
  const std::size_t n_listed = ledger.n_nodes;
  std::uint32_t n_nodes = static_cast<std::uint32_t>(n_listed);
  if (ledger.node.size() < n_listed + 8 * n + 1) // room for every node to be new
    ledger.node.resize(n_listed + 8 * n + 1);
  std::size_t* node_list = ledger.node.data();
  // the rank that gives each particle its force (that of its stencil's
  // first node): looked up when the stencil moved, as the key tells
  std::vector<int>& giver = ledger.giver;
  for (std::size_t k = 0; k < n_looked; ++k) {
    const std::size_t i = particle(k);
    bool base_owned;
    Vec3i base;
    CompactStencil& s = stencils[i];
    const std::uint64_t old_key = s.key;
    compact_stencil(fluid, frame, p.pos[i], base_owned, base, s);
    const bool moved = renumber || s.key != old_key;
    if (split && (moved || giver[i] < 0))
      giver[i] = fluid.domain().owner_of(base);
    if (!moved || not_here(s))
      continue;
    for (int m = 0; m < 8; ++m) {
      const std::size_t node = steps.node(s, m);
      // branch-free: whether a node is new is as good as random
      const std::uint64_t word = needed[node >> 6], bit = std::uint64_t{1} << (node & 63);
      const bool is_new = !(word & bit);
      needed[node >> 6] = word | bit;
      const std::uint32_t entry = is_new ? n_nodes : compact[node];
      compact[node] = entry;
      node_list[n_nodes] = node; // kept only if new
      n_nodes += is_new;
      entries[8 * i + m] = entry;
    }
  }
  // after a renumbering the list is rewritten in memory order (the velocity
  // pass then reads the 19 population streams forwards); otherwise new
  // nodes were appended in the order of their entries
  ledger.n_nodes = n_nodes;
  if (renumber) {
    std::size_t j = 0;
    for (std::size_t word = 0; word < n_words; ++word)
      for (std::uint64_t bits = needed[word]; bits; bits &= bits - 1)
        node_list[j++] = 64 * word + static_cast<std::size_t>(__builtin_ctzll(bits));
  }
  fluid.velocities_at(ledger);
  auto* const state = ledger.node_coupling.data();
  const double noise =
      params.kT > 0.0 ? std::sqrt(2.0 * params.gamma * params.kT / time_step) : 0.0;
  random::Key key{params.seed, static_cast<std::uint64_t>(random::Stream::lb_coupling), step, 0};
  std::vector<Vec3>& coupling_force = ledger.coupling_force;
  for (std::size_t q = 0; q < n_looked; ++q) {
    const std::size_t i = particle(q);
    const CompactStencil& s = stencils[i];
    if (not_here(s)) {
      coupling_force[i].setZero();
      ledger.last_impulse[i].setZero();
      continue;
    }
    const std::uint32_t* k = entries + 8 * i;
    double weight[8];
    Vec3 u = Vec3::Zero();
    for (int m = 0; m < 8; ++m) {
      weight[m] = s.weight(m);
      u += weight[m] * state[k[m]].velocity;
    }
    Vec3 f = params.gamma * (u - p.vel[i]);
    if (noise > 0.0) {
      key.key = static_cast<std::uint64_t>(p.id[i]);
      for (int d = 0; d < 3; ++d)
        f[d] += noise * random::normal(key, d);
    }
    coupling_force[i] = f;
    // the fluid gets -F time_step of momentum per MD step, applied at its
    // next update (what a recomputation of this step takes back half of)
    const Vec3 impulse = -time_step * f;
    ledger.last_impulse[i] = impulse;
    const Vec3 spread = (scale * fraction) * impulse;
    for (int m = 0; m < 8; ++m)
      state[k[m]].impulse += weight[m] * spread;
  }
  // the field is the size of the lattice and out of cache by now, and the
  // entries are read out of their order: both are requested a few nodes
  // ahead (the list is mostly in memory order, but with gaps the hardware
  // prefetcher does not follow)
  constexpr std::size_t ahead = 8;
  for (std::size_t j = 0; j < n_nodes; ++j) {
    if (j + ahead < n_nodes) {
      const std::size_t later = node_list[j + ahead];
      fluid.prefetch_field(later);
      __builtin_prefetch(&state[compact[later]].impulse, 0, 3);
    }
    const std::size_t node = node_list[j];
    if (mine(node)) // a ghost's deposit is its owner's (who made the same)
      fluid.add_field_impulse(node, state[compact[node]].impulse);
  }
}

} // namespace

void couple_particles(LBFluid& fluid, CouplingLedger& ledger, ParticleStore& particles,
                      const BoxGeometry& box, const CouplingParams& params, std::uint64_t step,
                      double time_step, const CouplingDistribution* distribution) {
  if (params.gamma <= 0.0)
    return;
  fluid.require_flagged("the particle coupling"); // the flags and cuts the stencils use
  // Decomposed lattice: each rank couples the particles whose stencils
  // touch its subdomain, in the same order as one rank would, deposits on
  // its own nodes only, and the rank of a stencil's first node gives the
  // particle its force (a copy of that rank's value: exact). So every node
  // receives the serial deposits in the serial order, and every particle the
  // serial force, bit for bit. A rank that fails before its ghost-layer
  // velocities are sent sends none (its neighbours do not wait in vain).
  const StencilFrame frame(fluid);
  const bool split = frame.any_split;
  // records of another lattice layout (a repartition) hold stale indices
  if (ledger.lattice_generation != fluid.layout_generation()) {
    ledger = CouplingLedger{};
    ledger.lattice_generation = fluid.layout_generation();
  }
  fluid.note_coupling(); // (every rank: the load balance stops moving the cuts alike)
  // the ghost-layer velocities come from their owners in the velocity pass
  // (no particles, no stencil reads them: every rank stores every particle,
  // so all ranks skip that exchange alike)
  ledger.ghosts_pending = split && particles.n_local() > 0;
  const std::uint8_t* const current = distribution ? distribution->current : nullptr;
  auto& p = particles;
  const std::size_t n = p.n_local();
  const bool distributed = distribution && distribution->share;
  if (split && !distributed) // (System always passes it with a split lattice)
    throw std::logic_error("couple_particles: a split lattice needs a CouplingDistribution");
  const bool list_changed = current && list_current(ledger, current, n);
  const std::vector<std::uint32_t>* listed = current ? &ledger.current_list : nullptr;
  try {
    couple_on_this_rank(fluid, ledger, p, box, params, step, time_step, frame, listed,
                        list_changed);
  } catch (...) {
    if (ledger.ghosts_pending) // the neighbours wait for this rank's ghost velocities
      fluid.exchange_coupling_ghosts(ledger, false);
    if (distributed && n > 0) { // the other ranks wait for this one's part of the exchange
      ledger.coupling_force.assign(n, Vec3::Zero());
      ledger.giver.assign(n, -1);
      distribution->share(ledger.coupling_force, ledger.giver, nullptr);
      ledger.current_mask.clear(); // the list is made anew (and the entries cleared) next time
    }
    throw;
  }
  std::vector<Vec3>& coupling_force = ledger.coupling_force;
  // (no particles: every rank stores every particle, so all ranks skip the
  // exchange alike, as the ghost velocities' above)
  if (split && n > 0) {
    const auto start = std::chrono::steady_clock::now();
    distribution->share(coupling_force, ledger.giver, listed);
    fluid.add_coupling_exchange_seconds(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  // in flight: half of this step's impulses, of the particles this rank
  // integrates (summed over the ranks where they are spread; the unlisted
  // particles' forces are zero)
  Vec3 impulse_sum = Vec3::Zero();
  const std::size_t n_looked = listed ? listed->size() : n;
  for (std::size_t k = 0; k < n_looked; ++k) {
    const std::size_t i = listed ? (*listed)[k] : k;
    p.force[i] += coupling_force[i];
    impulse_sum += -time_step * coupling_force[i];
  }
  ledger.in_flight = 0.5 * impulse_sum;
  ledger.in_flight_partial = distributed;
}

Vec3 CouplingLedger::in_flight_momentum(const LBFluid& fluid) const {
  if (lattice_generation != fluid.layout_generation())
    return Vec3::Zero(); // records of another layout: reset at the next pass, nothing in flight
  Vec3 p = in_flight;
  // every rank's share, or known whole on every rank (in_flight_partial is
  // alike on every rank: the System passes a distribution on every rank)
  if (fluid.distributed() && in_flight_partial)
    MPI_Allreduce(MPI_IN_PLACE, p.data(), 3, MPI_DOUBLE, MPI_SUM, fluid.domain().comm());
  return p;
}

} // namespace pyoif::lb
