#include "interactions/bonded/oif_out_direction.hpp"

#include <Eigen/Geometry>

#include <cmath>

namespace pyoif {

void OifOutDirection::prepare(const BondGroup& group, ParticleStore& p, const BoxGeometry& box,
                              const Communicator& comm) {
  // oriented volume per cell: its sign says which way the triangles point
  sums.compute(group, p, box, comm);
  const std::size_t n = group.size();
  for (std::size_t b = 0; b < n; ++b)
    for (int k = 0; k < 3; ++k)
      p.normal[p.index(group.bond(b)[k])].setZero();
  for (std::size_t b = 0; b < n; ++b) {
    const int* ids = group.bond(b);
    const int i0 = p.index(ids[0]), i1 = p.index(ids[1]), i2 = p.index(ids[2]);
    // unfolded coordinates, as in the cell sums (no minimum-image rounding)
    const Vec3 x0 = box.unfolded(p.pos[i0], p.image[i0]);
    const Vec3 e1 = box.unfolded(p.pos[i1], p.image[i1]) - x0;
    const Vec3 e2 = box.unfolded(p.pos[i2], p.image[i2]) - x0;
    const double s = sums.volume[sums.bond_cell[b]] < 0.0 ? -1.0 : 1.0;
    const Vec3 n2 = s * e1.cross(e2); // twice the area times the outward unit normal
    p.normal[i0] += n2;
    p.normal[i1] += n2;
    p.normal[i2] += n2;
  }
  for (std::size_t b = 0; b < n; ++b)
    for (int k = 0; k < 3; ++k) {
      Vec3& nrm = p.normal[p.index(group.bond(b)[k])];
      const double len = nrm.norm(); // a node of several bonds: idempotent
      if (len > 0.0)
        nrm /= len;
    }
}

} // namespace pyoif
