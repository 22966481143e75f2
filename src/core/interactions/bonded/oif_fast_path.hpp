// The time-step path of the OIF membrane bonds: a compiled evaluation of one
// bond group (OifLocalForces, OifGlobalForces or OifOutDirection) that gives
// the same forces and normals as the generic bond loop (bond_loop.hpp) up to
// the order of floating-point operations, at a fraction of its cost.
//
// Derived once per set of bonds and particles (rebuilt when the particle
// store's layout version, the bonds or, for the global forces, a node's mol_id
// change): the local particle index of every node the group touches (compact
// "slots", so a step does no id -> index lookups), grouped in frames (the
// connected sets of bonds: cells), each bond as four slots with its reference
// values as arrays, the unique triangles, and the cells. Per step the nodes
// are gathered once, frame by frame, as unfolded positions relative to the
// frame's first node: separations need no minimum image per bond while every
// frame spans at most half the box (checked per step; else the minimum image
// of the generic loop per block), the volume no unfolding per triangle. Each
// pass works in blocks: gather the separations (indexed loads), all
// arithmetic as loops over plain arrays (vectorised), scatter the forces to
// the slots. Per step:
//  - OifLocalForces: one pass over the edges: stretching (eq. 3), viscosity,
//    bending (eq. 4) -- the deviation from the relaxed angle taken as one
//    angle, its sine from (n1 x n2).e = |e|^2 n1.(d - b), a polynomial
//    arctangent below 14 degrees, std::atan2 above -- and the local area
//    (eq. 5) of each unique triangle once, by an owner bond that owns no
//    other (a matching; leftovers, e.g. on open strips, in a scalar loop),
//    with the mean of its bonds' reference areas (the generic loop applies
//    1/3 in each of its three bonds). No energies (the time-step loop never
//    reads them).
//  - OifGlobalForces, one pass over each cell's triangles: the cell's area
//    and volume (eqs. 6, 7; volume as sum a.N/6, N = (b-a)x(c-a), a the first
//    vertex relative to the cell's reference point, unfolded) and per node
//    the sums its forces are the cell's factors times (sum of g_t (T - p_i)
//    for the area, sum of N_t for the volume); the node normals of an
//    OifOutDirection group over the same triangles (write_normals) are the
//    directions of the latter, so that group needs no pass of its own.
//    Declines (generic loop) when a node is in triangles of two cells.
//  - OifOutDirection otherwise: one pass over the triangles for the normals.
//  - An OifCellType's OifLocalForces and OifGlobalForces groups together
//    (FusedMembranePlan; add_bonded_forces pairs a local group with a global
//    group over the same particles), cell by cell: one gather of the cell's
//    nodes (unfolded, relative to its first node), one pass over its
//    triangles -- N, area and centroid once per triangle for the local area
//    (eq. 5; weight and area0 of the local bonds that have the triangle, as
//    above) and the cell's area and volume (eqs. 6, 7) -- then, with the
//    cell's factors known, the area forces along the shared centroid
//    directions, the volume forces and node normals from the per-node sums
//    of N; the edge pass for stretching, viscosity and bending alone; one
//    commit. Declines (each group's own plan) unless every triangle of a
//    local bond is a global one and each connected set of triangles is one
//    cell (one mol_id, no other set with it), and for a cell wider than half
//    the box. Cells with one copy of the tables (the cells of a type) go
//    four at a time, one per vector lane (evaluate_batch: the same
//    arithmetic, edge_terms<BatchLanes>, with plain vector loads and adds of the
//    nodes' components); the rest of them (n mod 4) and cells of other
//    tables one at a time, vectorised over their triangles and edges.
// Forces are accumulated per slot and added to the particles only when the
// whole group succeeded: on a degenerate or broken bond (or any non-finite
// force) run() returns false without touching the particles, and the caller
// runs the generic loop, which throws the SimulationInstability naming the
// bond. Energies, analysis and multi-rank runs use the generic loop.
// Positions: as the generic loop, separations by the minimum image (edges
// shorter than half the box), the volume from unfolded positions (a cell's
// nodes move continuously, as the integrator moves them).
#pragma once

#include "interactions/bonded/bond_group.hpp"
#include "interactions/bonded/oif_global_forces.hpp"
#include "interactions/bonded/oif_local_forces.hpp"
#include "interactions/bonded/oif_out_direction.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace pyoif::oif {

/** A node's vector (x, y, z, 0) as one 4-lane register (GCC/Clang vector
 *  extension): the fused membrane pass keeps a cell's nodes in this form. */
using Lanes = double __attribute__((vector_size(32)));
/** The fused membrane pass's batches: one cell per lane. Four: eight
 *  (512-bit vectors) made the pass only 2-7 % faster per cell at 8-60 cells,
 *  as its loops are bound by the number of vector operations per lane, and
 *  left 5 of them, the usual remainder, to the one-cell pass. */
using BatchLanes = double __attribute__((vector_size(32)));

template <class IA>
constexpr bool has_fast_path =
    std::is_same_v<IA, OifLocalForces> || std::is_same_v<IA, OifGlobalForces> ||
    std::is_same_v<IA, OifOutDirection>;

/** What a plan was derived from: a group's bond arrays (their addresses and
 *  sizes: adding or removing bonds changes them) and the particle store's
 *  layout version (local indices). */
struct GroupKey {
  std::uint64_t particles_version = 0;
  const void* ids = nullptr;
  const void* per_bond = nullptr;
  std::size_t n_ids = 0, n_per_bond = 0;
  int kind = -1;
  GroupKey() = default;
  GroupKey(const BondGroup& group, const ParticleStore& p, int kind_);
  bool operator==(const GroupKey& o) const {
    return particles_version == o.particles_version && ids == o.ids && per_bond == o.per_bond &&
           n_ids == o.n_ids && n_per_bond == o.n_per_bond && kind == o.kind;
  }
};

/** The outcome of comparing two bond groups, kept until either group's id
 *  array changes (its address or length): the pairings in
 *  System::add_bonded_forces ask every step. */
class CachedGroupComparison {
public:
  template <class Compare> bool get(const BondGroup& a, const BondGroup& b, Compare&& compare) {
    const Key now{a.ids.data(), a.ids.size(), b.ids.data(), b.ids.size()};
    if (!(now == m_key)) {
      m_key = now;
      m_result = compare();
    }
    return m_result;
  }

private:
  struct Key {
    const int* a = nullptr;
    std::size_t n_a = 0;
    const int* b = nullptr;
    std::size_t n_b = 0;
    bool operator==(const Key& o) const {
      return a == o.a && n_a == o.n_a && b == o.b && n_b == o.n_b;
    }
  };
  Key m_key;
  bool m_result = false;
};

class FastBondPlan {
public:
  /** Adds the group's forces (writes the node normals for OifOutDirection).
   *  Returns false, with the particles untouched, when the fast path cannot
   *  evaluate the group (missing particle, bad reference value, degenerate or
   *  broken bond, non-finite force): the caller then runs the generic loop. */
  bool run(const OifLocalForces& ia, const BondGroup& group, ParticleStore& p,
           const BoxGeometry& box);
  bool run(const OifGlobalForces& ia, const BondGroup& group, ParticleStore& p,
           const BoxGeometry& box);
  bool run(const OifOutDirection& ia, const BondGroup& group, ParticleStore& p,
           const BoxGeometry& box);

  /** OifGlobalForces plans: also write the node normals of OifOutDirection
   *  (set when an OifOutDirection group has exactly this group's triangles,
   *  as an OifCellType's have), saving that group its own pass. */
  bool write_normals = false;
  /** Whether the last run() wrote the normals (it succeeded, write_normals). */
  bool normals_written() const { return m_normals_written; }
  /** OifOutDirection plans: whether `source` (an OifGlobalForces group) has
   *  exactly the triangles of `own`; compared once per change of either. */
  bool same_triangles(const BondGroup& own, const BondGroup& source);
  /** OifOutDirection plans: the bonded id of the group whose pass wrote the
   *  normals at the last step, -1 if none (tried first next step). */
  int normals_source = -1;

  /** Number of (re)builds so far (tests: the plan is reused across steps). */
  std::size_t n_builds() const { return m_n_builds; }

private:
  /** One OifLocalForces bond (B, A, C, D) as slots. */
  struct EdgeBond {
    int b = 0, a = 0, c = 0, d = 0;
  };
  /** Per-bond reference values, one array each (vectorised loops): relaxed
   *  length, the relaxed dihedral as psi0 = pi - phi0, and the local area
   *  term of the one triangle the bond evaluates: bcd 0 for ABC, 1 for BCD
   *  (weight 0 where it owns none; see build_local). */
  struct EdgeReferences {
    std::vector<double> r0, inv_r0, cos_psi0, sin_psi0;
    std::vector<double> bcd, weight, area0;
    void resize(std::size_t n) {
      for (auto* v : {&r0, &inv_r0, &cos_psi0, &sin_psi0, &bcd, &weight, &area0})
        v->assign(n, 0.0);
    }
  };
  /** A triangle whose bonds all own another one (rare; none on the meshes
   *  seen): evaluated by its bond in a scalar loop. */
  struct ExtraTriangle {
    std::size_t bond;
    int bcd; ///< 0: ABC, 1: BCD
    double weight, area0;
  };
  /** One triangle of a triangle group (OifGlobalForces, OifOutDirection) as
   *  slots, with its cell. */
  struct Triangle {
    int v0, v1, v2;
    int cell;
  };

  /** Slots of the group's particles; false when a particle is missing. Also
   *  the frames: the connected sets of bonds (cells), their slots contiguous,
   *  the first one the frame's reference node. */
  bool build_slots(const BondGroup& group, const ParticleStore& p, std::vector<int>& bond_slots);
  bool build_local(const BondGroup& group, const ParticleStore& p);
  bool build_triangles(const BondGroup& group, const ParticleStore& p);
  /** gather_relative(), and whether every node still has the mol_id of the
   *  build (the cells of a triangle group are mol_ids). */
  bool gather_relative_same_cells(const ParticleStore& p, const BoxGeometry& box);
  /** m_x = each node's unfolded position relative to its frame's reference
   *  node, (x - x_ref) + (image - image_ref) L: a cell's separations without
   *  a minimum image per bond, its volume without unfolding per triangle. */
  void gather_relative(const ParticleStore& p, const BoxGeometry& box);
  /** m_x = folded positions (OifOutDirection). */
  void gather_positions(const ParticleStore& p);
  /** Adds the slot forces to the particles if all are finite. */
  bool commit_forces(ParticleStore& p) const;

  CachedGroupComparison m_same_triangles;
  bool m_normals_written = false;
  std::vector<Vec3> m_normal; ///< slot -> normal accumulated (write_normals)

  GroupKey m_key;
  bool m_usable = false; ///< false: the group cannot use the fast path (generic loop)
  std::size_t m_n_builds = 0;

  std::vector<int> m_index;       ///< slot -> local particle index
  std::vector<int> m_frame_begin; ///< frame -> its first slot (its reference node)
  std::vector<Vec3> m_x;          ///< slot -> position of this step (see gather_*)
  bool m_within_half = false;     ///< every frame within half the box (gather_relative)
  std::vector<Vec3> m_v;          ///< slot -> velocity (membrane viscosity only)
  std::vector<Vec3> m_f;          ///< slot -> force (or normal) accumulated this step
  std::vector<EdgeBond> m_bonds;
  EdgeReferences m_ref;
  std::vector<ExtraTriangle> m_extra; ///< sorted by bond
  std::vector<Triangle> m_triangles;

  // cells of a triangle group (OifGlobalForces, OifOutDirection)
  std::vector<int> m_cell_mol;       ///< cell -> mol_id
  std::vector<int> m_cell_reference; ///< cell -> slot of its reference node
  std::vector<int> m_slot_mol;       ///< slot -> mol_id at build
  std::vector<int> m_slot_cell;      ///< slot -> its (last) cell
  bool m_nodes_in_one_cell = true;   ///< every node in one cell's triangles only
  std::vector<double> m_cell_area_factor, m_cell_volume_factor, m_cell_sign; ///< this step
  std::vector<std::size_t> m_cell_begin; ///< cell -> first triangle (triangles sorted by cell)
  std::vector<Vec3> m_cell_origin;       ///< unfolded reference point of this step
  static constexpr int kCellArrays = 23; ///< per-triangle arrays of one cell's pass
  std::vector<double> m_scratch;         ///< kCellArrays x (largest cell's triangles)
  std::vector<double> m_outward_sign;    ///< OifOutDirection: +1/-1 per triangle
};

/** An OifCellType's OifLocalForces and OifGlobalForces groups, and the node
 *  normals of its OifOutDirection group, evaluated together cell by cell
 *  (see the file comment). Derived once per set of bonds and particles, when
 *  the two groups pair up: every triangle of a local bond (ABC, BCD) is one of
 *  the global group's, and the cells (mol_ids) of the global group are its
 *  connected sets of triangles. Otherwise it declines and the groups use
 *  their own FastBondPlans. */
class FusedMembranePlan {
public:
  /** Whether `local` and `global` hold the same particles (as an
   *  OifCellType's groups do): the pair to fuse. Compared once per change of
   *  either group's bonds. */
  bool same_particles(const BondGroup& local, const BondGroup& global);
  /** The bonded id of the OifGlobalForces group this OifLocalForces group was
   *  fused with at the last step, -1 if none (tried first next step). */
  int partner = -1;

  /** Adds the forces of both groups; with write_normals also the node normals
   *  of an OifOutDirection group over the global group's triangles. Returns
   *  false, with the particles untouched, when the groups do not pair up or
   *  the fused pass cannot evaluate them (degenerate or broken bond,
   *  non-finite force, a cell wider than half the box): the caller then runs
   *  each group's own plan. */
  bool run(const OifLocalForces& local_ia, const BondGroup& local, const OifGlobalForces& global_ia,
           const BondGroup& global, bool write_normals, ParticleStore& p, const BoxGeometry& box);

  /** Number of (re)builds so far (as FastBondPlan::n_builds). */
  std::size_t n_builds() const { return m_n_builds; }

private:
  bool build(const BondGroup& local, const BondGroup& global, const ParticleStore& p);
  /** Positions (and velocities) of a cell's nodes relative to its reference
   *  node into m_node; false when the cell spans more than half the box on
   *  a periodic axis or a node's mol_id changed (*regroup set). */
  bool gather_cell(std::size_t cell, const ParticleStore& p, const BoxGeometry& box,
                   bool velocities, bool* regroup);
  /** gather_cell's work for one cell: `store(k, x)` and, with velocities,
   *  `store_velocity(k, v)` for its k-th node. */
  template <class Store, class StoreVelocity>
  bool gather_cell_with(std::size_t cell, const ParticleStore& p, const BoxGeometry& box,
                        bool velocities, bool* regroup, Store&& store,
                        StoreVelocity&& store_velocity) const;
  /** Forces of one cell into m_f, its normals (write_normals) into the
   *  particles; false on a degenerate triangle or edge or a non-finite
   *  force. */
  bool evaluate_cell(std::size_t cell, const OifLocalForces& local_ia,
                     const OifGlobalForces& global_ia, bool write_normals, ParticleStore& p);

  /** Four cells with one copy of the tables (see share_cell_tables),
   *  evaluated together, one cell per vector lane: the arithmetic of
   *  evaluate_cell, operation for operation (the same forces bit for bit),
   *  but a node's component of the four cells is one vector, so the
   *  gathers and scatters of the triangle and edge passes are plain vector
   *  loads and stores instead of the transposes and 4-lane node vectors of
   *  the one-cell pass (which vectorises over the edges). */
  static constexpr int kBatchCells = sizeof(BatchLanes) / sizeof(double);
  struct Batch {
    int cell[kBatchCells];
  };
  std::vector<Batch> m_batches;
  std::vector<int> m_single_cells; ///< cells evaluated one at a time
  /** Groups the cells into batches (cells with the same tables, in order)
   *  and singles; called at the end of a build. */
  void form_batches();
  /** A node of a batch: component d of the four cells in c[d]. */
  struct alignas(sizeof(BatchLanes)) NodeLanes {
    BatchLanes c[3];
  };
  std::vector<NodeLanes> m_batch_node; ///< kNodeArrays x (largest cell's nodes)
  std::vector<BatchLanes> m_batch_tri; ///< 2 x (largest cell's triangles): g, coef
  bool gather_batch(const Batch& batch, const ParticleStore& p, const BoxGeometry& box,
                    bool velocities, bool* regroup);
  bool evaluate_batch(const Batch& batch, const OifLocalForces& local_ia,
                      const OifGlobalForces& global_ia, bool write_normals, ParticleStore& p);

  CachedGroupComparison m_same_particles;

  GroupKey m_local_key, m_global_key;
  bool m_usable = false;
  std::size_t m_n_builds = 0;

  /** A cell's nodes (slots), triangles and edges: contiguous ranges. */
  struct CellRange {
    int node_begin, node_end;
    int triangle_begin, triangle_end;
    int edge_begin, edge_end;
    int origin; ///< cell-local index of the volume's reference point
  };
  std::vector<CellRange> m_cells;
  /** Cells with identical triangle and edge tables point to one copy
   *  (their ranges rewritten); called at the end of a build. */
  void share_cell_tables();
  /** f(table, edges) for each table a CellRange indexes: the per-triangle
   *  ones (edges false), then the per-edge ones. */
  template <class F> void for_each_cell_table(F&& f);
  std::vector<int> m_index;    ///< slot -> local particle index
  std::vector<int> m_slot_mol; ///< slot -> mol_id at build
  // triangles (global group order within a cell), vertices as cell-local
  // node indices, with the local area (eq. 5) terms of the local bonds that
  // have them: weight = (bonds) / 3, area0 = sum of their references / 3
  std::vector<int> m_tri_v0, m_tri_v1, m_tri_v2;
  std::vector<double> m_tri_weight, m_tri_area0;
  // edges (local bonds B, A, C, D) as cell-local node indices, references
  std::vector<int> m_edge_b, m_edge_a, m_edge_c, m_edge_d;
  std::vector<double> m_edge_r0, m_edge_inv_r0, m_edge_cos_psi0, m_edge_sin_psi0;

  static constexpr int kNodeArrays = 4;     ///< x, v, f, normal sum
  static constexpr int kTriangleArrays = 5; ///< N (3), g, c: what the force scatter reads
  /** A node as one 4-lane register (Lanes): the scatters add a bond's force
   *  to a node with one load, add and store instead of three (the passes are
   *  bound by stores), the gathers load a node at once. */
  struct alignas(32) Node4 {
    Lanes v;
  };
  std::vector<Node4> m_node; ///< kNodeArrays x (largest cell's nodes)
  /// kTriangleArrays x (largest cell's triangles); the triangle pass's other
  /// per-triangle values (edge vectors, area, volume term) live in its block
  /// only: this scratch leaves L2 at every lattice sweep and is read back
  /// from L3 once per step, so it is kept small
  std::vector<double> m_tri;
  std::vector<Vec3> m_f; ///< slot -> force of this step
};

} // namespace pyoif::oif
