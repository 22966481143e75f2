// The membrane component: every OIF membrane term (interactions/membrane/*.hpp:
// one parameter struct and one kernel per term, templated over the scalar
// type) evaluated cell by cell, by one driver, for the time step and for
// analysis alike.
//
// The OIF bonds (oif_bonds.hpp) are descriptions. compile() turns them into
//  - topologies: the tables of one kind of cell, as cell-local node numbers
//    (the cell's particle ids in increasing order), with the reference values
//    and moduli per edge and per triangle; cells with bit-for-bit the same
//    tables (the cells of an OifCellType) share one copy, which the pass then
//    reads from L1/L2 for every cell;
//  - cells: a mol_id, its topology, its nodes' local particle indices, and its
//    global-area and volume parameters;
//  - groups: the order of evaluation, four cells of one topology at a time,
//    one cell per vector lane (T = Lanes), or one cell (T = double).
// A cell is the mol_id of a bond's first particle (the bond's owner): an
// OifCellType's three interactions over one cell become one cell record, so
// its nodes are gathered once and each triangle is visited once for the local
// area, the cell's area and volume and the node normals.
//
// One evaluation (evaluate()), per group: gather the nodes' positions
// (unfolded, relative to the cell's first node: exact for a cell of any size,
// no minimum image per bond; where that spans more than half the box, as
// when a script set a node's position to its folded value, relative by the
// minimum image instead), the triangle pass, the cell's global area and
// volume factors, the area forces, the edge pass (stretching, viscosity,
// bending), then add the forces to the particles and write the normals; with
// reports, also each cell's area, volume and energy per term. The terms'
// equations are in their headers. A degenerate element or a non-finite
// force stops with a SimulationInstability naming the bond's particles, the
// cell and the time.
//
// Ownership under MPI (doc/architecture.md, "Parallel model"): a cell will
// be evaluated whole, by one rank; the driver already works on gathered
// per-cell node arrays (positions in, forces and normals out), which the
// domain decomposition will fill from local particles and received remote
// nodes. Today every node of a cell must be a local particle.
#pragma once

#include "interactions/bonded/bonded_registry.hpp"
#include "interactions/membrane/area.hpp"
#include "interactions/membrane/bending.hpp"
#include "interactions/membrane/lanes.hpp"
#include "interactions/membrane/stretching.hpp"
#include "interactions/membrane/viscosity.hpp"
#include "interactions/membrane/volume.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace pyoif::membrane {

/** The membrane terms, for analysis (energies per term, forces of one term). */
enum Term : int { stretching, bending, local_area, global_area, volume, viscosity, n_terms };
/** Their names as the Python API spells them. */
const char* term_name(int term);
/** The term of a name, -1 for none; InputError for an unknown name. */
int term_of(const std::string& name);

/** What the evaluation of one cell reports (analysis). */
struct CellReport {
  int mol_id = 0;
  double area = 0.0;   ///< of its OifGlobalForces (else OifOutDirection) triangles
  double volume = 0.0; ///< oriented: > 0 for outward triangle order
  std::array<double, n_terms> energy{};
};

/** Which bonds to compile, and how. */
struct Selection {
  int bond_id = -1;  ///< only this bonded interaction's bonds (-1: all membrane bonds)
  int mol_id = -1;   ///< only this cell's bonds (-1: all cells)
  int term = -1;     ///< only this term's moduli (-1: all)
  bool lanes = true; ///< batches of four cells per vector lane where a topology has them
  /// per local index: only the cells whose bonds' first particles this rank
  /// owns (particles spread over ranks; null: all)
  const std::uint8_t* owned = nullptr;
};

/** Counters of the evaluations, so that tests see which path ran. */
struct PassCounts {
  std::uint64_t compiles = 0;           ///< tables built from the bonds
  std::uint64_t lane_batches = 0;       ///< groups of four cells evaluated in vector lanes
  std::uint64_t padded_lanes = 0;       ///< lanes of those groups that repeat a cell
  std::uint64_t plain_cells = 0;        ///< cells evaluated one at a time
  std::uint64_t viscous_solves = 0;     ///< cells whose viscosity was solved (viscosity.hpp)
  std::uint64_t viscous_iterations = 0; ///< their conjugate-gradient iterations, summed
  int viscous_max_iterations = 0;       ///< the most of one solve
};

/** The shape tables of one kind of cell (see the file comment). */
struct Topology {
  int n_nodes = 0;
  int origin = 0; ///< cell-local node of the volume's reference point
  // triangles: vertices; their local area (area.hpp); whether each is one of
  // the cell's closed surface (OifGlobalForces, or OifOutDirection without
  // those: area, volume and orientation) and of its normals (OifOutDirection)
  std::vector<int> tri_v0, tri_v1, tri_v2;
  std::vector<LocalAreaParams> local_area;
  std::vector<double> closed_weight, normal_weight;
  // edges: the local bonds (B, A, C, D), edge BC, wings A and D, with their
  // terms' parameters and reference values
  std::vector<int> edge_b, edge_a, edge_c, edge_d;
  std::vector<StretchingParams> stretching;
  std::vector<BendingParams> bending;
  std::vector<ViscosityParams> viscosity;
  std::vector<std::uint8_t> has_normal; ///< per node: in a normals triangle
  // the terms that occur: the pass's instantiation
  bool neo = false, visc = false, bend = false;
  /// the most, over the nodes, of the summed kvisc of a node's edges: the
  /// explicit dashpots' fastest rate is about this / m (viscosity.hpp)
  double kvisc_node_max = 0.0;
  bool edges = false;          ///< an edge term is on (the edge pass runs)
  bool has_local_area = false; ///< local area on some triangle
  bool closed = false;         ///< a closed surface: area, volume, orientation
  bool normals = false;        ///< node normals
  bool separate_sums = false;  ///< closed and normal triangles differ: two node sums
};

/** One cell (see the file comment). */
struct Cell {
  int mol_id = 0;
  int topology = 0;
  int node_begin = 0; ///< its nodes in Model::node_index, topology.n_nodes of them
  GlobalAreaParams<> global_area{0.0, 1.0};
  VolumeParams<> volume{0.0, 1.0};
  int local_bond_id = -1, global_bond_id = -1; ///< for messages
};

/** Cells evaluated together: one (lanes = 1) or up to four of one topology. */
struct Group {
  int lanes = 1;
  std::array<int, lanes_of<Lanes>> cell{}; ///< unused lanes repeat the first cell
  int n_cells = 1;                         ///< lanes that are distinct cells
};

/** A cell whose volume or surface left the tolerance (noted once per cell
 *  and quantity). */
struct DriftNote {
  int mol_id;
  const char* quantity; ///< "volume" or "surface"
  double ratio;         ///< to the relaxed value
  double time;
  long long step;
};

class Model {
public:
  /** Checks of the time step (not of analysis): inverted triangles, volumes
   *  collapsed or exploded (errors), volume and surface drift (notes). */
  bool shape_checks = false;
  double drift_tolerance = 0.05; ///< relative; 0: no notes
  long long step = -1;           ///< the MD step evaluated (for the notes)
  std::vector<DriftNote> drift_notes;
  /** The time step of the membrane viscosity's implicit solve (viscosity.hpp);
   *  0: the explicit force at the current velocities (analysis). */
  double time_step = 0.0;
  /** dt kvisc_node_max / m up to which the viscosity stays explicit
   *  (viscosity.hpp). */
  static constexpr double explicit_viscosity_limit = 1.5;
  /** Where not null, the viscous forces alone are also added here, per
   *  local index (analysis of the viscosity term). */
  Vec3* viscous_force = nullptr;
  /** The time step's mode: evaluate() leaves out the implicit viscosity and
   *  lists its cells; add_deferred_viscosity() adds it once every other
   *  force of the step is in (viscosity.hpp). false: evaluate() solves it
   *  against the membrane's own forces and the external ones (analysis). */
  bool defer_implicit_viscosity = false;
  /** The viscous solves since the counters were last taken. */
  std::uint64_t viscous_solves = 0, viscous_iterations = 0;
  int viscous_max_iterations = 0;

  /** Builds the tables from the membrane bonds of `bonded` chosen by `select`.
   *  Throws SimulationInstability for a bond of a missing particle,
   *  InputError for a cell with two OifGlobalForces interactions. */
  void compile(const std::vector<BondedEntry>& bonded, const Selection& select,
               const ParticleStore& p);
  bool empty() const { return m_cells.empty(); }
  /** (particle id, local index) of all cells' nodes, each once, by id. */
  std::vector<std::pair<int, int>> nodes_by_id(const ParticleStore& p) const;

  /** Forces of all cells added to force[local index] (may be null), node
   *  normals written to normal[local index] (may be null), and with reports
   *  (may be null) one CellReport per cell, in cells() order. */
  void evaluate(const ParticleStore& p, const BoxGeometry& box, double time, Vec3* force,
                Vec3* normal, std::vector<CellReport>* reports, PassCounts& counts);
  /** The implicit viscosity of the cells the last evaluate() deferred,
   *  solved against force[local index] (all the step's forces on their
   *  nodes: membrane, contacts, walls, thermostat, coupling, external) and
   *  added to it. */
  void add_deferred_viscosity(const ParticleStore& p, const BoxGeometry& box, Vec3* force);

private:
  template <class T, bool with_reports>
  void evaluate_group(const Group& group, const ParticleStore& p, const BoxGeometry& box,
                      double time, Vec3* force, Vec3* normal, std::vector<CellReport>* reports);
  /** The nodes of `cell` (positions relative to its first node, and with v
   *  the velocities) into lane j of the node arrays x and v. */
  /** The viscous forces of `cell` (lane j of the gathered x and v) added
   *  to lane j of f. */
  template <class Node>
  void add_viscous_forces(const Cell& cell, int j, const ParticleStore& p, const Node* x,
                          const Node* v, Node* f, bool implicit);
  /** The cell's viscosity needs the implicit solve: time_step > 0 and
   *  dt kvisc_node_max / m (its lightest node) beyond
   *  explicit_viscosity_limit. */
  bool needs_implicit_viscosity(const Cell& cell, const ParticleStore& p) const;
  /** The last viscous solve added to the counters. */
  void count_viscous_solve() {
    ++viscous_solves;
    viscous_iterations += static_cast<std::uint64_t>(m_viscous.last_iterations);
    viscous_max_iterations = std::max(viscous_max_iterations, m_viscous.last_iterations);
  }
  template <class Node>
  void gather(const Cell& cell, int j, const ParticleStore& p, const BoxGeometry& box, Node* x,
              Node* v) const;
  /** Throws the SimulationInstability that names what went wrong in `cell`
   *  (positions as gathered in lane `lane` of the workspace). */
  template <class T>
  [[noreturn]] void report_failure(const Group& group, int lane, const ParticleStore& p,
                                   double time, double volume) const;

  std::vector<Topology> m_topologies;
  std::vector<Cell> m_cells;
  std::vector<Group> m_groups;
  std::vector<int> m_node_index;   ///< cell node -> local particle index
  std::vector<int> m_deferred;     ///< cells whose implicit viscosity waits (m_cells index)
  bool m_shared_nodes = false;     ///< a particle is a node of two cells (normals summed)
  std::vector<int> m_normal_nodes; ///< local indices that get a normal, each once
  /// per mol_id: bit 1 volume, 2 surface noted (kept across compiles)
  std::unordered_map<int, std::uint8_t> m_drift_warned;

  /** Scratch of the pass for one scalar type. */
  template <class T> struct Workspace {
    struct Node {
      T c[3];
    };
    std::vector<Node> x, v, f, nsum, vsum; ///< per node of the largest cell
    std::vector<T> g, coef;                ///< per triangle of the largest cell
  };
  Workspace<double> m_plain;
  Workspace<Lanes> m_lanes;
  ViscousSolver m_viscous;
  struct ViscousScratch {
    std::vector<double> x, v, f, mass, load;
  } m_viscous_scratch;
  template <class T> Workspace<T>& workspace();
};

/** The membranes of a System: the compiled model of all its membrane bonds,
 *  kept until the particles' layout, their mol_ids or the bonds change. */
class Membranes {
public:
  /** Batches of four cells in vector lanes (true) or every cell alone
   *  (false; tests compare the two, bit for bit). */
  bool lanes = true;
  PassCounts counts;
  /** The time step's shape checks (Model::shape_checks; System sets it for
   *  the steps of a run) and the drift tolerance (0: none). */
  bool shape_checks = false;
  double drift_tolerance = 0.05;
  long long step = -1;    ///< the MD step evaluated (for the notes)
  double time_step = 0.0; ///< of the viscous solve (Model::time_step)
  /** Model::defer_implicit_viscosity for the time step (System sets it). */
  bool defer_implicit_viscosity = false;
  /** The drift notes since the last call. */
  std::vector<DriftNote> take_drift_notes() { return std::exchange(m_model.drift_notes, {}); }

  /** The time step's membrane phase: forces of all membrane bonds added to
   *  the particles, node normals written. bonds_version: the System's count
   *  of bond changes. */
  void add_forces(const std::vector<BondedEntry>& bonded, std::uint64_t bonds_version,
                  ParticleStore& p, const BoxGeometry& box, double time,
                  const std::uint8_t* owned = nullptr, std::uint64_t owners_version = 0);
  /** The step's implicit membrane viscosity, after every other force
   *  (Model::add_deferred_viscosity); nothing unless add_forces deferred it. */
  void add_deferred_viscosity(ParticleStore& p, const BoxGeometry& box);
  /** Drops the compiled model (the next call compiles again). */
  void invalidate() { m_key = Key{}; }

private:
  struct Key {
    std::uint64_t layout = 0, mol = 0, bonds = 0, owners = 0;
    bool lanes = true, valid = false;
    bool operator==(const Key& o) const {
      return layout == o.layout && mol == o.mol && bonds == o.bonds && owners == o.owners &&
             lanes == o.lanes && valid == o.valid;
    }
  };
  Key m_key;
  Model m_model;
  /** The model's viscous-solve counters moved into counts. */
  void take_viscous_counts();
};

/** Analysis of the membrane bonds chosen by `select` (one interaction, one
 *  cell, one term), compiled anew and evaluated by the same driver as the
 *  time step: one report per cell; with force (may be null) the selected
 *  forces added to force[local index]; with nodes (may be null) the
 *  selected cells' nodes (Model::nodes_by_id). time_step: the viscosity as
 *  the time step applies it (implicit, viscosity.hpp); 0: explicit. */
std::vector<CellReport> analyse(const std::vector<BondedEntry>& bonded, const Selection& select,
                                const ParticleStore& p, const BoxGeometry& box, double time,
                                Vec3* force, std::vector<std::pair<int, int>>* nodes = nullptr,
                                double time_step = 0.0);

} // namespace pyoif::membrane
