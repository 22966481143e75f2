// OifOutDirection: the outward unit normal of every membrane node, for the
// membrane-collision contacts (model eq. 9). A 3-particle bond per triangle;
// its prepare() -- run before any pair force of the step -- writes
// ParticleStore::normal of its nodes: the area-weighted mean of the normals of
// the node's triangles (sum of (b - a) x (c - a)), normalised, and pointing out
// of the cell whatever the triangles' orientation (the sign of the cell's
// oriented volume decides). Upstream PyOIF computed the normal from three
// neighbours in a bond that could run after the pair forces, so the contacts
// used last step's normals; here they are always current. forces() gives nothing.
#pragma once

#include "interactions/bonded/bond_loop.hpp"
#include "interactions/bonded/oif_cell_sums.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace pyoif {

struct OifOutDirection {
  static constexpr const char* name = "OifOutDirection";
  static constexpr int n_particles = 3;
  static constexpr int per_bond_stride = 0;

  oif::CellSums sums; ///< per-cell sums of the last orientation check

  /** The orientation of a cell's triangles is fixed by its mesh, so it is
   *  determined once per set of bonds (keyed by a checksum of the bond ids)
   *  rather than from a full area/volume pass every step; outside the fast
   *  path the force loop sums them each step anyway, with the other cells'
   *  sums in the one reduction (sums_ready), and prepare() then takes the
   *  orientation from them instead of a reduction of its own, which a rank
   *  would make alone when only its own bonds changed. */
  std::uint64_t m_bonds_key = 0;
  std::vector<double> m_sign; ///< +1/-1 per bond: flips the normal outward
  std::vector<int> m_nodes;   ///< ids of the nodes that get a normal, each once

  void prepare(const BondGroup& group, ParticleStore& p, const BoxGeometry& box,
               const Communicator& comm, bool sums_ready);

  bool forces(const BondInput<3>&, std::array<Vec3, 3>& f, double& energy) const {
    for (auto& fk : f)
      fk.setZero();
    energy = 0.0;
    return true;
  }
};

} // namespace pyoif
