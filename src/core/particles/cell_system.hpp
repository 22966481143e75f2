// Linked cells + Verlet list with skin. At every re-sort the local particles are
// folded into the box, ghost copies are made of those within the interaction
// range of a periodic face (periodic images are ghosts, as neighbouring
// subdomains will be with MPI), particles and ghosts are binned into cells of
// at least the range, and the pair list is built from each cell's half shell.
// Between re-sorts only the ghost positions are refreshed.
#pragma once

#include "particles/particle_store.hpp"
#include "system/box_geometry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pyoif {

class CellSystem {
public:
  double skin = 0.4;

  /** Pairs of combined indices (local, or ghost as n_local + g), each physical
   *  pair-and-image exactly once, within cutoff + skin at the last re-sort. */
  const std::vector<std::array<int, 2>>& pairs() const { return m_pairs; }

  /** Fold, make ghosts, bin, build the pair list for interaction range max_cut.
   *  With owned (per local index; particles spread over MPI ranks) only the
   *  pairs with a particle this rank owns, in the order of the full list;
   *  with current, only the particles marked there (whose positions this
   *  rank holds up to date) are binned and imaged. */
  void rebuild(ParticleStore& p, const BoxGeometry& box, double max_cut,
               const std::uint8_t* owned = nullptr, const std::uint8_t* current = nullptr);
  /** True when some particle moved more than skin/2 since the last re-sort or
   *  the structure was invalidated. Throws SimulationInstability on a
   *  non-finite position. */
  bool needs_rebuild(const ParticleStore& p, double time) const;
  /** The test of needs_rebuild for a loop that has the new positions at hand
   *  (the integrator's drift), so the positions are not read twice: the
   *  positions at the last re-sort, null when a re-sort is due anyway (the
   *  structure is invalid or the particles changed). */
  const Vec3* displacement_reference(std::size_t n_local) const {
    if (!m_valid || m_pos_at_rebuild.size() != n_local)
      return nullptr;
    // no particles is a reference too (nothing can have moved): an empty
    // list's data() may be null, which read "re-sort" at every step (under
    // MPI a collective re-sort per step of a fluid without particles)
    static const Vec3 no_particles = Vec3::Zero();
    return n_local == 0 ? &no_particles : m_pos_at_rebuild.data();
  }
  /** Squared displacement since the last re-sort beyond which one is due. */
  double displacement_limit2() const { return 0.25 * skin * skin; }
  /** Whether position x is non-finite or runaway (needs_rebuild throws on it). */
  bool runaway(const Vec3& x) const {
    // beyond BoxGeometry::image_range() a particle has certainly blown up
    // (and folding would overflow the image counter)
    return !std::isfinite(x[0] + x[1] + x[2]) ||
           (x.cwiseAbs().array() > m_blowup_distance.array()).any();
  }
  void invalidate() { m_valid = false; }
  /** The cell grid of the next rebuild as if made from all particles and
   *  their images (bounding box lo..hi, n_all of them): a rank that bins
   *  only some of them (particles spread over ranks) gets the grid, and so
   *  the pair orientations, of the full list. Used once. */
  struct GridHint {
    Vec3 lo, hi;
    std::size_t n_all = 0;
  };
  void set_grid_hint(const GridHint& hint) {
    m_hint = hint;
    m_has_hint = true;
  }
  /** Refresh ghost positions from their origins (MPI: ghost exchange). */
  void update_ghosts(ParticleStore& p, const BoxGeometry& box) const;
  /** Add the forces accumulated on ghosts to their owners (MPI: reverse exchange). */
  void collect_ghost_forces(ParticleStore& p) const;

  /** Pairs of particle ids that must not interact (e.g. mesh neighbours). */
  void add_exclusion(int id1, int id2) {
    m_exclusions.push_back(key(id1, id2)); // sorted (duplicates dropped) when next read
    m_exclusions_sorted = false;
    m_exclusion_lists_valid = false;
    invalidate();
  }
  void remove_exclusion(int id1, int id2) {
    sort_exclusions();
    const auto it = std::lower_bound(m_exclusions.begin(), m_exclusions.end(), key(id1, id2));
    if (it != m_exclusions.end() && *it == key(id1, id2))
      m_exclusions.erase(it);
    m_exclusion_lists_valid = false;
    invalidate();
  }
  bool excluded(int id1, int id2) const {
    if (m_exclusions.empty())
      return false;
    if (!m_exclusion_lists_valid) {
      sort_exclusions();
      return std::binary_search(m_exclusions.begin(), m_exclusions.end(), key(id1, id2));
    }
    // the pair-list build asks this for every close pair: a scan of id1's
    // short sorted list (mesh neighbours) instead of a hash probe
    if (id1 < 0 || static_cast<std::size_t>(id1) + 1 >= m_exclusion_start.size())
      return false;
    const int* it = m_exclusion_partners.data() + m_exclusion_start[id1];
    const int* end = m_exclusion_partners.data() + m_exclusion_start[id1 + 1];
    for (; it != end && *it < id2; ++it) {
    }
    return it != end && *it == id2;
  }
  void remove_exclusions_of(int pid) {
    m_exclusions.erase(std::remove_if(m_exclusions.begin(), m_exclusions.end(),
                                      [pid](std::uint64_t k) {
                                        return static_cast<int>(k >> 32) == pid ||
                                               static_cast<int>(k & 0xffffffffu) == pid;
                                      }),
                       m_exclusions.end()); // (the order stays: sorted stays sorted)
    m_exclusion_lists_valid = false;
    invalidate();
  }
  void clear_exclusions() {
    m_exclusions.clear();
    m_exclusions_sorted = true;
    m_exclusion_lists_valid = false;
    invalidate();
  }
  std::size_t n_rebuilds() const { return m_n_rebuilds; }
  /** The folded positions of the last re-sort, empty when a re-sort is due
   *  anyway: a checkpoint keeps them, so that a restart re-sorts at them and
   *  has the pair list, in its order, of the run it continues. */
  std::vector<Vec3> rebuild_reference() const {
    return m_valid ? m_pos_at_rebuild : std::vector<Vec3>{};
  }
  /** Every excluded pair (id1 < id2), sorted. */
  std::vector<std::array<int, 2>> exclusion_pairs() const {
    sort_exclusions(); // key order is (id1, id2) order
    std::vector<std::array<int, 2>> out;
    out.reserve(m_exclusions.size());
    for (const std::uint64_t k : m_exclusions)
      out.push_back({static_cast<int>(k >> 32), static_cast<int>(k & 0xffffffffu)});
    return out;
  }
  double range() const { return m_range; }

private:
  static std::uint64_t key(int a, int b) {
    if (a > b)
      std::swap(a, b);
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) |
           static_cast<std::uint32_t>(b);
  }
  void make_ghosts(ParticleStore& p, const BoxGeometry& box, double range,
                   const std::uint8_t* current) const;
  void build_pairs(const ParticleStore& p, double range, const std::uint8_t* owned,
                   const std::uint8_t* current);
  /** The exclusions as sorted partner lists per id (both directions). */
  void build_exclusion_lists();

  bool m_valid = false;
  GridHint m_hint;
  bool m_has_hint = false;
  double m_range = 0.0;
  Vec3 m_blowup_distance = Vec3::Constant(1e300); ///< per axis (BoxGeometry::image_range)
  std::size_t m_n_rebuilds = 0;
  std::vector<Vec3> m_pos_at_rebuild;
  std::vector<std::array<int, 2>> m_pairs;
  /// The excluded pairs as keys (smaller id << 32 | larger id): a sorted
  /// vector without duplicates once sort_exclusions() ran, 8 bytes a pair.
  /// (A hash set took about 40 bytes a pair: with two mesh rings excluded,
  /// some 9 pairs per membrane node, 270 MB of 2000 RBCs' 1 GB.) Additions
  /// are appended and sorted when next read; mutable: a read sorts them.
  mutable std::vector<std::uint64_t> m_exclusions;
  mutable bool m_exclusions_sorted = true;
  void sort_exclusions() const {
    if (m_exclusions_sorted)
      return;
    std::sort(m_exclusions.begin(), m_exclusions.end());
    m_exclusions.erase(std::unique(m_exclusions.begin(), m_exclusions.end()), m_exclusions.end());
    m_exclusions_sorted = true;
  }
  bool m_exclusion_lists_valid = false;
  std::vector<std::size_t> m_exclusion_start; ///< by id, size max id + 2
  std::vector<int> m_exclusion_partners;
  // cell binning scratch
  std::vector<int> m_cell_start, m_cell_particles;
};

} // namespace pyoif
