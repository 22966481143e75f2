#include "interactions/bonded/oif_cell_sums.hpp"

#include "interactions/bonded/oif_area.hpp"
#include "interactions/bonded/oif_volume.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <climits>
#include <string>

namespace pyoif::oif {

namespace {
int local_index(const ParticleStore& p, int pid) {
  const int i = p.index(pid);
  if (i < 0)
    throw SimulationInstability("OIF triangle bond refers to particle " + std::to_string(pid) +
                                ", which does not exist");
  return i;
}
} // namespace

void CellSums::compute(const BondGroup& group, const ParticleStore& p, const BoxGeometry& box,
                       const Communicator& comm) {
  const std::size_t n = group.size();
  // The cells' mol_id range, agreed by all ranks so every rank uses the same
  // dense slot table for the reduction.
  int lo = INT_MAX, hi = INT_MIN;
  for (std::size_t b = 0; b < n; ++b) {
    const int mol = p.mol_id[local_index(p, group.bond(b)[0])];
    lo = std::min(lo, mol);
    hi = std::max(hi, mol);
  }
  if (comm.size() > 1) {
    const double glo = -comm.allreduce_max(n ? -static_cast<double>(lo) : -1e18);
    const double ghi = comm.allreduce_max(n ? static_cast<double>(hi) : -1e18);
    if (ghi < glo) { // no triangles on any rank
      lo = 0;
      hi = -1;
    } else {
      lo = static_cast<int>(glo);
      hi = static_cast<int>(ghi);
    }
  }
  mol_ids.clear();
  bond_cell.assign(n, -1);
  m_min_mol = lo;
  const long range = (hi >= lo) ? static_cast<long>(hi) - lo + 1 : 0;
  if (range > 16 * static_cast<long>(n) + 4096 && comm.size() == 1)
    throw InputError("OIF cells: mol_id values span " + std::to_string(range) + " numbers for " +
                     std::to_string(n) + " triangles; number the cells (mol_id) compactly");
  // dense per-mol arrays: [area | volume | triangles], reduced in ONE call
  std::vector<double> sums(3 * static_cast<std::size_t>(range), 0.0);
  std::vector<Vec3> reference(static_cast<std::size_t>(range));
  std::vector<char> has_reference(static_cast<std::size_t>(range), 0);
  for (std::size_t b = 0; b < n; ++b) {
    const int* ids = group.bond(b);
    const int i0 = local_index(p, ids[0]);
    const long k = static_cast<long>(p.mol_id[i0]) - lo;
    bond_cell[b] = static_cast<int>(k);
    // unfolded coordinates (position + image count): continuous along the
    // trajectory, so exact for a cell of any size, and no minimum-image
    // rounding in this per-step pass
    const Vec3 x0 = box.unfolded(p.pos[i0], p.image[i0]);
    if (!has_reference[k]) {
      reference[k] = x0;
      has_reference[k] = 1;
    }
    const int i1 = local_index(p, ids[1]), i2 = local_index(p, ids[2]);
    const Vec3 a = x0 - reference[k];
    const Vec3 bb = box.unfolded(p.pos[i1], p.image[i1]) - reference[k];
    const Vec3 c = box.unfolded(p.pos[i2], p.image[i2]) - reference[k];
    sums[k] += triangle_area(a, bb, c);
    sums[range + k] += tetra_volume(a, bb, c);
    sums[2 * range + k] += 1.0;
  }
  comm.allreduce_sum(sums);
  // compact slots: only cells that have triangles
  m_slot_of_mol.assign(static_cast<std::size_t>(range), -1);
  area.clear();
  volume.clear();
  n_triangles.clear();
  for (long k = 0; k < range; ++k) {
    if (sums[2 * range + k] == 0.0)
      continue;
    m_slot_of_mol[k] = static_cast<int>(mol_ids.size());
    mol_ids.push_back(static_cast<int>(lo + k));
    area.push_back(sums[k]);
    volume.push_back(sums[range + k]);
    n_triangles.push_back(sums[2 * range + k]);
  }
  for (auto& s : bond_cell)
    s = m_slot_of_mol[s];
}

} // namespace pyoif::oif
