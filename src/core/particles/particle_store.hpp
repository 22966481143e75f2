// Particle storage: structure of arrays for the particles this rank owns
// ("local"), followed by ghost copies (periodic images now, particles of
// neighbouring subdomains with MPI). Ghosts carry the index of their origin and
// their image shift so forces on them are collected back onto the owner.
#pragma once

#include "utils/vector.hpp"

#include <atomic>
#include <cstdint>
#include <vector>

namespace pyoif {

struct ParticleStore {
  // --- local particles, index 0 .. n_local()-1 ---------------------------
  std::vector<int> id;
  std::vector<Vec3> pos;    ///< folded into the box at the last re-sort
  std::vector<Vec3i> image; ///< periodic images crossed: unfolded = pos + image * L
  std::vector<Vec3> vel, force, ext_force;
  std::vector<Vec3> normal; ///< outward membrane normal (filled by the normals pass)
  std::vector<double> mass;
  std::vector<int> type, mol_id;
  std::vector<std::uint8_t> fixed; ///< bit d set: coordinate d is fixed

  // --- ghosts ---------------------------------------------------------------
  std::vector<Vec3> ghost_pos, ghost_force;
  std::vector<int> ghost_origin;  ///< local index of the particle imaged
  std::vector<Vec3i> ghost_shift; ///< image shift in box lengths

  // --- id -> local index (-1 where none) ------------------------------------
  std::vector<int> index_of_id;

  /** Changes whenever local indices may change (insertion, removal, clear),
   *  unique over all stores of the process: caches of local indices (the OIF
   *  fast path) compare it instead of re-looking-up ids every step. */
  std::uint64_t layout_version = next_layout_version();
  static std::uint64_t next_layout_version() {
    static std::atomic<std::uint64_t> counter{0};
    return ++counter;
  }

  /** Changes whenever a mol_id may have changed (writers of mol_id bump it):
   *  the compiled membranes group their cells by mol_id. */
  std::uint64_t mol_version = 0;

  std::size_t n_local() const { return id.size(); }
  std::size_t n_ghost() const { return ghost_pos.size(); }

  int index(int pid) const {
    return (pid >= 0 && static_cast<std::size_t>(pid) < index_of_id.size()) ? index_of_id[pid] : -1;
  }
  int max_id() const { return static_cast<int>(index_of_id.size()) - 1; }

  /** Append a particle; returns its local index. The id must be unused. */
  std::size_t add(int pid, const Vec3& p, const Vec3i& img, const Vec3& v, double m, int t, int mol,
                  const Vec3& fext, std::uint8_t fix);
  /** Remove by id (swap with the last local particle). */
  void remove(int pid);
  void clear();

  void clear_ghosts() {
    ghost_pos.clear();
    ghost_force.clear();
    ghost_origin.clear();
    ghost_shift.clear();
  }
  /** Position of the particle with combined index i (local or ghost). */
  const Vec3& position(std::size_t i) const {
    return i < n_local() ? pos[i] : ghost_pos[i - n_local()];
  }
  /** Local index owning combined index i. */
  int owner(std::size_t i) const {
    return i < n_local() ? static_cast<int>(i) : ghost_origin[i - n_local()];
  }
};

} // namespace pyoif
