// The System owns all simulation state: box, particles, interactions, bonds,
// constraints, thermostats, the fluid and the communicator. No globals: two
// Systems in one process are independent.
#pragma once

#include "communication/communicator.hpp"
#include "constraints/shape_based_constraint.hpp"
#include "interactions/bonded/bond_group.hpp"
#include "interactions/bonded/bonded_registry.hpp"
#include "interactions/bonded/oif_fast_path.hpp"
#include "interactions/nonbonded/nonbonded_table.hpp"
#include "lb/lb_coupling.hpp"
#include "lb/lb_fluid.hpp"
#include "particles/cell_system.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace pyoif {

struct LangevinParams {
  bool active = false;
  double kT = 0.0, gamma = 0.0;
  std::uint64_t seed = 0;
};

struct LBCouplingState {
  bool active = false;
  lb::CouplingParams params;
};

/** One registered bonded interaction and its bonds. */
struct BondedEntry {
  BondedInteraction interaction;
  BondGroup bonds;
};

struct Energies {
  double kinetic = 0.0, bonded = 0.0, non_bonded = 0.0;
  std::map<int, double> bonded_by_id; ///< per bonded interaction id
  double total() const { return kinetic + bonded + non_bonded; }
};

class System {
public:
  System(const Vec3& box_l, const std::array<bool, 3>& periodic);

  // --- geometry and integration parameters ----------------------------------
  BoxGeometry box;
  CellSystem cells;
  Communicator comm;
  double time_step() const { return m_time_step; }
  void set_time_step(double dt);
  double time = 0.0;
  std::uint64_t step_count = 0; ///< MD steps done (RNG counter)
  void set_box_l(const Vec3& l);
  void set_periodicity(const std::array<bool, 3>& p);

  // --- particles --------------------------------------------------------------
  ParticleStore particles;
  /** Adds a particle and returns its id (next free id when pid < 0). */
  int add_particle(int pid, const Vec3& pos, const Vec3& vel, double mass, int type, int mol_id,
                   const Vec3& ext_force, std::uint8_t fixed);
  void remove_particle(int pid);
  void clear_particles();
  /** Local index of id, throwing InputError when it does not exist. */
  int checked_index(int pid) const;

  // --- interactions -----------------------------------------------------------
  NonbondedTable nonbonded;
  void on_interactions_changed() {
    cells.invalidate();
    m_forces_valid = false;
  }
  std::vector<BondedEntry> bonded; ///< index = bonded interaction id
  int add_bonded_interaction(const BondedInteraction& ia);
  /** Adds bonds of interaction `bond_id`: ids is n_bonds * n_particles ids,
   *  per_bond the per-bond reference values (or empty). */
  void add_bonds(int bond_id, const std::vector<int>& ids, const std::vector<double>& per_bond);
  /** The time-step loop evaluates the OIF bond groups with the compiled fast
   *  path (oif_fast_path.hpp); false: the generic bond loop (tests compare). */
  bool bonded_fast_path = true;
  std::vector<std::shared_ptr<ShapeBasedConstraint>> constraints;

  // --- thermostats and fluid --------------------------------------------------
  LangevinParams langevin;
  LBCouplingState lb_coupling;
  std::shared_ptr<lb::LBFluid> lb;
  void set_lb(std::shared_ptr<lb::LBFluid> fluid);

  // --- integration ------------------------------------------------------------
  /** n velocity-Verlet steps, all in C++. */
  void integrate(int n_steps, bool recalc_forces = false, bool reuse_forces = false);
  /** Recompute all forces for the current positions (no time advance). */
  void compute_forces();
  Energies compute_energies();
  Vec3 particle_momentum() const;
  /** The forces of the last step no longer hold (a particle's position,
   *  velocity, external force or type was set, a constraint, thermostat or
   *  exclusion changed): the next run recomputes them before its first half
   *  kick. */
  void invalidate_forces() { m_forces_valid = false; }
  /** Number of MD steps per lattice update (tau / time_step). */
  int lb_steps_per_update() const;

private:
  /** Re-sort if needed and update ghosts. moved: the integrator's drift
   *  already tested the displacements (1 beyond the skin, 0 not); -1: test. */
  void prepare_step(int moved = -1);
  /** All forces; forces_preset: the local forces already hold the external
   *  forces (the integrator's fused pass set them). */
  template <bool with_energy> void force_loop(Energies* e, bool forces_preset = false);
  void add_bonded_forces(Energies* e);
  void add_nonbonded_forces(Energies* e);
  void add_constraint_forces(Energies* e);
  void add_langevin_forces();
  std::vector<oif::FastBondPlan> m_fast_plans; ///< per bonded interaction id
  std::vector<double> m_constraint_dist;       ///< per particle, one constraint at a time
  /** Per OifLocalForces id: that group fused with its cell type's
   *  OifGlobalForces group (add_bonded_forces). */
  std::vector<oif::FusedMembranePlan> m_fused_plans;
  double m_time_step = 0.01;
  bool m_forces_valid = false;
  int m_lb_substep = 0;
};

} // namespace pyoif
