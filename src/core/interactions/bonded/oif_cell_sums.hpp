// Per-cell surface and volume of closed triangle meshes, summed over the
// triangle bonds of one bond group in one O(triangles) pass for all cells
// together, followed by ONE reduction over ranks, also for several groups
// (cell types) at once: compute_all (upstream PyOIF looped over all particles
// once per cell). A cell is the mol_id of a triangle's first
// particle. Used by OifGlobalForces (eqs. 6, 7) and OifOutDirection.
#pragma once

#include "communication/communicator.hpp"
#include "interactions/bonded/bond_group.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <utility>
#include <vector>

namespace pyoif::oif {

struct CellSums {
  std::vector<int> mol_ids;        ///< slot -> mol_id (slots of cells with triangles)
  std::vector<int> bond_cell;      ///< bond -> slot
  std::vector<double> area;        ///< per slot
  std::vector<double> volume;      ///< per slot, oriented: > 0 for outward triangles
  std::vector<double> n_triangles; ///< per slot

  /** Recompute from the current positions. Volumes are exact for a closed mesh
   *  in a periodic box, also for cells crossing the boundary and cells larger
   *  than half the box: vertices are taken in unfolded coordinates (position +
   *  image count, continuous along the trajectory) relative to the cell's
   *  reference point (the first node of its first triangle). (A minimum-image
   *  chain would need the cell to span less than half the box, and costs a
   *  rounding per coordinate.) Requirement: a cell's nodes have continuous
   *  unfolded positions, as they do when created and moved by the integrator.
   *  Throws SimulationInstability if a bond refers to a missing particle. */
  void compute(const BondGroup& group, const ParticleStore& p, const BoxGeometry& box,
               const Communicator& comm);
  /** compute() for several groups (e.g. every cell type's) with one reduction
   *  over ranks for all of them: each rank sums its own triangles, then one
   *  allreduce of all groups' partial sums. The mol_id range of each group,
   *  which fixes the layout of the reduced array, is agreed by all ranks and
   *  kept from call to call; a call that finds a mol_id outside it (cells
   *  added) agrees on new ranges (a second reduction) and sums again. */
  static void compute_all(const std::vector<std::pair<const BondGroup*, CellSums*>>& jobs,
                          const ParticleStore& p, const BoxGeometry& box, const Communicator& comm);
  /** Slot of a mol_id, -1 if the group has no triangle of that cell. */
  int slot_of(int mol_id) const {
    const long k = static_cast<long>(mol_id) - m_min_mol;
    return (k >= 0 && k < static_cast<long>(m_slot_of_mol.size())) ? m_slot_of_mol[k] : -1;
  }

private:
  /** Adds the local triangles' area, volume and count into sums (layout
   *  [area | volume | triangles] over the agreed range) and sets bond_cell;
   *  partial: other ranks hold the cells' other triangles, so the volumes
   *  are made to add up across ranks (see the .cpp). */
  void accumulate(const BondGroup& group, const ParticleStore& p, const BoxGeometry& box,
                  bool partial, double* sums);
  /** The per-cell values and slots from the reduced sums. */
  void finish(const double* sums);

  int m_min_mol = 0;
  std::vector<int> m_slot_of_mol; ///< mol_id - m_min_mol -> slot
  int m_range_lo = 0;             ///< the agreed mol_id range of the reduction layout
  long m_range_size = 0;
};

} // namespace pyoif::oif
