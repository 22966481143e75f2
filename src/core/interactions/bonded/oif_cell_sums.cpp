#include "interactions/bonded/oif_cell_sums.hpp"

#include "interactions/bonded/oif_area.hpp"
#include "interactions/bonded/oif_volume.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <climits>
#include <string>

namespace pyoif::oif {

namespace {

[[noreturn]] void missing_particle(int pid) {
  throw SimulationInstability("OIF triangle bond refers to particle " + std::to_string(pid) +
                              ", which does not exist");
}

int local_index(const ParticleStore& p, int pid) {
  const int i = p.index(pid);
  if (i < 0)
    missing_particle(pid);
  return i;
}

/** The first particle id of the groups' bonds that this rank lacks, -1 if none. */
int first_missing(const std::vector<std::pair<const BondGroup*, CellSums*>>& jobs,
                  const ParticleStore& p) {
  for (const auto& job : jobs)
    for (const int id : job.first->ids)
      if (p.index(id) < 0)
        return id;
  return -1;
}

/** The mol_id range [lo, hi] of a group's local triangles (lo > hi: none). */
std::pair<int, int> local_mol_range(const BondGroup& group, const ParticleStore& p) {
  int lo = INT_MAX, hi = INT_MIN;
  for (std::size_t b = 0; b < group.size(); ++b) {
    const int mol = p.mol_id[local_index(p, group.bond(b)[0])];
    lo = std::min(lo, mol);
    hi = std::max(hi, mol);
  }
  return {lo, hi};
}

} // namespace

void CellSums::accumulate(const BondGroup& group, const ParticleStore& p, const BoxGeometry& box,
                          bool partial, double* sums) {
  const std::size_t n = group.size();
  const long range = m_range_size;
  bond_cell.assign(n, -1);
  std::vector<Vec3> reference(static_cast<std::size_t>(range));
  std::vector<Vec3> normal_sum(partial ? static_cast<std::size_t>(range) : 0, Vec3::Zero());
  std::vector<char> has_reference(static_cast<std::size_t>(range), 0);
  for (std::size_t b = 0; b < n; ++b) {
    const int* ids = group.bond(b);
    const int i0 = local_index(p, ids[0]);
    const long k = static_cast<long>(p.mol_id[i0]) - m_range_lo;
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
    if (partial)
      normal_sum[k] += (bb - a).cross(c - a);
  }
  // Part of a cell's triangles (the rest are on other ranks): the tetrahedra
  // above point at this rank's reference r, the other ranks' at theirs. With
  // S = sum (b - a) x (c - a) of these triangles, the same tetrahedra
  // pointing at the origin sum to V_r + r . S / 6, which adds up over ranks
  // (for the whole closed mesh S = 0 and any r gives the same volume). Its
  // round-off is eps |r| |S|, against eps |r|^3 per triangle if every
  // tetrahedron pointed at the origin.
  if (partial)
    for (long k = 0; k < range; ++k)
      if (has_reference[k])
        sums[range + k] += reference[k].dot(normal_sum[k]) / 6.0;
}

void CellSums::finish(const double* sums) {
  const long range = m_range_size;
  // compact slots: only cells that have triangles (on some rank)
  m_min_mol = m_range_lo;
  m_slot_of_mol.assign(static_cast<std::size_t>(range), -1);
  mol_ids.clear();
  area.clear();
  volume.clear();
  n_triangles.clear();
  for (long k = 0; k < range; ++k) {
    if (sums[2 * range + k] == 0.0)
      continue;
    m_slot_of_mol[k] = static_cast<int>(mol_ids.size());
    mol_ids.push_back(static_cast<int>(m_range_lo + k));
    area.push_back(sums[k]);
    volume.push_back(sums[range + k]);
    n_triangles.push_back(sums[2 * range + k]);
  }
  for (auto& s : bond_cell)
    s = m_slot_of_mol[s];
}

void CellSums::compute(const BondGroup& group, const ParticleStore& p, const BoxGeometry& box,
                       const Communicator& comm) {
  compute_all({{&group, this}}, p, box, comm);
}

void CellSums::compute_all(const std::vector<std::pair<const BondGroup*, CellSums*>>& jobs,
                           const ParticleStore& p, const BoxGeometry& box,
                           const Communicator& comm) {
  const std::size_t n_jobs = jobs.size();
  const bool parallel = comm.size() > 1;
  // A missing particle is found on one rank; the others must not wait in a
  // reduction for it: its count travels in the reduction, and every rank throws.
  const int missing = parallel ? first_missing(jobs, p) : -1;
  std::vector<std::pair<int, int>> local(n_jobs, {INT_MAX, INT_MIN});
  if (missing < 0)
    for (std::size_t j = 0; j < n_jobs; ++j)
      local[j] = local_mol_range(*jobs[j].first, p);
  if (!parallel) {
    // one rank: the range of this call's own triangles, no agreement needed
    for (std::size_t j = 0; j < n_jobs; ++j) {
      const auto [lo, hi] = local[j];
      CellSums& s = *jobs[j].second;
      const std::size_t n = jobs[j].first->size();
      s.m_range_lo = hi >= lo ? lo : 0;
      s.m_range_size = hi >= lo ? static_cast<long>(hi) - lo + 1 : 0;
      if (s.m_range_size > 16 * static_cast<long>(n) + 4096)
        throw InputError("OIF cells: mol_id values span " + std::to_string(s.m_range_size) +
                         " numbers for " + std::to_string(n) +
                         " triangles; number the cells (mol_id) compactly");
    }
  }
  // Every rank lays out all groups' sums, [area | volume | triangles] per
  // mol_id of the group's agreed range, in one array, plus a count of the
  // groups with a mol_id outside those ranges and one of missing particles;
  // reduced in ONE call.
  // The ranges are agreed by all ranks and kept from call to call, so the
  // steady state is one reduction per step for all cells together; only
  // when a rank finds a mol_id outside them (cells added) is a second
  // reduction needed, to agree on new ranges, and the sums are redone.
  auto offsets = [&] {
    std::vector<std::size_t> off(n_jobs + 1, 0);
    for (std::size_t j = 0; j < n_jobs; ++j)
      off[j + 1] = off[j] + 3 * static_cast<std::size_t>(jobs[j].second->m_range_size);
    return off;
  };
  auto fits = [&](std::size_t j) {
    const CellSums& s = *jobs[j].second;
    const auto [lo, hi] = local[j];
    return hi < lo || (lo >= s.m_range_lo && static_cast<long>(hi) - s.m_range_lo < s.m_range_size);
  };
  std::vector<double> sums;
  auto sum_all = [&] {
    const auto off = offsets();
    const std::size_t outside = off[n_jobs], lacking = off[n_jobs] + 1;
    sums.assign(off[n_jobs] + 2, 0.0);
    for (std::size_t j = 0; j < n_jobs; ++j) {
      if (missing >= 0)
        continue;
      if (fits(j))
        jobs[j].second->accumulate(*jobs[j].first, p, box, parallel, sums.data() + off[j]);
      else
        sums[outside] += 1.0;
    }
    if (missing >= 0)
      sums[lacking] = 1.0;
    comm.allreduce_sum(sums);
    // the same verdicts on every rank
    if (sums[lacking] > 0.0) {
      if (missing >= 0)
        missing_particle(missing);
      throw SimulationInstability("OIF triangle bond refers to a particle that does not exist "
                                  "(found on another rank)");
    }
    return sums[outside] == 0.0;
  };
  if (!sum_all()) {
    std::vector<double> bounds(2 * n_jobs); // (-lo, hi) per group, maximised over ranks
    for (std::size_t j = 0; j < n_jobs; ++j) {
      const auto [lo, hi] = local[j];
      bounds[2 * j] = hi >= lo ? -static_cast<double>(lo) : -1e18;
      bounds[2 * j + 1] = hi >= lo ? static_cast<double>(hi) : -1e18;
    }
    comm.allreduce_max(bounds);
    for (std::size_t j = 0; j < n_jobs; ++j) {
      const double lo = -bounds[2 * j], hi = bounds[2 * j + 1];
      CellSums& s = *jobs[j].second;
      s.m_range_lo = hi >= lo ? static_cast<int>(lo) : 0;
      s.m_range_size = hi >= lo ? static_cast<long>(hi - lo) + 1 : 0;
    }
    sum_all(); // every mol_id fits now
  }
  const auto off = offsets();
  for (std::size_t j = 0; j < n_jobs; ++j)
    jobs[j].second->finish(sums.data() + off[j]);
}

} // namespace pyoif::oif
