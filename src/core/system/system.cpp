#include "system/system.hpp"

#include <cmath>
#include <limits>

#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace pyoif {

// `comm` is MPI_COMM_SELF: without a decomposed fluid every rank of an mpirun
// holds and computes the whole system (a reduction over all ranks would count
// each particle once per rank); with one, the particles' reductions go over
// the fluid's ranks (spread_comm, system_parallel.cpp).
System::System(const Vec3& box_l, const std::array<bool, 3>& periodic)
    : box(box_l, periodic), comm(MPI_COMM_SELF) {}

void System::set_time_step(double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw InputError("time_step must be a finite positive number, got " + format_number(dt));
  if (m_lb) {
    const double ratio = m_lb->tau() / dt;
    if (std::abs(ratio - std::round(ratio)) > 1e-9 * ratio || std::round(ratio) < 1)
      throw InputError("time_step " + format_number(dt) +
                       " does not divide the lattice-Boltzmann tau " + format_number(m_lb->tau()) +
                       " (tau must be an integer multiple of time_step)");
  }
  m_time_step = dt;
  invalidate_forces();
}

void System::set_box_l(const Vec3& l) {
  box.set_length(l);
  cells.invalidate();
  invalidate_forces();
}

void System::set_periodicity(const std::array<bool, 3>& p) {
  box.set_periodic(p);
  cells.invalidate();
  invalidate_forces();
}

int System::add_particle(int pid, const Vec3& pos, const Vec3& vel, double mass, int type,
                         int mol_id, const Vec3& ext_force, std::uint8_t fixed) {
  if (pid < 0)
    pid = particles.max_id() + 1;
  if (pid >= std::numeric_limits<int>::max())
    throw InputError("id: particle ids must be in 0.." +
                     std::to_string(std::numeric_limits<int>::max() - 1));
  if (particles.index(pid) >= 0)
    throw InputError("id: particle " + std::to_string(pid) + " already exists");
  if (!(mass > 0.0) || !std::isfinite(mass))
    throw InputError("mass must be a finite positive number, got " + format_number(mass));
  if (type < 0)
    throw InputError("type must be a non-negative integer, got " + std::to_string(type));
  if (!pos.allFinite() || !vel.allFinite() || !ext_force.allFinite())
    throw InputError("pos, v and ext_force must be finite (particle " + std::to_string(pid) + ")");
  check_position_range(pos, pid);
  particles.add(pid, pos, Vec3i::Zero(), vel, mass, type, mol_id, ext_force, fixed);
  cells.invalidate();
  invalidate_forces();
  return pid;
}

void System::remove_particle(int pid) {
  checked_index(pid);
  particles.remove(pid);
  cells.remove_exclusions_of(pid); // a new particle may reuse the id
  for (auto& entry : bonded) {
    auto& g = entry.bonds;
    BondGroup kept;
    kept.n_particles = g.n_particles;
    kept.per_bond_stride = g.per_bond_stride;
    for (std::size_t b = 0; b < g.size(); ++b) {
      const int* ids = g.bond(b);
      if (std::find(ids, ids + g.n_particles, pid) != ids + g.n_particles)
        continue;
      kept.ids.insert(kept.ids.end(), ids, ids + g.n_particles);
      if (g.per_bond_stride)
        kept.per_bond.insert(kept.per_bond.end(), g.reference(b),
                             g.reference(b) + g.per_bond_stride);
    }
    g = std::move(kept);
  }
  cells.invalidate();
  bonds_changed();
}

void System::clear_particles() {
  particles.clear();
  cells.clear_exclusions(); // new particles may reuse the ids
  for (auto& entry : bonded) {
    entry.bonds.ids.clear();
    entry.bonds.per_bond.clear();
  }
  cells.invalidate();
  bonds_changed();
}

void System::check_position_range(const Vec3& pos, int pid) const {
  // the periodic image counters are ints: beyond 1e9 box lengths they would
  // overflow when the position is folded (the integrator stops a particle
  // that flies that far as a blow-up)
  for (int d = 0; d < 3; ++d)
    if (std::abs(pos[d]) > box.image_range()[d])
      throw InputError("pos: particle " + std::to_string(pid) + " at " + format_number(pos[d]) +
                       " along axis " + std::to_string(d) +
                       " is more than 1e9 box lengths from the box; positions must be within that");
}

int System::checked_index(int pid) const {
  const int idx = particles.index(pid);
  if (idx < 0)
    throw InputError("particle id " + std::to_string(pid) + " does not exist");
  return idx;
}

int System::add_bonded_interaction(const BondedInteraction& ia) {
  BondedEntry entry{ia, {}};
  std::visit(
      [&](const auto& b) {
        using IA = std::decay_t<decltype(b)>;
        entry.bonds.n_particles = IA::n_particles;
        entry.bonds.per_bond_stride = IA::per_bond_stride;
      },
      ia);
  bonded.push_back(std::move(entry));
  bonds_changed();
  return static_cast<int>(bonded.size()) - 1;
}

void System::add_bonds(int bond_id, const std::vector<int>& ids,
                       const std::vector<double>& per_bond) {
  if (bond_id < 0 || bond_id >= static_cast<int>(bonded.size()))
    throw InputError("bond: bonded interaction " + std::to_string(bond_id) +
                     " is not registered; add it with system.bonded_inter.add() first");
  BondGroup& g = bonded[bond_id].bonds;
  if (ids.size() % g.n_particles != 0)
    throw InputError("bond partners: this bond joins " + std::to_string(g.n_particles) +
                     " particles, got " + std::to_string(ids.size()) + " ids");
  const std::size_t n = ids.size() / g.n_particles;
  if (per_bond.size() != n * g.per_bond_stride)
    throw InputError("bond reference values: expected " + std::to_string(g.per_bond_stride) +
                     " per bond");
  for (std::size_t b = 0; b < n; ++b)
    for (int k = 0; k < g.n_particles; ++k) {
      const int pid = ids[b * g.n_particles + k];
      if (particles.index(pid) < 0)
        throw InputError("bond partner: particle " + std::to_string(pid) + " does not exist");
      for (int l = 0; l < k; ++l)
        if (ids[b * g.n_particles + l] == pid)
          throw InputError("bond partners: particle " + std::to_string(pid) +
                           " appears twice in one bond");
    }
  g.ids.insert(g.ids.end(), ids.begin(), ids.end());
  g.per_bond.insert(g.per_bond.end(), per_bond.begin(), per_bond.end());
  bonds_changed();
}

bool System::remove_bond(int bond_id, const std::vector<int>& ids) {
  if (bond_id < 0 || bond_id >= static_cast<int>(bonded.size()))
    throw InputError("bond: bonded interaction " + std::to_string(bond_id) + " is not registered");
  BondGroup& g = bonded[bond_id].bonds;
  for (std::size_t b = 0; b < g.size(); ++b)
    if (ids.size() == static_cast<std::size_t>(g.n_particles) &&
        std::equal(ids.begin(), ids.end(), g.bond(b))) {
      g.ids.erase(g.ids.begin() + b * g.n_particles, g.ids.begin() + (b + 1) * g.n_particles);
      if (g.per_bond_stride)
        g.per_bond.erase(g.per_bond.begin() + b * g.per_bond_stride,
                         g.per_bond.begin() + (b + 1) * g.per_bond_stride);
      bonds_changed();
      return true;
    }
  return false;
}

void System::set_lb(std::shared_ptr<lb::LBFluid> fluid) {
  if (fluid)
    fluid->validate(box, m_time_step);
  synchronize(); // every copy current before the particles' spread changes
  m_lb = std::move(fluid);
  m_lb_coupling.ledger = lb::CouplingLedger{}; // its records are the old fluid's
  update_spread();
  if (!m_lb)
    m_lb_coupling.active = false;
  m_lb_substep = 0;
  invalidate_forces();
}

Vec3 System::fluid_momentum() const {
  if (!m_lb)
    return Vec3::Zero();
  return m_lb->total_momentum() - m_lb_coupling.ledger.in_flight_momentum(*m_lb);
}

void System::set_lb_coupling(double gamma, std::uint64_t seed) {
  if (!m_lb)
    throw InputError("set_lb_coupling: no lattice-Boltzmann fluid is active");
  if (!(gamma >= 0.0) || !std::isfinite(gamma))
    throw InputError("gamma must be a finite number >= 0");
  m_lb_coupling.active = true; // (the ledger stays: a deposit may be in flight)
  m_lb_coupling.params = {gamma, m_lb->params().kT, seed};
  invalidate_forces();
}

void System::remove_constraint(const std::shared_ptr<ShapeBasedConstraint>& c) {
  m_constraints.erase(std::remove(m_constraints.begin(), m_constraints.end(), c),
                      m_constraints.end());
  invalidate_forces();
}

int System::lb_steps_per_update() const {
  if (!m_lb)
    return 0;
  return static_cast<int>(std::lround(m_lb->tau() / m_time_step));
}

Vec3 System::particle_momentum() const {
  Vec3 p = Vec3::Zero();
  const std::uint8_t* own = owned_mask();
  for (std::size_t i = 0; i < particles.n_local(); ++i)
    if (!own || own[i])
      p += particles.mass[i] * particles.vel[i];
  if (own)
    m_spread.comm.allreduce_sum(p.data(), 3);
  return p;
}

} // namespace pyoif
