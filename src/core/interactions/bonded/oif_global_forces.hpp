// OifGlobalForces: global area (model eq. 6) and volume (eq. 7) of every cell,
// a 3-particle bond per triangle (a, b, c). prepare() sums each cell's surface
// and volume in one O(triangles) pass for all cells together and one
// reduction (oif_cell_sums.hpp); forces() then distributes eqs. 6 and 7 on the
// triangle. One interaction serves all cells of a type: a cell is the mol_id of
// the triangle's first particle, and A0_g, V0 are those of the type.
//
// Orientation: the volume is computed oriented and its absolute value used, with
// the force sign following the orientation, so both outward and inward
// (PyOIF's file convention) triangle orders work.
#pragma once

#include "interactions/bonded/bond_loop.hpp"
#include "interactions/bonded/oif_area.hpp"
#include "interactions/bonded/oif_cell_sums.hpp"
#include "interactions/bonded/oif_volume.hpp"

#include <array>
#include <string>
#include <vector>

namespace pyoif {

struct OifGlobalForces {
  static constexpr const char* name = "OifGlobalForces";
  static constexpr int n_particles = 3;
  static constexpr int per_bond_stride = 0;
  double A0_g = 0.0, ka_g = 0.0, V0 = 0.0, kv = 0.0;

  oif::CellSums sums; ///< per-cell sums of the current step, filled by prepare()

  static std::vector<std::string> terms() { return {"global_area", "volume"}; }
  static std::vector<std::string> energy_terms() { return terms(); }
  OifGlobalForces only(const std::string& term) const {
    OifGlobalForces o = *this;
    if (term == "global_area")
      o.kv = 0.0;
    else if (term == "volume")
      o.ka_g = 0.0;
    else
      throw InputError("term: OifGlobalForces has the terms 'global_area' and 'volume', got '" +
                       term + "'");
    return o;
  }

  void prepare(const BondGroup& group, ParticleStore& p, const BoxGeometry& box,
               const Communicator& comm, bool sums_ready) {
    if (!sums_ready)
      sums.compute(group, p, box, comm);
  }

  bool forces(const BondInput<3>& in, std::array<Vec3, 3>& f, double& energy) const {
    const Vec3 &a = in.x[0], &b = in.x[1], &c = in.x[2];
    for (auto& fk : f)
      fk.setZero();
    energy = 0.0;
    const int slot = in.bond_index < sums.bond_cell.size() ? sums.bond_cell[in.bond_index] : -1;
    if (slot < 0)
      throw SimulationInstability("OifGlobalForces: cell sums are stale (bonds changed after "
                                  "prepare()); this is a bug");
    const double area = oif::triangle_area(a, b, c);
    const double cell_area = sums.area[slot], cell_volume = sums.volume[slot];
    if (!(area > 0.0) || !(cell_area > 0.0))
      return false;
    // each triangle carries its area's share of the cell energies
    const double share = area / cell_area;
    if (ka_g != 0.0) {
      oif::add_centroid_allocated(
          a, b, c, oif::global_area_coefficient(area, cell_area, A0_g, ka_g), f[0], f[1], f[2]);
      energy += share * oif::global_area_energy(cell_area, A0_g, ka_g);
    }
    if (kv != 0.0) {
      const Vec3 fv = oif::volume_force(a, b, c, cell_volume, V0, kv);
      for (auto& fk : f)
        fk += fv;
      energy += share * oif::volume_energy(cell_volume, V0, kv);
    }
    return true;
  }
};

} // namespace pyoif
