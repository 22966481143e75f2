// Per-cell surface and volume of closed triangle meshes, summed over the
// triangle bonds of one bond group in one O(triangles) pass for all cells
// together, followed by ONE reduction over ranks (upstream PyOIF looped over
// all particles once per cell). A cell is the mol_id of a triangle's first
// particle. Used by OifGlobalForces (eqs. 6, 7) and OifOutDirection.
#pragma once

#include "communication/communicator.hpp"
#include "interactions/bonded/bond_group.hpp"
#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

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
  /** Slot of a mol_id, -1 if the group has no triangle of that cell. */
  int slot_of(int mol_id) const {
    const long k = static_cast<long>(mol_id) - m_min_mol;
    return (k >= 0 && k < static_cast<long>(m_slot_of_mol.size())) ? m_slot_of_mol[k] : -1;
  }

private:
  int m_min_mol = 0;
  std::vector<int> m_slot_of_mol; ///< mol_id - m_min_mol -> slot
};

} // namespace pyoif::oif
