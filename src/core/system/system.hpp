// The System owns all simulation state: box, particles, interactions, bonds,
// constraints, thermostats, the fluid and the communicator. No globals: two
// Systems in one process are independent.
#pragma once

#include "communication/communicator.hpp"
#include "constraints/shape_based_constraint.hpp"
#include "interactions/bonded/bond_group.hpp"
#include "interactions/bonded/bonded_registry.hpp"
#include "interactions/membrane/membrane_model.hpp"
#include "interactions/nonbonded/nonbonded_table.hpp"
#include "lb/lb_coupling.hpp"
#include "lb/lb_fluid.hpp"
#include "particles/cell_system.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <cstdint>
#include <exception>
#include <functional>
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
  /// the coupling's records between passes (reset with a new fluid)
  lb::CouplingLedger ledger;
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
  /** Throws InputError when pos is too far from the box to be folded (its
   *  image counter would overflow), naming particle pid. */
  void check_position_range(const Vec3& pos, int pid) const;

  // --- interactions -----------------------------------------------------------
  // Changes of the force field go through methods of System that mark the
  // forces stale (the next run recomputes them before its first half kick).
  // The constraint list, the thermostat settings and the fluid are private;
  // the non-bonded table, the cell system, the bonded interactions, the
  // particles and the box are public members with many other uses: change
  // their parameters and exclusions through set_nonbonded and
  // add_/remove_exclusion, the box through its setters, and call
  // invalidate_forces() after writing particles or bonds directly.
  NonbondedTable nonbonded;
  /** Sets the parameters of a pair model for the type pair (t1, t2). */
  template <class Model> void set_nonbonded(int t1, int t2, const typename Model::Params& p) {
    nonbonded.at(t1, t2).template get<Model>() = p;
    nonbonded.commit(t1, t2);
    on_interactions_changed();
  }
  /** After a direct change of `nonbonded` (its ranges: the cell grid too). */
  void on_interactions_changed() {
    cells.invalidate();
    invalidate_forces();
  }
  void add_exclusion(int id1, int id2) {
    checked_index(id1); // both must exist: the exclusion lists are indexed by id
    checked_index(id2);
    if (id1 == id2)
      throw InputError("a particle cannot be excluded from itself (id " + std::to_string(id1) +
                       ")");
    cells.add_exclusion(id1, id2);
    invalidate_forces();
  }
  void remove_exclusion(int id1, int id2) {
    cells.remove_exclusion(id1, id2);
    invalidate_forces();
  }
  std::vector<BondedEntry> bonded; ///< index = bonded interaction id
  int add_bonded_interaction(const BondedInteraction& ia);
  /** Adds bonds of interaction `bond_id`: ids is n_bonds * n_particles ids,
   *  per_bond the per-bond reference values (or empty). */
  void add_bonds(int bond_id, const std::vector<int>& ids, const std::vector<double>& per_bond);
  /** Removes the first bond of interaction `bond_id` with exactly these
   *  particle ids; false if there is none. */
  bool remove_bond(int bond_id, const std::vector<int>& ids);
  /** Counts every change of the bonds (added, removed, interactions
   *  registered): the compiled membranes are kept while it stays. Code that
   *  writes `bonded` directly must call bonds_changed(). */
  std::uint64_t bonds_version() const { return m_bonds_version; }
  void bonds_changed() {
    ++m_bonds_version;
    invalidate_forces();
  }
  /** The membrane component: every OIF bond compiled into cells and
   *  evaluated by one driver (interactions/membrane/membrane_model.hpp);
   *  `membranes.lanes` chooses four cells per vector lane (default) or one
   *  at a time, `membranes.counts` counts which ran. */
  membrane::Membranes membranes;
  const std::vector<std::shared_ptr<ShapeBasedConstraint>>& constraints() const {
    return m_constraints;
  }
  void add_constraint(std::shared_ptr<ShapeBasedConstraint> c) {
    m_constraints.push_back(std::move(c));
    invalidate_forces();
  }
  void remove_constraint(const std::shared_ptr<ShapeBasedConstraint>& c);

  // --- thermostats and fluid --------------------------------------------------
  const LangevinParams& langevin() const { return m_langevin; }
  void set_langevin(const LangevinParams& params) {
    m_langevin = params;
    invalidate_forces();
  }
  void langevin_off() {
    m_langevin.active = false;
    invalidate_forces();
  }
  const LBCouplingState& lb_coupling() const { return m_lb_coupling; }
  /** The coupling's records, for checkpoints to restore. */
  lb::CouplingLedger& lb_coupling_ledger() { return m_lb_coupling.ledger; }
  /** Couples the particles to the fluid (kT is the fluid's). Throws
   *  InputError without a fluid or for a bad gamma. */
  void set_lb_coupling(double gamma, std::uint64_t seed);
  void lb_coupling_off() {
    m_lb_coupling.active = false;
    invalidate_forces();
  }
  /** The lattice-Boltzmann fluid, null without one. */
  const std::shared_ptr<lb::LBFluid>& fluid() const { return m_lb; }
  /** Collective: the fluid's momentum less the coupling impulse still in
   *  flight to the particles (CouplingLedger), so that particle + fluid
   *  momentum is conserved to round-off at every step; zero without a
   *  fluid. */
  Vec3 fluid_momentum() const;
  /** Sets or (null) removes the fluid; removing it switches the coupling off. */
  void set_lb(std::shared_ptr<lb::LBFluid> fluid);

  // --- integration ------------------------------------------------------------
  /** n velocity-Verlet steps, all in C++. */
  void integrate(int n_steps, bool recalc_forces = false, bool reuse_forces = false);
  /** The explicit collective set-up step (every rank calls it): flags the
   *  lattice for boundaries set since the last one, which may move the
   *  ranks' cuts (load balance) and the populations with them. integrate()
   *  calls it first; queries never do (they throw while boundaries are
   *  pending: LBFluid::require_flagged). */
  void prepare();
  /** Throws SimulationInstability naming the fastest particle (a drift, in
   *  the given step, of
   *  more than half the box, or with pair contacts more than the skin, in
   *  one step of length dt). */
  [[noreturn]] void report_fast_particle(double dt, std::uint64_t step) const;
  /** Throws SimulationInstability ("membrane_crossing") when the pair's two
   *  membrane nodes lie each behind the other's membrane. */
  void check_membrane_crossing(const PairContext& c, int id_i, int id_j) const;
  /** hard_contact's guard gaps from the time step and the lightest particle
   *  of each type (hard_contact.hpp), at the start of every run. */
  void update_contact_guards();
  /** A pair model's error (hard_contact's "contact_overrun") with the pair's
   *  particles, cells (or the wall) and the time. */
  /** Rethrows a contact_overrun of the pair loop with the pair that caused
   *  it (found again; returns when none is found). */
  void name_contact_overrun(const SimulationInstability& error) const;
  [[noreturn]] void rethrow_pair_error(const SimulationInstability& e, int id_i, int id_j,
                                       const PairContext& c, const std::string& wall) const;
  /** Called by integrate every 16 steps, where the particles are as at the
   *  end of a step; an exception it throws ends the run there, in the state
   *  of a run asked for that many steps (forces valid: a later run goes on
   *  bit for bit as after a split run). The Python binding uses it for
   *  Ctrl-C. Empty: never called. */
  std::function<void()> interruption_point;
  /** The cells' checks in the steps of a run, the first and every 8th
   *  (inverted triangles, membranes crossed,
   *  collapsed or exploded volumes: SimulationInstability; volume or surface
   *  drift beyond membranes.drift_tolerance: a note, see take_drift_notes).
   *  Force and energy evaluations outside a run's steps are not checked. */
  bool cell_checks = true;
  /** Where the runs' time went (wall clock, seconds), summed over the runs
   *  since the System was made or the last reset (LAMMPS prints such a
   *  breakdown after each run). total: all of integrate(); the phases are
   *  parts of it, the rest (velocity Verlet, neighbour rebuilds, checks) is
   *  total minus their sum. Force computations outside runs are not
   *  counted. Six clock reads per step (eight with a lattice update):
   *  nothing against a step's cost. */
  struct RunTimings {
    std::uint64_t steps = 0;
    double total = 0.0, membrane = 0.0, bonded = 0.0, non_bonded = 0.0, constraints = 0.0,
           coupling = 0.0, lb_fluid = 0.0;
  };
  RunTimings run_timings;
  /** Recompute all forces for the current positions (no time advance). */
  void compute_forces();
  Energies compute_energies();
  Vec3 particle_momentum() const;
  /** The forces of the last step no longer hold: the next run recomputes
   *  them before its first half kick. The methods above call it for what
   *  they change; a caller that writes `particles` (positions, velocities,
   *  external forces, types) directly must call it. */
  void invalidate_forces() { m_forces_valid = false; }
  /** The stored forces are those of the current state (a run or a force
   *  calculation made them, nothing changed since). */
  bool forces_valid() const { return m_forces_valid; }
  /** Number of MD steps per lattice update (tau / time_step). */
  int lb_steps_per_update() const;

  // --- checkpoints (system/checkpoint.cpp) ------------------------------------
  /** MD steps since the last lattice update. */
  int lb_substep() const { return m_lb_substep; }
  /** Collective. The run state of a checkpoint, once the configuration, the
   *  particles (in the saved local order), the bonds and the fluid are back:
   *  folded positions and images, forces and normals of the last step (per
   *  local index), the positions of the last re-sort (empty: none valid) and
   *  the MD steps since the last lattice update. Re-sorts at the reference
   *  positions, so the pair list is that of the saved run, then puts the
   *  particles where they were and marks the forces valid: the next run goes
   *  on as the saved run would have, bit for bit. */
  void restore_run_state(const std::vector<Vec3>& folded_pos, const std::vector<Vec3i>& image,
                         const std::vector<Vec3>& force, const std::vector<Vec3>& normal,
                         const std::vector<Vec3>& rebuild_reference, int lb_substep,
                         bool forces_valid = true);

  // --- particles over the ranks of a decomposed lattice (system_parallel.cpp)
  // Every rank stores every particle (same local indices everywhere), but
  // with a decomposed fluid each particle is integrated, and its forces
  // computed, by one rank: the rank whose subdomain holds the lattice node
  // of its cell's first node (a whole cell on one rank, with the membrane
  // driver's lanes), or of its own position. The other ranks' copies are
  // kept current only where needed (coupling stencils, pair contacts,
  // bonds across ranks), point to point every step; at a re-sort the owners
  // send their particles to the ranks within reach (resort_spread), and all
  // copies are made current before a query (synchronize).
  /** Whether the particles are spread over the ranks. */
  bool particles_spread() const { return m_spread.active; }
  /** Collective: makes every rank's copy of every particle current (before
   *  reading or writing particles from Python). */
  void synchronize();
  /** Per local index: this rank integrates the particle (null: all). */
  const std::uint8_t* owned_mask() const {
    // none before the first assignment after particles were added or
    // removed (every copy is current then)
    return m_spread.active && m_spread.layout == particles.layout_version &&
                   m_spread.owned.size() == particles.n_local()
               ? m_spread.owned.data()
               : nullptr;
  }
  /** The particles this rank integrates as runs [first, second) of
   *  consecutive local indices, ascending (all particles: one run). Made
   *  with the owned mask, at the assignments of owners: the per-step passes
   *  (Verlet, Langevin, walls) then do no work for other ranks' particles. */
  const std::vector<std::pair<std::size_t, std::size_t>>& owned_runs() const;
  /** Ranks of the particles' spread (the world under a decomposed fluid). */
  const Communicator& spread_comm() const { return m_spread.comm; }

private:
  /// owned_runs() where every particle is this rank's: [0, n), or none
  mutable std::vector<std::pair<std::size_t, std::size_t>> m_all_particles_run;

  /** The spread of the particles (particles_spread()). */
  struct Spread {
    bool active = false;
    Communicator comm{MPI_COMM_SELF};
    std::vector<int> owner;          ///< per local index (-1: current everywhere)
    std::vector<std::uint8_t> owned; ///< owner == this rank (or -1)
    /// the runs of consecutive owned particles (owned_runs), with `owned`
    std::vector<std::pair<std::size_t, std::size_t>> owned_runs;
    std::vector<std::uint8_t> current; ///< owned or received every step
    struct Peer {
      int rank;
      std::vector<int> send, recv; ///< local indices, sorted
      std::vector<double> send_buffer, recv_buffer;
    };
    std::vector<Peer> peers;
    bool stale = false;        ///< copies out of date since the last run
    std::uint64_t version = 0; ///< counts changes of the owned set (membrane cache key)
    std::uint64_t layout = 0, mol = 0, bonds = 0; ///< the versions at the assignment
    /// per local index the particle whose position decides the owner (a
    /// cell's first node), and the bonds that can join two owners (count,
    /// then local indices); for the versions below
    std::vector<int> reference, cross_bonds;
    /// at the last re-sort: the particles whose state this rank held
    /// current (owned, and within reach; empty after a full gather: all)
    std::vector<std::uint8_t> binned;
    std::uint64_t topology_layout = 0, topology_mol = 0, topology_bonds = ~std::uint64_t{0};
    std::array<std::vector<int>, 3> cuts; ///< the lattice's cuts at the assignment
  };
  Spread m_spread;
  /** Switches the spread on or off with the fluid (collective). */
  void update_spread();
  /** Every rank sends its particles' state to all (allgather). */
  void gather_all_particles();
  /** The rank whose lattice subdomain holds position x. */
  int rank_of_position(const Vec3& x) const;
  /** Spread.reference and cross_bonds, when the particles or bonds changed. */
  void update_topology();
  /** Owners from the current state (all ranks alike), before a re-sort. */
  void assign_owners();
  /** Spread.owned from Spread.owner, its runs, and the version when it changed. */
  void set_owned();
  /** The point-to-point lists, after the re-sort. */
  void build_exchange_lists();
  /** A re-sort that moves only the particles that change owner and those
   *  within reach of other ranks (no gather of all). */
  void resort_spread();
  /** Sends the owners' positions and velocities (or normals) to the ranks
   *  that keep copies. */
  void exchange_current(bool normals);
  /** The coupling's forces to their particles' owners (CouplingDistribution). */
  void share_coupling_forces(std::vector<Vec3>& force, const std::vector<int>& giver,
                             const std::vector<std::uint32_t>* listed);
  /** Largest code over the ranks (one allreduce; the code itself on one rank). */
  int agree(int code) const;
  /** Whether any membrane bond exists (the same on every rank). */
  bool has_membrane_bonds() const;
  /** Raises on every rank the error of the lowest failing rank (collective
   *  where there are particles; without, every rank fails alike and raises
   *  its own; local: this rank's error or null). Returns when no rank failed. */
  void raise_agreed(const std::exception_ptr& local) const;
  /** Re-sort if needed and update ghosts. moved: the integrator's drift
   *  already tested the displacements (1 beyond the skin, 0 not); -1: test. */
  void prepare_step(int moved = -1);
  /** All forces; forces_preset: the local forces already hold the external
   *  forces (the integrator's fused pass set them); timings: where the
   *  phases' time is added (the time steps of a run), or none. */
  template <bool with_energy>
  void force_loop(Energies* e, bool forces_preset = false, RunTimings* timings = nullptr);
  /** The membrane phase: every OIF bond through the membrane component
   *  (forces, node normals; with e the energies per bonded interaction). */
  void add_membrane_forces(Energies* e);
  /** The generic bonds (bond_loop.hpp). */
  void add_bonded_forces(Energies* e);
  void add_nonbonded_forces(Energies* e);
  void add_constraint_forces(Energies* e);
  void add_langevin_forces();
  std::vector<std::shared_ptr<ShapeBasedConstraint>> m_constraints;
  LangevinParams m_langevin;
  LBCouplingState m_lb_coupling;
  std::shared_ptr<lb::LBFluid> m_lb;
  /// the fluid's state_version() and the constraints' shape versions when
  /// the forces were last made valid
  std::uint64_t m_fluid_version_of_forces = 0, m_shape_version_of_forces = 0;
  std::uint64_t constraint_shape_version() const {
    std::uint64_t v = 0;
    for (const auto& c : m_constraints)
      v += c->shape ? c->shape->version() : 0;
    return v;
  }
  /** The forces hold for the current state, the fluid's and shapes' included. */
  void mark_forces_valid() {
    m_forces_valid = true;
    m_fluid_version_of_forces = m_lb ? m_lb->state_version() : 0;
    m_shape_version_of_forces = constraint_shape_version();
  }
  /// a constraint's signed distances by local index (spread over ranks: only this
  /// rank's entries are written and read), one constraint at a time
  std::vector<double> m_constraint_dist;
  /// the constraints' runs of up to 32 of this rank's particles and the
  /// box around each (infinite where a position is not finite)
  struct ConstraintChunk {
    std::size_t begin, end;
    Vec3 lo, hi;
  };
  std::vector<ConstraintChunk> m_constraint_chunks;
  std::uint64_t m_bonds_version = 0;
  double m_time_step = 0.01;
  bool m_forces_valid = false;
  bool m_checks_due = false; ///< the cells' checks run in this step (cell_checks)
  int m_lb_substep = 0;
};

} // namespace pyoif
