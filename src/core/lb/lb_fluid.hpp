// Lattice-Boltzmann D3Q19 fluid on a cubic lattice with one ghost (halo) layer.
//
// Padded node index n = (z * Py + y) * Px + x with x, y, z in [0, N + 1]
// (0 and N + 1 are the ghost layer; the lattice node (i, j, k) of the
// domain is padded node (i + 1, j + 1, k + 1) and sits at position
// ((i, j, k) + 1/2) * agrid). The populations, their in-place (AA) update
// parity and their precision are PopulationStorage's
// (population_storage.hpp); every node access goes through m_pop.slot().
// After an even update the ghost layer is filled from the periodic images
// (the odd update reads it); after an odd update what was pushed into the
// ghost layer is folded back into the domain. Halfway bounce-back on the
// precomputed fluid-solid links (Ladd 1994, moving walls by the momentum
// term) follows either halo step.
//
// Domain decomposition (MPI): the lattice is split into a Cartesian grid of
// subdomains (DomainGrid), one per rank; each rank stores its subdomain with
// the ghost layer around it, flags its own nodes and ghosts from the shapes,
// and the halo steps above exchange exactly the populations that cross a
// subdomain face, edge or corner: with the neighbouring rank in one message
// per neighbour (packed in an order both sides derive from the shared
// cuts), or as the copies above where the neighbour is the rank itself. The
// update is node-local and the exchange copies values, so a decomposed run
// is bit for bit the serial one. Node (i, j, k) below is always the global
// lattice node; padded indices are this rank's.
//
// Precision: every function that touches the populations is a template on
// the stored type (Real: double, or float as deviations from the rest
// state), chosen once per call by m_pop.visit(), outside the node loops.
//
// Units: populations are mass densities (the unit of `dens`); velocities in
// the kernel are lattice velocities u * tau / agrid, force densities are
// momentum-density changes per update in those units, F * tau^2 / agrid.
#pragma once

#include "communication/domain_grid.hpp"
#include "communication/shared_segment.hpp"
#include "lb/boundary_links.hpp"
#include "lb/collide_stream.hpp"
#include "lb/coupling_nodes.hpp"
#include "lb/halo_plan.hpp"
#include "lb/lb_lattice.hpp"
#include "lb/population_storage.hpp"
#include "lb/speed_watch.hpp"
#include "shapes/shape.hpp"
#include "system/box_geometry.hpp"
#include "utils/vector.hpp"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace pyoif::lb {

/** mrt: DSL's MRT with the odd ghost modes at the magic rate (default, wall
 *  position independent of viscosity); mrt_espresso: every ghost mode at
 *  rate 1 (ESPResSo 4.2's choice); trt: magic TRT; bgk: one rate. */
enum class Collision { mrt, mrt_espresso, trt, bgk };

/** Parameters in MD units (ESPResSo 4.2 names). */
struct LBParams {
  double agrid = 1.0;
  double tau = 1.0;
  double density = 1.0;        ///< mass per volume
  double viscosity = 1.0;      ///< kinematic, length^2 / time
  double bulk_viscosity = 1.0; ///< kinematic (MRT only; BGK and TRT tie it to visc)
  Vec3 ext_force_density = Vec3::Zero();
  double kT = 0.0;
  std::uint64_t seed = 0;
  Collision collision = Collision::mrt;
  int n_threads = 0; ///< 0: OMP_NUM_THREADS if set, else 1
  /// populations stored as float, as deviations from the rest state at
  /// `density`, and collided in float: half the memory and traffic
  bool single_precision = false;
};

/** Second-order equilibrium (Qian et al. 1992) of population q at density
 *  rho and lattice velocity u. */
inline double equilibrium(int q, double rho, const Vec3& u) {
  const auto& cq = d3q19::c[q];
  const double cu = cq[0] * u[0] + cq[1] * u[1] + cq[2] * u[2];
  return d3q19::w[q] * rho * (1.0 + 3.0 * cu + 4.5 * cu * cu - 1.5 * u.squaredNorm());
}

/** An open face of the lattice (lb_open_boundary.cpp): the node plane at the
 *  low or high end of `axis` takes, after every update, the populations of
 *  the non-equilibrium extrapolation scheme (Guo, Zheng & Shi, Chin. Phys.
 *  11, 366 (2002)): the equilibrium at the face's density and velocity plus
 *  the non-equilibrium part of the next node inward. A velocity inlet gives
 *  the velocity per node (the density is the inward neighbour's), a
 *  pressure outlet the density (the velocity is the inward neighbour's). */
struct OpenBoundarySpec {
  int axis = 0;
  bool high = false; ///< the face at the high end of the axis
  bool pressure = false;
  /// velocity inlet: 3 values (MD units) per node of the face plane, the two
  /// other axes in increasing order, the second fastest
  std::vector<double> velocity;
  double density = 0.0; ///< pressure outlet (MD units)
  /// velocity inlet with a flow rate (volume per time, MD units; 0: none):
  /// the velocities are scaled by `gain`, which every update moves towards
  /// the flow through the plane next to the face (lb_open_boundary.cpp)
  double flow_rate = 0.0;
  double gain = 1.0;
};

/** Post-collision = equilibrium + lambda (pre - equilibrium) per mode group;
 *  lambda = 1 - omega, omega the relaxation rate. */

using Populations = std::array<double, d3q19::Q>;
using Mat3 = Eigen::Matrix3d;

class LBFluid {
public:
  /** Throws InputError for a bad parameter or a box not divisible by agrid.
   *  The lattice is split over the ranks of comm (collective): node_grid
   *  ranks per axis (all zero: chosen by DomainGrid), cuts moved to balance
   *  the fluid nodes when boundaries are first set if balance_fluid. */
  LBFluid(const LBParams& params, const BoxGeometry& box, MPI_Comm comm = MPI_COMM_SELF,
          const Vec3i& node_grid = Vec3i::Zero(), bool balance_fluid = true);
  LBFluid(const LBFluid&) = delete;
  LBFluid& operator=(const LBFluid&) = delete;

  double agrid() const { return m_p.agrid; }
  double tau() const { return m_p.tau; }
  const LBParams& params() const { return m_p; }
  /** Populations stored as float (true) or double. */
  bool single_precision() const { return m_p.single_precision; }
  const Relaxation& relaxation() const { return m_relax; }
  /** The global lattice (nodes per axis). */
  const Vec3i& grid() const { return m_global; }
  /** This rank's subdomain: first global node and extent. */
  const Vec3i& local_origin() const { return m_origin; }
  const Vec3i& local_grid() const { return m_n; }
  const DomainGrid& domain() const { return m_grid; }
  bool distributed() const { return m_grid.size() > 1; }
  std::uint64_t n_updates() const { return m_updates; }
  /** Sets the update counter (the thermal noise's counter), from a checkpoint. */
  void set_n_updates(std::uint64_t n) {
    m_updates = n;
    ++m_state_version;
  }
  /** Changes whenever the populations, the boundaries or ext_force_density
   *  change (every update, every setter): System recomputes the coupling
   *  forces when a run starts from a fluid changed since the last one. */
  std::uint64_t state_version() const { return m_state_version; }
  int n_threads() const { return m_threads; }
  void set_n_threads(int n);
  void set_ext_force_density(const Vec3& f);

  /** Throws InputError when the fluid does not fit the box (box_l a multiple
   *  of agrid, unchanged since creation) or tau is not a multiple of time_step. */
  void validate(const BoxGeometry& box, double time_step) const;
  /** One lattice update: collide with the force density accumulated since the
   *  last update (+ ext_force_density), stream, bounce back; clear the force
   *  field. Throws SimulationInstability naming node and update on a
   *  non-positive or non-finite density or a speed >= the lattice sound speed;
   *  that update is abandoned half done, and every later call throws too. */
  void step();
  /** The speed watch (speed_watch.hpp): a pass over the fluid nodes every
   *  `every` updates (0: off) for the fastest node. */
  int speed_watch_every() const { return m_speed_watch.every; }
  void set_speed_watch_every(int every);
  /** Collective: the fastest node any rank's watch saw since the last call
   *  (the lowest rank's on a tie), then every rank's watch starts afresh. */
  SpeedWatch take_speed_watch();
  /** Throws SimulationInstability (with the first failure's message) once an
   *  update has failed: System::integrate calls it before anything moves. */
  void check_usable() const;
  /** Momentum of the populations plus the impulse accumulated in the force
   *  field that the next update will apply (particle coupling), MD units.
   *  The coupling's impulse still in flight to the particles is the
   *  coupling's to subtract (System::fluid_momentum). No half-force term: a uniform
   * ext_force_density raises it by exactly F V tau per update, and particle + fluid momentum is
   * conserved to round-off. */
  Vec3 total_momentum() const;
  double total_mass() const;

  // --- boundaries -------------------------------------------------------------
  // set_boundaries() checks its input and records the list; the nodes are
  // flagged (and the fluid runs, bounce-back links, halo lists and the load
  // balance with its repartition derived) by update_boundaries(), one
  // explicit collective step that only System::prepare() calls (Python's
  // system.prepare(), and the start of every run). Adding N boundaries one
  // by one thus flags once. Everything that reads the flags or what derives
  // from them checks require_flagged() and throws while boundaries are
  // pending: no query ever turns into a collective call.
  /** Replaces all boundaries (flagged later, see above); nodes that become
   *  fluid start at rest at `dens`. Throws InputError at once for a null
   *  shape, a non-finite velocity or too many boundaries. */
  void set_boundaries(const std::vector<BoundarySpec>& boundaries);
  /** Replaces the open faces (collective; checked: the plane sizes). A
   *  face may be open alone on its axis where the opposite face is closed
   *  by walls: open_seam_leaks() tells, once the lattice is flagged. */
  void set_open_boundaries(const std::vector<OpenBoundarySpec>& faces);
  /** Collective, on a flagged lattice: per open face, 0 where the opposite
   *  face is open too or closed; else how many fluid nodes of the opposite
   *  face meet fluid nodes of this one across the periodic edge (the
   *  lattice's streaming would carry the open face's rewritten populations
   *  into them: a leak). */
  std::vector<long> open_seam_leaks() const;
  const std::vector<OpenBoundarySpec>& open_boundaries() const { return m_open; }
  /** The flow-rate inlets' gains (a checkpoint keeps them). */
  std::vector<double> open_boundary_gains() const;
  void set_open_boundary_gains(const std::vector<double>& gains);
  /** Mass flux (MD units: mass per time) into the lattice at open face i,
   *  through the node plane next to the face; collective. */
  double open_boundary_mass_flux(std::size_t i) const;
  /** Collective: flags the nodes for the boundaries of the last
   *  set_boundaries(), if not done yet (else nothing). One pass over the
   *  nodes per boundary's bounding box; a node belongs to the first
   *  boundary in the list that contains its centre. Throws InputError
   *  naming the boundaries when they leave no fluid node (the boundaries
   *  stay pending: every later call throws until they change). */
  void update_boundaries();
  /** Whether set_boundaries() was called since the last flagging. */
  bool boundaries_pending() const { return m_boundaries_pending; }
  /** Throws InputError, naming `what` and system.prepare(), while
   *  boundaries are pending (local: never communicates). */
  void require_flagged(const char* what) const;
  /** Number of flagging passes so far (set-up cost; tests of laziness). */
  std::uint64_t n_flaggings() const { return m_n_flaggings; }
  /** Force of the fluid on boundary b in the last update (momentum exchange). */
  Vec3 boundary_force(int b) const;
  /** Over all ranks. */
  std::size_t n_fluid_nodes() const {
    require_flagged("the number of fluid nodes");
    return m_n_fluid_global;
  }
  std::size_t n_links() const {
    require_flagged("the number of bounce-back links");
    return m_n_links_global;
  }
  /** Bytes this rank sends to other ranks in one population halo exchange. */
  std::size_t halo_bytes() const;
  /** Neighbouring ranks whose population halo goes through shared memory
   *  (the others' through MPI messages). */
  int shared_halo_peers() const;
  /** Seconds this rank spent in the population halo exchanges with other
   *  ranks, waiting included (not the periodic copies within the rank). */
  double halo_seconds() const { return m_halo_seconds; }
  /** Seconds this rank spent in the coupling's exchanges with other ranks
   *  (ghost velocities, particle forces), waiting included. */
  double coupling_exchange_seconds() const { return m_coupling_exchange_seconds; }
  void add_coupling_exchange_seconds(double s) const { m_coupling_exchange_seconds += s; }

  // --- node access: (i, j, k) in [0, N) ----------------------------------------
  // Node accessors give the node's values on the rank that owns it (check
  // owns()); setters write on the owner and are no-ops elsewhere, after the
  // same checks on every rank. get_block/set_block/gather_* are collective.
  /** Padded index of global node (i, j, k) when this rank owns it, else npos. */
  std::size_t owned_index(const Vec3i& node) const;
  bool owns(const Vec3i& node) const { return owned_index(node) != npos; }
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);
  /** Collective: property values of the block lo <= node < hi, (x, y, z,
   *  component) order with z fastest, the same on every rank. prop:
   *  velocity, density, boundary, population, pressure_tensor; for
   *  checkpoints also stored_population (the 19 stored values, exact: in
   *  single precision the float deviations from the rest state) and
   *  coupling_field (per node: 1 where the particles deposited since the
   *  last update, else 0, and the 3 deposited values). */
  std::vector<double> get_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi) const;
  /** Collective: sets velocity, density or population on the block; a block
   *  of several nodes skips boundary nodes, a single boundary node is an
   *  error on every rank. stored_population and coupling_field (see
   *  get_block) are set on every node of the block. */
  void set_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                 const std::vector<double>& values);
  /** Collective: get_block's values on rank `root` only (empty elsewhere).
   *  Each rank sends the nodes it owns, so no other rank holds more than its
   *  own part of the block (checkpoints and VTK fields, whose writer alone
   *  needs them). The root holds the block and one rank's part at a time. */
  std::vector<double> gather_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                                   int root) const;
  /** Collective: set_block of a checkpoint's raw state (stored_population,
   *  coupling_field) with the values given on rank `root` only (ignored
   *  elsewhere): each rank receives the nodes it owns. The root holds the
   *  values and one rank's part at a time, no more. */
  void scatter_block(const std::string& prop, const Vec3i& lo, const Vec3i& hi,
                     const double* values, std::size_t count, int root);
  /** -1 for a fluid node, else the index of the boundary. */
  int node_boundary(const Vec3i& node) const;
  double node_density(const Vec3i& node) const;
  /** (j + F_ext tau / 2) / rho, the velocity of the Guo-forcing scheme. */
  Vec3 node_velocity(const Vec3i& node) const;
  Populations node_populations(const Vec3i& node) const;
  Mat3 node_pressure_tensor(const Vec3i& node) const;
  void set_node_populations(const Vec3i& node, const Populations& f);
  /** Sets the equilibrium populations of density rho and velocity u. */
  void set_node_density_velocity(const Vec3i& node, double rho, const Vec3& u);

  // --- particle coupling (lattice indices are padded node indices) -----------
  /** Padded index of a node given by local coordinates in [-1, n] (no folding). */
  std::size_t padded_index_in_box(int i, int j, int k) const { return index(i + 1, j + 1, k + 1); }
  /** Whether padded index n, a node a coupling stencil reaches, is a ghost
   *  (another rank's node): a table lookup, read for every node of every
   *  coupling pass (the coordinates would cost three integer divisions).
   *  A stencil reaches the ghost layer only across split axes (on the
   *  others it wraps onto this rank's own nodes), where every ghost has a
   *  velocity slot. */
  bool is_stencil_ghost(std::size_t n) const {
    return !m_halo.ghost_slot.empty() && m_halo.ghost_slot[n] != HaloPlan::no_ghost_slot;
  }
  /** A fluid ghost node: its velocity is its owner's (a solid one's is the
   *  boundary's, known here). */
  bool is_fluid_ghost(std::size_t n) const { return !m_flag[n] && is_stencil_ghost(n); }
  /** Collective: refreshes the velocities of the ghost-layer nodes from the
   *  ranks that own them, when the fluid changed since the last time (the
   *  coupling's stencils reach one node into the ghost layer). */
  void refresh_ghost_velocities();
  /** Velocity (MD units) at padded index n, ghost nodes of a decomposed
   *  lattice included (from refresh_ghost_velocities). */
  Vec3 coupling_velocity(std::size_t n) const {
    if (is_fluid_ghost(n))
      return m_halo.ghost_velocity[m_halo.ghost_slot[n]];
    return velocity_at_index(n);
  }
  /** Difference of the padded indices of neighbours along axis d. */
  std::ptrdiff_t padded_axis_stride(int d) const {
    return d == 0 ? 1 : d == 1 ? m_pad[0] : static_cast<std::ptrdiff_t>(m_pad[0]) * m_pad[1];
  }
  /** Number of padded node slots (bound of every padded index). */
  std::size_t n_padded_slots() const { return m_pop.stride(); }
  /** Node velocity in MD units at a padded index (boundary velocity on solid nodes). */
  inline Vec3 velocity_at_index(std::size_t n) const;
  /** Bulk deposits: open_impulse_field() switches the force field on for the
   *  next update (allocating it on first use); then add_field_impulse(n, p)
   *  adds p = impulse (MD units) * impulse_scale() at padded index n. */
  void open_impulse_field();
  double impulse_scale() const {
    const double a2 = m_p.agrid * m_p.agrid;
    // momentum-density change per update in lattice units: p / agrid^3 * tau / agrid
    return m_p.tau / (a2 * a2);
  }
  void add_field_impulse(std::size_t n, const Vec3& p) {
    double* g = m_field.data() + 3 * n;
    std::uint64_t& word = m_field_valid[n >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (n & 63);
    if (word & bit) {
      g[0] += p[0];
      g[1] += p[1];
      g[2] += p[2];
    } else { // the node's first deposit of this update interval
      g[0] = p[0];
      g[1] = p[1];
      g[2] = p[2];
      word |= bit;
    }
  }
  /** Requests the field line of padded index n (a later add_field_impulse). */
  void prefetch_field(std::size_t n) const { __builtin_prefetch(m_field.data() + 3 * n, 1, 3); }
  /** The coupling stencils' steps (StencilSteps). */
  StencilSteps stencil_steps() const {
    StencilSteps st;
    for (int d = 0; d < 3; ++d) {
      st.plain[d] = padded_axis_stride(d);
      st.wrapped[d] = padded_axis_stride(d) * (1 - m_n[d]); // undecomposed axes only
    }
    return st;
  }
  /** Velocity-at for a coupling pass: for each node n of the list (`node`,
   *  mostly in increasing index order): node_coupling[compact[n]] =
   *  {velocity_at_index(n), 0}, with the populations of nodes further down
   *  the list prefetched. On a decomposed lattice the fluid ghost nodes of
   *  the list take their velocities from their owners instead (collective
   *  while ghosts_pending: exchange_coupling_ghosts). */
  void velocities_at(CouplingNodes& nodes);
  /** Collective, once per coupling pass on a decomposed lattice: sends each
   *  neighbour the velocities of this rank's face nodes that its own list
   *  holds (with_values; else nothing, for a pass that failed) and writes
   *  those received into the list's ghost entries. A neighbour's particle
   *  whose stencil reaches a ghost node of this rank touches that node's
   *  owner's subdomain, so the owner keeps the particle current and lists
   *  the node too: the owner's list covers every ghost the neighbour reads,
   *  and no node list needs to be agreed on beforehand. */
  void exchange_coupling_ghosts(CouplingNodes& nodes, bool with_values);
  /** Changes whenever the subdomain is laid out anew (construction, a
   *  repartition): padded indices the coupling holds are stale then. */
  std::uint64_t layout_generation() const { return m_layout_generation; }
  /** The coupling tells the lattice (every rank, every pass) that its
   *  records now hold this rank's node indices: the load balance no longer
   *  moves the cuts (a pass's in-flight deposit could not be taken back). */
  void note_coupling() { m_coupled = true; }

  // --- output -----------------------------------------------------------------
  /** Collective: rank 0 writes; an error there is raised on every rank. */
  void write_vtk_velocity(const std::string& path) const;
  void write_vtk_boundary(const std::string& path) const;

private:
  using Run = FluidRun;
  /** This rank's subdomain with its ghost layer (boundary_links.hpp). */
  PaddedBox padded_box() const { return {m_global, m_origin, m_n, m_pad}; }
  std::size_t index(int x, int y, int z) const { // as PaddedBox::index
    return (static_cast<std::size_t>(z) * m_pad[1] + y) * m_pad[0] + x;
  }
  /** Padded (x, y, z) of a padded node index. */
  Vec3i padded_coordinates(std::size_t n) const {
    const std::size_t px = static_cast<std::size_t>(m_pad[0]),
                      py = static_cast<std::size_t>(m_pad[1]);
    return Vec3i(static_cast<int>(n % px), static_cast<int>((n / px) % py),
                 static_cast<int>(n / (px * py)));
  }
  /** Throws InputError for a node outside [0, N); returns owned_index(node). */
  std::size_t checked_node(const Vec3i& node) const;
  /** Collective: property prop of every node as VTK structured points, by rank 0. */
  void write_vtk_field(const std::string& path, const std::string& prop) const;
  /** Throws InputError unless lo <= node < hi is a non-empty block of the lattice. */
  void check_block(const Vec3i& lo, const Vec3i& hi) const;
  /** The values of node property `prop` at a node this rank owns. */
  void node_values(const std::string& prop, const Vec3i& node, double* out) const;
  /** Sets a settable property at `node` where this rank owns it (solid
   *  nodes: the raw state only); no checks, no state-version count. */
  void set_node_values(const std::string& prop, const Vec3i& node, const double* v);
  /** The part of block [lo, hi) that rank r owns (gather/scatter_block). */
  void block_part(int r, const Vec3i& lo, const Vec3i& hi, Vec3i& first, Vec3i& extent) const;
  /** Flags of this rank's padded nodes (ghosts too) for these boundaries
   *  (flag_nodes: each boundary visits only the nodes of its bounding box
   *  that no earlier boundary took). */
  std::vector<std::uint16_t> flags_for(const std::vector<BoundarySpec>& boundaries) const {
    return flag_nodes(boundaries, padded_box(), m_p.agrid);
  }
  /** Allocates the populations (rest state at dens) and flags for the grid's subdomain. */
  void allocate_subdomain();
  /** Moves the populations to the grid's new cuts (collective). */
  void repartition(const DomainGrid& old_grid);
  void rebuild_geometry();
  void build_halo_pairs();
  /** Sets up the shared-memory halo with each neighbouring rank on this
   *  machine (both must map the other's segment; else messages). Pairwise
   *  with the neighbours, called by every rank in build_halo_pairs.
   *  PYOIF_HALO_SHARED=0 in the environment keeps the messages. */
  void connect_shared_halo();
  /** Packs this update's sends to the shared-memory neighbours into this
   *  rank's segment (before the update's agreement, which is also what
   *  tells the neighbours the values are there). */
  template <typename Real> void pack_shared_halo(const Real* f, bool fill_ghosts) const;
  /** Nodes of the ghost region o of the subdomain (lower, extent), in the
   *  order both neighbours list them: (global node, q) for every q moving
   *  into the region when with_q (the population halo: fluid pairs only),
   *  else every node once with q = 0. */
  template <class Visit>
  void visit_region(const Vec3i& lower, const Vec3i& extent, const Vec3i& o, bool with_q,
                    Visit&& visit) const;
  /** This rank's padded index of global node g that lies in its subdomain. */
  std::size_t domain_index(const Vec3i& g) const;
  /** Sends/receives the remote part of a halo step (fill_ghosts: faces to
   *  the neighbours' ghosts, else ghosts folded into the neighbours' faces). */
  template <typename Real> void exchange_remote(Real* f, bool fill_ghosts) const;
  template <typename Real> void apply_bounce_back(Real* f) const;
  /** The open faces' populations after an update (lb_open_boundary.cpp). */
  void apply_open_boundaries();
  /** Mass and volume per time through the node plane next to open face
   *  `face`, into the lattice (MD units); collective. */
  std::pair<double, double> open_boundary_fluxes(const OpenBoundarySpec& face) const;
  /** Calls body(padded node, global node, plane offset) for each fluid node
   *  of open face `face` that this rank owns. */
  template <class Body> void for_each_open_node(const OpenBoundarySpec& face, Body&& body) const;
  std::vector<OpenBoundarySpec> m_open;
  /** Rewrites a swapped lattice in the normal layout (rare: geometry changes). */
  void normalize_layout();
  /** fill_ghosts: copy the domain into the ghost layer (after an even update);
   *  else fold the ghost layer into the domain (after an odd update). */
  template <typename Real> void halo_exchange(Real* f, bool fill_ghosts) const;
  /** step() on the populations stored as Real. */
  template <typename Real> void step_stored_as(Real* f);
  /** Throws SimulationInstability for the bad node; step() refuses to run
   *  after it (m_failed_update). */
  [[noreturn]] void report_instability(const BadNode& bad);
  /** One pass of the speed watch (after an update). */
  void watch_speed();
  inline void moments(std::size_t n, double& rho, Vec3& j) const;
  template <typename Real>
  inline void moments_of(const Real* populations, std::size_t n, double& rho, Vec3& j) const;

  LBParams m_p;
  Relaxation m_relax{};
  Vec3 m_box;
  DomainGrid m_grid;
  bool m_balance = true;
  Vec3i m_global, m_origin; ///< global lattice, this rank's first node
  Vec3i m_n, m_pad;         ///< this rank's extent, + 2 ghost layers
  /// the populations and the parity of the in-place update
  PopulationStorage m_pop;
  /// force density of the particle coupling, 3 components per node
  /// (node-major: one cache line per deposit; the kernel reads it per block).
  /// A node's entry holds a deposit only where its bit in m_field_valid is
  /// set; elsewhere it is stale and nobody reads it. So neither the update
  /// nor anything else clears the field itself: the first deposit of an
  /// update interval overwrites, the update reads only marked nodes, and
  /// clearing the bits (a bit per node, 1/192 of the field) resets it.
  std::vector<double> m_field;
  std::vector<std::uint64_t> m_field_valid;
  bool m_field_used = false;
  bool field_valid(std::size_t n) const { return (m_field_valid[n >> 6] >> (n & 63)) & 1u; }
  std::vector<std::uint16_t> m_flag;      ///< 0 fluid, b + 1 boundary b (ghosts too)
  std::vector<BoundarySpec> m_boundaries; ///< those the flags are of
  /// set by set_boundaries(), flagged by update_boundaries()
  std::vector<BoundarySpec> m_pending_boundaries;
  bool m_boundaries_pending = false;
  std::uint64_t m_n_flaggings = 0;
  /// runs, links and bounce-back made from the flags (rebuild_geometry)
  FluidGeometry m_geometry;
  std::size_t m_n_fluid_global = 0, m_n_links_global = 0;
  /// the halo's plan and buffers (halo_plan.hpp), made by build_halo_pairs
  HaloPlan m_halo;
  mutable double m_halo_seconds = 0.0, m_coupling_exchange_seconds = 0.0;
  std::array<std::ptrdiff_t, d3q19::Q> m_offset{};
  Vec3 m_ext_lattice = Vec3::Zero();
  double m_kT_lattice = 0.0;
  std::array<double, d3q19::Q> m_noise_factor{}; ///< 3 kT (1 - lambda_m^2) / b_m
  std::array<std::array<double, d3q19::Q>, d3q19::Q> m_basis{};
  std::uint64_t m_updates = 0;
  std::uint64_t m_state_version = 0;
  /// the message of the update that found a bad node (empty: none); that
  /// update was abandoned half done, so the fluid takes no more updates
  std::string m_failed_update;
  SpeedWatch m_speed_watch;
  std::uint64_t m_layout_generation = 0;
  bool m_coupled = false; ///< see note_coupling
  int m_threads = 1;
};

// Inline: the coupling's velocity pass calls these once per lattice node it
// needs, so the 19 sums belong in its loop.
inline void LBFluid::moments(std::size_t n, double& rho, Vec3& j) const {
  m_pop.visit([&](const auto* f) { moments_of(f, n, rho, j); });
}

template <typename Real>
inline void LBFluid::moments_of(const Real* populations, std::size_t n, double& rho,
                                Vec3& j) const {
  // the 19 loads with the layout's offsets, the velocity components known at
  // compile time after unrolling, so the zero ones drop out
  const std::ptrdiff_t* off = m_pop.read_offset();
  const Real* f = populations + n;
  double r = 0.0, jx = 0.0, jy = 0.0, jz = 0.0;
#pragma GCC unroll 19
  for (int q = 0; q < d3q19::Q; ++q) {
    const double v = f[off[q]];
    r += v;
    if (d3q19::c[q][0])
      jx += d3q19::c[q][0] * v;
    if (d3q19::c[q][1])
      jy += d3q19::c[q][1] * v;
    if (d3q19::c[q][2])
      jz += d3q19::c[q][2] * v;
  }
  if constexpr (std::is_same_v<Real, float>)
    r += m_p.density; // deviation storage: sum_q w_q rho0 = rho0
  rho = r;
  j = Vec3(jx, jy, jz);
}

inline Vec3 LBFluid::velocity_at_index(std::size_t n) const {
  if (m_flag[n])
    return m_boundaries[m_flag[n] - 1].velocity;
  double rho;
  Vec3 j;
  moments(n, rho, j);
  const double scale = m_p.agrid / m_p.tau / rho;
  return Vec3((j[0] + 0.5 * m_ext_lattice[0]) * scale, (j[1] + 0.5 * m_ext_lattice[1]) * scale,
              (j[2] + 0.5 * m_ext_lattice[2]) * scale);
}

} // namespace pyoif::lb
