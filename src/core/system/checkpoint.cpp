// The run state a checkpoint restores (the rest of a checkpoint, configuration
// and bulk state, goes through the ordinary setters; see lbmd/checkpoint.py).
#include "system/system.hpp"
#include "utils/errors.hpp"

#include <string>

namespace pyoif {

void System::restore_run_state(const std::vector<Vec3>& folded_pos, const std::vector<Vec3i>& image,
                               const std::vector<Vec3>& force, const std::vector<Vec3>& normal,
                               const std::vector<Vec3>& rebuild_reference, int lb_substep,
                               bool forces_valid) {
  synchronize();
  auto& p = particles;
  const std::size_t n = p.n_local();
  const auto check = [n](std::size_t got, const char* what) {
    if (got != n)
      throw InputError(std::string("checkpoint: ") + what + " has " + std::to_string(got) +
                       " rows for " + std::to_string(n) + " particles");
  };
  check(folded_pos.size(), "the positions");
  check(image.size(), "the images");
  check(force.size(), "the forces");
  check(normal.size(), "the normals");
  if (!rebuild_reference.empty())
    check(rebuild_reference.size(), "the positions of the last re-sort");
  if (lb_substep < 0 || (m_lb && lb_substep >= lb_steps_per_update()))
    throw InputError("checkpoint: MD steps since the last lattice update " +
                     std::to_string(lb_substep) + " out of range");
  p.image = image;
  if (!rebuild_reference.empty()) {
    // the re-sort of the saved run, at its positions: the same pair list in
    // the same order (and under MPI the same owners), so the pair forces
    // are summed as in the run this one continues
    p.pos = rebuild_reference;
    cells.invalidate();
    prepare_step(-1);
  } else {
    cells.invalidate();
  }
  p.pos = folded_pos;
  p.force = force;
  p.normal = normal;
  m_lb_substep = m_lb ? lb_substep : 0;
  // valid only where they were at the save: a checkpoint written before
  // any force calculation (a stop signal before the first step) holds no
  // forces, and the resumed run must compute them as the first run would
  if (forces_valid)
    mark_forces_valid();
  else
    invalidate_forces();
}

} // namespace pyoif
