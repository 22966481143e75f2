#include "interactions/bonded/oif_out_direction.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace pyoif {

void OifOutDirection::prepare(const BondGroup& group, ParticleStore& p, const BoxGeometry& box,
                              const Communicator& comm, bool sums_ready) {
  const std::size_t n = group.size();
  std::uint64_t key = 1469598103934665603ULL ^ group.ids.size();
  for (const int id : group.ids)
    key = (key ^ static_cast<std::uint64_t>(id)) * 1099511628211ULL; // FNV-1a
  if (sums_ready || key != m_bonds_key || m_sign.size() != n) {
    // oriented volume per cell: its sign says which way the triangles point
    if (!sums_ready)
      sums.compute(group, p, box, comm);
    m_sign.resize(n);
    for (std::size_t b = 0; b < n; ++b)
      m_sign[b] = sums.volume[sums.bond_cell[b]] < 0.0 ? -1.0 : 1.0;
    m_nodes.assign(group.ids.begin(), group.ids.end());
    std::sort(m_nodes.begin(), m_nodes.end());
    m_nodes.erase(std::unique(m_nodes.begin(), m_nodes.end()), m_nodes.end());
    m_bonds_key = key;
  }
  for (const int id : m_nodes)
    p.normal[p.index(id)].setZero();
  for (std::size_t b = 0; b < n; ++b) {
    const int* ids = group.bond(b);
    const int i0 = p.index(ids[0]), i1 = p.index(ids[1]), i2 = p.index(ids[2]);
    // unfolded coordinates, as in the cell sums (no minimum-image rounding)
    const Vec3 x0 = box.unfolded(p.pos[i0], p.image[i0]);
    const Vec3 e1 = box.unfolded(p.pos[i1], p.image[i1]) - x0;
    const Vec3 e2 = box.unfolded(p.pos[i2], p.image[i2]) - x0;
    const Vec3 n2 = m_sign[b] * e1.cross(e2); // twice the area times the outward unit normal
    p.normal[i0] += n2;
    p.normal[i1] += n2;
    p.normal[i2] += n2;
  }
  for (const int id : m_nodes) {
    Vec3& nrm = p.normal[p.index(id)];
    const double len = nrm.norm();
    if (len > 0.0)
      nrm /= len;
  }
}

} // namespace pyoif
