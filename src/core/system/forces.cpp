// Force calculation of one step (architecture data flow steps 1-5).
#include "interactions/bonded/bond_loop.hpp"
#include "system/system.hpp"
#include "utils/phase_clock.hpp"
#include "utils/random.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <type_traits>

namespace pyoif {

void System::prepare_step(int moved) {
  if (!m_spread.active) {
    if (moved < 0 ? cells.needs_rebuild(particles, time) : moved > 0)
      cells.rebuild(particles, box, nonbonded.max_range());
    else
      cells.update_ghosts(particles, box);
    return;
  }
  // the cuts the owners follow: flagged by prepare() (a flagging may move them)
  m_lb->require_flagged("sharing the particles over the ranks");
  // Particles spread over the ranks: every rank tests its own (moved: 1
  // beyond the skin, 0 not, -1 test here, -3 too fast a step), all agree
  // on the largest code: 0 the copies are refreshed; 1 all copies made
  // current, re-sort, owners anew; 2 (runaway) and 3 (too fast) all copies
  // current, then every rank raises the error of the serial code.
  auto& p = particles;
  const std::size_t n = p.n_local();
  int code = moved == -3 ? 3 : moved > 0 ? 1 : 0;
  const bool assigned = m_spread.layout == p.layout_version && m_spread.owner.size() == n &&
                        m_spread.mol == p.mol_version && m_spread.bonds == m_bonds_version &&
                        m_spread.cuts == m_lb->domain().cuts();
  if (!assigned)
    code = std::max(code, 1);
  if (moved == -1) {
    const Vec3* x0 = cells.displacement_reference(n);
    if (!x0)
      code = std::max(code, 1);
    const double limit2 = cells.displacement_limit2();
    for (std::size_t i = 0; i < n; ++i) {
      if (assigned && !m_spread.owned[i])
        continue;
      if (cells.runaway(p.pos[i]))
        code = std::max(code, 2);
      else if (x0 && (p.pos[i] - x0[i]).squaredNorm() > limit2)
        code = std::max(code, 1);
    }
  }
  // No particles at all (a fluid alone, e.g. while the flow develops before
  // the cells are seeded): every rank stores every particle, so every rank
  // knows this alike and reaches the same code; there is nothing to agree
  // on and no copy to refresh, and the step is the lattice update alone
  const bool none = n == 0;
  code = none ? code : agree(code);
  if (code == 0) {
    if (!none)
      exchange_current(false);
    cells.update_ghosts(p, box);
    return;
  }
  if (code == 1 && assigned) {
    // the usual re-sort: particles moved, nothing else changed
    m_spread.stale = true; // copies out of reach stay out of date
    resort_spread();
    return;
  }
  // the owners' state to every rank (their assignment holds while the
  // particles' layout does, whatever else changed since)
  if (m_spread.layout == p.layout_version && m_spread.owner.size() == n)
    gather_all_particles();
  if (code == 3)
    report_fast_particle(m_time_step, step_count);
  if (code == 2)
    cells.needs_rebuild(p, time); // names the runaway particle
  assign_owners();
  m_spread.binned.clear(); // every copy current
  cells.rebuild(p, box, nonbonded.max_range(), m_spread.owned.data());
  build_exchange_lists();
}

void System::add_membrane_forces(Energies* e) {
  membranes.shape_checks = m_checks_due && !e;
  membranes.step = static_cast<long long>(step_count);
  membranes.time_step = m_time_step; // the viscosity's implicit solve over one step
  // the time step solves it after every other force (force_loop); energies
  // and analysis leave it to the pass (no coupling there)
  membranes.defer_implicit_viscosity = !e;
  membranes.add_forces(bonded, m_bonds_version, particles, box, time, owned_mask(),
                       m_spread.version);
  if (!e)
    return;
  // energies per bonded interaction: each one's bonds compiled alone and
  // evaluated by the same driver (analysis, not the time step)
  for (std::size_t bond_id = 0; bond_id < bonded.size(); ++bond_id)
    std::visit(
        [&](const auto& ia) {
          using IA = std::decay_t<decltype(ia)>;
          if constexpr (is_membrane_bond<IA>) {
            membrane::Selection select;
            select.bond_id = static_cast<int>(bond_id);
            select.owned = owned_mask(); // each cell's energy on one rank
            double energy = 0.0;
            for (const auto& cell :
                 membrane::analyse(bonded, select, particles, box, time, nullptr))
              for (const double term : cell.energy)
                energy += term;
            e->bonded += energy;
            e->bonded_by_id[static_cast<int>(bond_id)] += energy;
          }
        },
        bonded[bond_id].interaction);
}

void System::add_bonded_forces(Energies* e) {
  auto& p = particles;
  for (std::size_t bond_id = 0; bond_id < bonded.size(); ++bond_id) {
    BondedEntry& entry = bonded[bond_id];
    std::visit(
        [&](const auto& ia) {
          using IA = std::decay_t<decltype(ia)>;
          if constexpr (!is_membrane_bond<IA>) {
            double energy_sum = 0.0;
            const std::uint8_t* own = owned_mask();
            for_each_bond(
                ia, entry.bonds, p, box, time,
                [&](const auto& idx, const auto& f, double energy, const auto&) {
                  // spread: each owner its own particles' forces, the
                  // energy once (the first particle's owner)
                  for (std::size_t k = 0; k < idx.size(); ++k)
                    if (!own || own[idx[k]])
                      p.force[idx[k]] += f[k];
                  if (!own || own[idx[0]])
                    energy_sum += energy;
                },
                own);
            if (e) {
              e->bonded += energy_sum;
              e->bonded_by_id[static_cast<int>(bond_id)] += energy_sum;
            }
          }
        },
        entry.interaction);
  }
}

void System::add_nonbonded_forces(Energies* e) {
  auto& p = particles;
  const std::size_t n_local = p.n_local();
  double energy = 0.0;
  PairContext c;
  // spread: a pair of particles of two ranks is computed by both, each for
  // its own particle (the same value, so a particle's sum is the serial one)
  const std::uint8_t* own = owned_mask();
  const bool crossing_check = m_checks_due && !e;
  for (const auto& pair : cells.pairs()) {
    const int a = pair[0], b = pair[1];
    const int owner_b = p.owner(b);
    if (own && !own[a] && !own[owner_b])
      continue;
    const PairParams* params = nonbonded.find(p.type[a], p.type[owner_b]);
    if (!params)
      continue;
    c.d = p.pos[a] - p.position(b);
    const double dist2 = c.d.squaredNorm();
    if (dist2 >= params->range * params->range)
      continue;
    c.dist = std::sqrt(dist2);
    c.mol_i = p.mol_id[a];
    c.mol_j = p.mol_id[owner_b];
    c.normal_i = p.normal[a];
    c.normal_j = p.normal[owner_b];
    if (crossing_check && c.mol_i != c.mol_j)
      check_membrane_crossing(c, p.id[a], p.id[owner_b]);
    double pair_energy = 0.0;
    const Vec3 f = pair_force(*params, c, e ? &pair_energy : nullptr);
    if (!own || own[a]) {
      energy += pair_energy;
      p.force[a] += f;
    }
    if (own && !own[owner_b])
      continue;
    if (static_cast<std::size_t>(b) < n_local)
      p.force[b] -= f;
    else
      p.ghost_force[b - n_local] -= f;
  }
  cells.collect_ghost_forces(p);
  if (e)
    e->non_bonded += energy;
}

void System::check_membrane_crossing(const PairContext& c, int id_i, int id_j) const {
  // Two membrane nodes of different cells, each behind the other's surface
  // (x_i - x_j) . n_j < 0 and (x_j - x_i) . n_i < 0, with normals more than
  // 60 degrees apart (|n_i - n_j| > 1; nearly parallel normals, at the rim
  // of a contact, say nothing of the sides): the membranes have passed
  // through each other. The contact model pulls a crossed pair back
  // (membrane_collision.hpp), but a crossing means it was too weak.
  // the signs first (most pairs face each other): no square roots for them
  const double behind_j = -c.d.dot(c.normal_j), behind_i = c.d.dot(c.normal_i);
  if (!(behind_j > 0.0 && behind_i > 0.0))
    return;
  const double ni = c.normal_i.norm(), nj = c.normal_j.norm();
  const double inside_j = behind_j / nj, inside_i = behind_i / ni;
  if (!((c.normal_i / ni - c.normal_j / nj).squaredNorm() > 1.0))
    return;
  std::ostringstream msg;
  msg << "membranes crossed: node " << id_i << " of the cell with mol_id " << c.mol_i << " is "
      << inside_j << " inside the membrane of the cell with mol_id " << c.mol_j << " (its node "
      << id_j << " likewise " << inside_i << " inside the first) at time " << time
      << ". The cell-cell contact did not hold: with membrane_collision raise its a or cutoff "
         "(or use hard_contact, oif.set_contacts); hard_contact's offset covers the triangles "
         "of the relaxed mesh, and a membrane stretched well beyond them can let a node "
         "through: lower the flow or raise the offset; or lower the time step "
         "(system.cell_checks = False lets cells pass)";
  throw SimulationInstability("membrane_crossing", msg.str())
      .at_particle(id_i)
      .in_cell(c.mol_i)
      .at_time(time)
      .with_value(inside_j);
}

void System::rethrow_pair_error(const SimulationInstability& e, int id_i, int id_j,
                                const PairContext& c, const std::string& wall) const {
  std::ostringstream msg;
  msg << "particle " << id_i << " (cell mol_id " << c.mol_i << ") and ";
  if (c.wall)
    msg << "the " << wall << " constraint";
  else
    msg << "particle " << id_j << " (cell mol_id " << c.mol_j << ")";
  msg << " at time " << time << ": " << e.what();
  throw e.with_message(msg.str()).at_particle(id_i).in_cell(c.mol_i).at_time(time);
}

void System::name_contact_overrun(const SimulationInstability& error) const {
  // the closest hard_contact pair at or below its guard gap: the one whose
  // force threw (the pair loop stops at the first, and nothing moved since)
  const auto& p = particles;
  PairContext c;
  double worst = HUGE_VAL;
  int best_i = -1, best_j = -1;
  for (const auto& pair : cells.pairs()) {
    const int a = pair[0], b = pair[1], owner_b = p.owner(b);
    const PairParams* params = nonbonded.find(p.type[a], p.type[owner_b]);
    if (!params || p.mol_id[a] == p.mol_id[owner_b])
      continue;
    const auto& hc = params->get<HardContact>();
    if (!hc.active())
      continue;
    const double h = (p.pos[a] - p.position(b)).norm() - hc.offset;
    if ((h <= hc.guard_gap || h <= 0.0) && h - hc.guard_gap < worst) {
      worst = h - hc.guard_gap;
      best_i = a;
      best_j = owner_b;
    }
  }
  if (best_i < 0)
    return; // not found: the error goes on as it is
  c.wall = false;
  c.mol_i = p.mol_id[best_i];
  c.mol_j = p.mol_id[best_j];
  rethrow_pair_error(error, p.id[best_i], p.id[best_j], c, "");
}

void System::update_contact_guards() {
  const int n_types = nonbonded.n_types();
  bool any = false;
  for (int t1 = 0; t1 < n_types && !any; ++t1)
    for (int t2 = 0; t2 < n_types && !any; ++t2)
      any = nonbonded.entry_or_default(t1, t2).get<HardContact>().active();
  if (!any)
    return;
  // the lightest particle of each type over all ranks (as the largest -mass)
  std::vector<double> lightest(n_types, -HUGE_VAL);
  const auto& p = particles;
  for (std::size_t i = 0; i < p.n_local(); ++i)
    if (p.type[i] < n_types)
      lightest[p.type[i]] = std::max(lightest[p.type[i]], -p.mass[i]);
  comm.allreduce_max(lightest);
  for (int t1 = 0; t1 < n_types; ++t1)
    for (int t2 = t1; t2 < n_types; ++t2) {
      auto& params = nonbonded.at(t1, t2).get<HardContact>();
      if (!params.active())
        continue;
      // a wall's type has no particles: the other type's mass counts
      const double m = std::min(-lightest[t1], -lightest[t2]);
      params.guard_gap = std::isfinite(m) ? HardContact::guard_for(params, m_time_step, m) : 0.0;
      nonbonded.at(t2, t1).get<HardContact>().guard_gap = params.guard_gap;
    }
}

void System::add_constraint_forces(Energies* e) {
  auto& p = particles;
  double energy = 0.0;
  PairContext c;
  c.wall = true;
  c.mol_j = -1;
  c.normal_j = Vec3::Zero();
  // the largest range of any pair: beyond it no constraint acts
  const double range = nonbonded.max_range();
  // Spread over ranks: this rank's particles only (a pass over every stored
  // particle per shape cost as much as the walls' own work at 2 ranks), in
  // ascending local index as one rank goes, so each wall's total force sums
  // in the serial order.
  // A bounded shape (a block, a cylinder, a union of them) is far from most
  // particles: per run of up to `chunk` consecutive particles (a cell's
  // nodes are contiguous, so a run is a patch of a membrane) the box around
  // them is tested against the shape's box, and a run farther than the
  // range from it is skipped. The shape's distance is at least the distance
  // between the boxes (Shape::bounding_box), so the skipped particles are
  // some of those the range test below passes over: the same forces, summed
  // in the same order. A run with a position that is not finite has no box
  // and is always evaluated (the error names it as before).
  constexpr std::size_t chunk = 32;
  std::vector<ConstraintChunk>& chunks = m_constraint_chunks;
  chunks.clear();
  for (const auto& [first, last] : owned_runs())
    for (std::size_t begin = first; begin < last; begin += chunk) {
      ConstraintChunk r{begin, std::min(last, begin + chunk), p.pos[begin], p.pos[begin]};
      Vec3 sum = Vec3::Zero();
      for (std::size_t i = r.begin; i < r.end; ++i) {
        r.lo = r.lo.cwiseMin(p.pos[i]);
        r.hi = r.hi.cwiseMax(p.pos[i]);
        sum += p.pos[i]; // not finite if any coordinate is not
      }
      if (!sum.allFinite()) {
        r.lo = Vec3::Constant(-HUGE_VAL);
        r.hi = Vec3::Constant(HUGE_VAL);
      }
      chunks.push_back(r);
    }
  std::vector<double>& dist = m_constraint_dist;
  dist.resize(p.n_local());
  for (auto& constraint : m_constraints) {
    constraint->total_force.setZero();
    Vec3 shape_lo, shape_hi;
    const bool bounded = constraint->shape->bounding_box(shape_lo, shape_hi);
    for (const ConstraintChunk& r : chunks) {
      if (bounded) {
        const Vec3 gap = (shape_lo - r.hi).cwiseMax(r.lo - shape_hi).cwiseMax(Vec3::Zero());
        if (gap.norm() >= range)
          continue; // every particle of the run is farther than the range
      }
      // the run's distances in one call (a tight loop for walls; bounded
      // shapes skip the exact distance of particles farther than the range
      // from their box), the force where a particle is within its pair's
      // range
      constraint->shape->signed_distances(p.pos.data() + r.begin, r.end - r.begin, range,
                                          dist.data() + r.begin);
      for (std::size_t i = r.begin; i < r.end; ++i) {
        const double d = dist[i];
        if (d >= range)
          continue;
        const PairParams* params = nonbonded.find(p.type[i], constraint->particle_type);
        if (!params)
          continue;
        if (d > 0.0) {
          if (d >= params->range)
            continue;
        } else if (constraint->penetrable) {
          // inside a penetrable shape: as in ESPResSo, the interaction at the
          // mirrored distance -dist, along the same vector dist * normal (so
          // a repulsion pushes the particle deeper in, away from the
          // surface), unless only_positive
          if (constraint->only_positive || !(d < 0.0) || -d >= params->range)
            continue;
        } else {
          std::ostringstream msg;
          msg << "particle " << p.id[i] << " at (" << p.pos[i].transpose()
              << ") penetrated the non-penetrable " << constraint->shape->name()
              << " constraint (signed distance " << d << ") at time " << time
              << "; at the start of a run this means it was placed inside: check the initial "
                 "positions; later, strengthen the node-wall interaction or reduce the time step";
          throw SimulationInstability("wall_penetration", msg.str())
              .at_particle(p.id[i])
              .in_cell(p.mol_id[i])
              .at_time(time)
              .with_value(d);
        }
        double exact;
        Vec3 normal;
        constraint->shape->calc_dist(p.pos[i], exact, normal);
        c.d = exact * normal;
        c.dist = std::abs(exact);
        c.mol_i = p.mol_id[i];
        c.normal_i = p.normal[i];
        Vec3 f;
        try {
          f = pair_force(*params, c, e ? &energy : nullptr);
        } catch (const SimulationInstability& error) {
          rethrow_pair_error(error, p.id[i], -1, c, constraint->shape->name());
        }
        p.force[i] += f;
        constraint->total_force -= f;
      }
    }
  }
  if (e)
    e->non_bonded += energy;
}

void System::add_langevin_forces() {
  auto& p = particles;
  const double gamma = m_langevin.gamma;
  const double noise = std::sqrt(2.0 * gamma * m_langevin.kT / m_time_step);
  const random::Key key{m_langevin.seed, static_cast<std::uint64_t>(random::Stream::langevin),
                        step_count, 0};
  for (const auto& [first, end] : owned_runs())
    for (std::size_t i = first; i < end; ++i) {
      Vec3 f = -gamma * p.vel[i];
      if (noise > 0.0) {
        random::Key k = key;
        k.key = static_cast<std::uint64_t>(p.id[i]);
        for (int d = 0; d < 3; ++d)
          f[d] += noise * random::normal(k, d);
      }
      p.force[i] += f;
    }
}

template <bool with_energy>
void System::force_loop(Energies* e, bool forces_preset, RunTimings* timings) {
  auto& p = particles;
  if (!forces_preset)
    for (std::size_t i = 0; i < p.n_local(); ++i)
      p.force[i] = p.ext_force[i];
  RunTimings untimed;
  RunTimings& t = timings ? *timings : untimed;
  PhaseClock clock(timings != nullptr);
  // Spread over the ranks, an error of one rank's phase must not leave the
  // others waiting in an exchange: it is kept, the later phases are
  // skipped on that rank, the exchanges still run, and at the end every
  // rank raises the lowest failing rank's error.
  std::exception_ptr failure;
  auto phase = [&](auto&& compute) {
    if (!m_spread.active) {
      compute();
      return;
    }
    if (failure)
      return;
    try {
      compute();
    } catch (...) {
      failure = std::current_exception();
    }
  };
  phase([&] { add_membrane_forces(e); });
  if (m_spread.active && has_membrane_bonds())
    exchange_current(true); // normals of other ranks' nodes for the contacts
  clock.lap(t.membrane);
  phase([&] { add_bonded_forces(e); });
  clock.lap(t.bonded);
  phase([&] {
    try {
      add_nonbonded_forces(e);
    } catch (const SimulationInstability& error) {
      // named here, off the pair loop (a handler inside it cost 5 % of the
      // loop's instructions): the pair is found again
      if (error.cause == "contact_overrun")
        name_contact_overrun(error);
      throw;
    }
  });
  clock.lap(t.non_bonded);
  phase([&] { add_constraint_forces(e); });
  clock.lap(t.constraints);
  if constexpr (!with_energy) {
    if (m_langevin.active && m_langevin.gamma > 0.0)
      phase([&] { add_langevin_forces(); });
    if (m_lb && m_lb_coupling.active) {
      if (m_spread.active) {
        const lb::CouplingDistribution spread{
            m_spread.current.data(), [this](std::vector<Vec3>& f, const std::vector<int>& giver,
                                            const std::vector<std::uint32_t>* listed) {
              share_coupling_forces(f, giver, listed);
            }};
        try { // every rank takes part, a failed one too (see couple_particles)
          lb::couple_particles(*m_lb, m_lb_coupling.ledger, p, box, m_lb_coupling.params,
                               step_count, m_time_step, &spread);
        } catch (...) {
          if (!failure)
            failure = std::current_exception();
        }
      } else {
        lb::couple_particles(*m_lb, m_lb_coupling.ledger, p, box, m_lb_coupling.params, step_count,
                             m_time_step);
      }
    }
    clock.lap(t.coupling);
    // the implicit membrane viscosity against all of the step's forces
    // (viscosity.hpp): the cell's owner holds them all by now
    phase([&] { membranes.add_deferred_viscosity(p, box); });
    clock.lap(t.membrane);
  }
  if (m_spread.active)
    raise_agreed(failure);
}

void System::prepare() {
  if (m_lb)
    m_lb->update_boundaries(); // collective; nothing when no boundary changed
}

void System::compute_forces() {
  prepare_step();
  force_loop<false>(nullptr);
  mark_forces_valid();
  m_spread.stale = m_spread.active; // forces on the owners only
}

bool System::has_membrane_bonds() const {
  bool any = false;
  for (const BondedEntry& entry : bonded)
    std::visit(
        [&](const auto& ia) {
          using IA = std::decay_t<decltype(ia)>;
          if constexpr (is_membrane_bond<IA>)
            any |= entry.bonds.size() > 0;
        },
        entry.interaction);
  return any;
}

Energies System::compute_energies() {
  Energies e;
  prepare_step();
  const std::vector<Vec3> saved = particles.force;
  force_loop<true>(&e);
  particles.force = saved;
  const std::uint8_t* own = owned_mask();
  for (std::size_t i = 0; i < particles.n_local(); ++i)
    if (!own || own[i])
      e.kinetic += 0.5 * particles.mass[i] * particles.vel[i].squaredNorm();
  // spread: every rank's share (the same keys on every rank)
  const Communicator& c = own ? m_spread.comm : comm;
  e.kinetic = c.allreduce_sum(e.kinetic);
  e.bonded = c.allreduce_sum(e.bonded);
  e.non_bonded = c.allreduce_sum(e.non_bonded);
  for (auto& [id, energy] : e.bonded_by_id)
    energy = c.allreduce_sum(energy);
  return e;
}

void System::report_fast_particle(double dt, std::uint64_t step) const {
  const double half_box = 0.5 * box.length().minCoeff();
  const bool pairs = nonbonded.max_range() > 0.0 && cells.skin > 0.0;
  const double limit = pairs ? std::min(half_box, cells.skin) : half_box;
  // the particle that moved farthest in this step (fixed coordinates do not move)
  const auto& p = particles;
  auto drift2 = [&](std::size_t i) {
    double d2 = 0.0;
    for (int d = 0; d < 3; ++d)
      if (!(p.fixed[i] & (1u << d)))
        d2 += dt * dt * p.vel[i][d] * p.vel[i][d];
    return d2;
  };
  std::size_t fastest = 0;
  for (std::size_t i = 1; i < p.n_local(); ++i)
    if (drift2(i) > drift2(fastest))
      fastest = i;
  std::ostringstream msg;
  msg << "the integration is unstable: particle " << p.id[fastest] << " moved "
      << std::sqrt(drift2(fastest)) << " in one time step (more than "
      << (limit < half_box ? "the skin of the pair lists, " : "half the box length, ") << limit
      << ") to time " << time + dt << ", velocity (" << p.vel[fastest].transpose()
      << "). Reduce the time step or the stiffness of the interactions (bonds, membrane "
         "moduli, contacts, coupling gamma). The positions are those after this step's drift";
  SimulationInstability error("particle_jump", msg.str());
  error.step = static_cast<long long>(step);
  throw error.at_particle(p.id[fastest])
      .in_cell(p.mol_id[fastest])
      .at_time(time + dt)
      .with_value(std::sqrt(drift2(fastest)));
}

void System::integrate(int n_steps, bool recalc_forces, bool reuse_forces) {
  if (n_steps < 0)
    throw InputError("steps must be a non-negative integer, got " + std::to_string(n_steps));
  // tau against the time step and box (not set_time_step, which marks the
  // forces stale: recomputing them at every call made a run split into
  // calls differ from one run -- the last step's coupling force recomputed
  // against the fluid updated since)
  prepare(); // the one collective set-up step: boundaries set since the last run flagged now
  if (m_lb) {
    m_lb->validate(box, m_time_step);
    m_lb->check_usable(); // refused before any particle moves or time advances
    // populations, boundaries or ext_force_density set since the last run:
    // the coupling forces of its last step no longer hold
    if (m_lb_coupling.active && m_lb->state_version() != m_fluid_version_of_forces)
      invalidate_forces();
  }
  if (constraint_shape_version() != m_shape_version_of_forces)
    invalidate_forces();   // a constraint's shape changed (Union.add ...)
  update_contact_guards(); // time step and masses as they are now
  auto& p = particles;
  if (!reuse_forces && (!m_forces_valid || recalc_forces)) {
    try { // the forces of the state the run starts from: named as of this step
      compute_forces();
    } catch (SimulationInstability& e) {
      throw e.at_step(step_count, time);
    }
  }
  // run_timings: the steps, however the call ends; not the force computation
  // a run may start with (stale forces: first run, changed parameters,
  // recalc_forces), which would inflate the time per step of short runs
  // (LAMMPS likewise reports its setup apart from the loop)
  struct TotalClock {
    double& total;
    PhaseClock clock{true};
    ~TotalClock() { clock.lap(total); }
  } total_clock{run_timings.total};
  const double dt = m_time_step;
  const int lb_interval = lb_steps_per_update();
  // Velocity Verlet. The half kick dt / 2m per particle is computed once per
  // run (mass, fixed flags and order do not change during it). Between two
  // steps of a run the second half kick of one, the first of the next and
  // its drift are one pass over the particles, which also resets the forces
  // to the external ones and does the cell system's displacement test while
  // the positions are at hand (the particle arrays do not stay in cache
  // between passes: the lattice update streams through in between). The
  // arithmetic is that of separate passes, (v + h f) + h f, bit for bit.
  // One mass for all (the usual case: a cell's nodes share theirs) and no
  // external forces spare the pass two of its input streams.
  const std::size_t n = p.n_local();
  std::vector<double> half_kick(n);
  bool any_fixed = false, one_mass = true, any_external = false;
  for (std::size_t i = 0; i < n; ++i) {
    half_kick[i] = 0.5 * dt / p.mass[i];
    any_fixed |= p.fixed[i] != 0;
    one_mass &= half_kick[i] == half_kick[0];
    any_external |= !(p.ext_force[i].array() == 0.0).all();
  }
  // A particle that moves half the box in one step has certainly blown up
  // (a stiff bond or membrane with too long a time step): stopped here,
  // long before its energy overflows, with its id and speed.
  // With pair contacts (and a skin), a step longer than the skin is one too: the pair
  // lists are rebuilt at every such step, and a node moving a skin (0.4 um
  // by default, 4 m/s at a step of 0.1 us against the mm/s of cells in flow)
  // per step has left the physics well before.
  const double half_box2 = 0.25 * std::pow(box.length().minCoeff(), 2);
  const double step_limit2 = nonbonded.max_range() > 0.0 && cells.skin > 0.0
                                 ? std::min(half_box2, cells.skin * cells.skin)
                                 : half_box2;
  // kicks half kicks (1 or 2), then the drift; returns the displacement test
  // (1: some particle moved beyond the skin or a re-sort is due anyway, 0:
  // none) or -1 when a position is not finite (prepare_step then names it)
  auto advance_with = [&](auto kicks, auto uniform, auto external) {
    constexpr int n_kicks = decltype(kicks)::value;
    const Vec3* const x0 = cells.displacement_reference(n);
    const double limit2 = cells.displacement_limit2();
    const double h0 = n > 0 ? half_kick[0] : 0.0;
    double worst2 = 0.0, step2 = 0.0;
    bool runaway = false;
    // spread over the ranks: the particles this rank integrates (runs of
    // them, made anew when they change, at re-sorts)
    for (const auto& [first, end] : owned_runs())
      for (std::size_t i = first; i < end; ++i) {
        const double h = decltype(uniform)::value ? h0 : half_kick[i];
        const Vec3 f = p.force[i];
        Vec3 v = p.vel[i];
        Vec3 x = p.pos[i];
        if (!any_fixed) {
          for (int k = 0; k < n_kicks; ++k)
            v += h * f;
          x += dt * v;
        } else {
          for (int d = 0; d < 3; ++d) {
            if (p.fixed[i] & (1u << d))
              continue; // neither kicked nor moved
            for (int k = 0; k < n_kicks; ++k)
              v[d] += h * f[d];
            x[d] += dt * v[d];
          }
        }
        step2 = std::max(step2, (x - p.pos[i]).squaredNorm());
        p.vel[i] = v;
        p.pos[i] = x;
        if constexpr (n_kicks == 2) {
          if constexpr (decltype(external)::value)
            p.force[i] = p.ext_force[i];
          else
            p.force[i].setZero();
        }
        if (x0)
          worst2 = std::max(worst2, (x - x0[i]).squaredNorm());
        runaway |= cells.runaway(x);
      }
    if (step2 > step_limit2 && !runaway) {
      if (m_spread.active)
        return -3;                              // raised on every rank in prepare_step
      report_fast_particle(dt, step_count + 1); // the drift of the next step
    }
    return runaway ? -1 : (!x0 || worst2 > limit2) ? 1 : 0;
  };
  auto advance = [&](auto kicks) {
    using yes = std::true_type;
    using no = std::false_type;
    if (one_mass)
      return any_external ? advance_with(kicks, yes{}, yes{}) : advance_with(kicks, yes{}, no{});
    return any_external ? advance_with(kicks, no{}, yes{}) : advance_with(kicks, no{}, no{});
  };
  auto second_kick = [&] {
    for (const auto& [first, end] : owned_runs())
      for (std::size_t i = first; i < end; ++i)
        for (int d = 0; d < 3; ++d)
          if (!(p.fixed[i] & (1u << d)))
            p.vel[i][d] += half_kick[i] * p.force[i][d];
  };
  if (n_steps == 0) {
    mark_forces_valid();
    return;
  }
  m_spread.stale = m_spread.active; // the owners' state only, from here on
  // until the run ends normally the forces are those of some step in
  // between, or partial after an exception: a later run recomputes them
  m_forces_valid = false;
  // an instability names the step and time it happened at (the throwers
  // deep inside know neither)
  struct ChecksDue {
    bool& flag;
    ~ChecksDue() { flag = false; }
  } checks_due{m_checks_due};
  try {
    int moved = advance(std::integral_constant<int, 1>{}); // first half kick + drift
    for (int step = 0; step < n_steps; ++step) {
      ++step_count;
      ++run_timings.steps; // begun (one cut short by an exception counts)
      time += dt;
      prepare_step(moved);
      // the cells' checks (cell_checks): in the first step of a run (a bad
      // start is named at once) and every 8th step, where they cost 1/8 of
      // about 3 % of a step; a fold or a crossing lasts longer than that
      m_checks_due = cell_checks && (step == 0 || (step_count & 7) == 0);
      // after the fused pass the forces already hold the external forces
      force_loop<false>(nullptr, step > 0 && moved >= 0, &run_timings);
      const bool last = step + 1 == n_steps;
      if (last)
        second_kick();
      if (m_lb && ++m_lb_substep >= lb_interval) {
        m_lb_substep = 0;
        try {
          PhaseClock clock(true);
          m_lb->step();
          clock.lap(run_timings.lb_fluid);
        } catch (const SimulationInstability& e) {
          if (!last)
            second_kick(); // leave the particles as a step that ended here
          // a stiff coupling (gamma dt / m of order 1 and more) makes coupled
          // particles and nodes overshoot: the fluid blows up, but the cause
          // is gamma, which the fluid's message cannot know
          const double max_half_kick =
              n > 0 ? *std::max_element(half_kick.begin(), half_kick.end()) : 0.0;
          const double stiffness = 2.0 * m_lb_coupling.params.gamma * max_half_kick;
          if (m_lb_coupling.active && stiffness > 1.0)
            throw e.with_message(
                std::string(e.what()) +
                ". The particle coupling may be the cause: gamma * time_step / mass = " +
                format_number(stiffness) +
                " (above about 1 particles and fluid overshoot); lower gamma or the time step");
          throw;
        } catch (...) {
          if (!last)
            second_kick(); // leave the particles as a step that ended here
          throw;
        }
      }
      // every 16 steps: the caller may end the run here (Ctrl-C), with the
      // particles as a run that ended with this step leaves them
      if (!last && interruption_point && (step & 15) == 15) {
        try {
          interruption_point();
        } catch (...) {
          // the state of a run that ended with this step: a later run goes
          // on from here exactly as after run(k) (no force recomputation)
          second_kick();
          mark_forces_valid();
          throw;
        }
      }
      if (!last) // second half kick of this step, first one and drift of the next
        moved = advance(std::integral_constant<int, 2>{});
    }
  } catch (SimulationInstability& e) {
    throw e.at_step(step_count, time);
  }
  mark_forces_valid();
}

} // namespace pyoif
