// The fluid's fastest node, watched during a run: every `every` lattice
// updates one read-only pass over this rank's fluid nodes finds the largest
// lattice speed |u| (the Mach number is |u| / c_s, c_s = 1/sqrt(3)), and the
// watch keeps the largest seen since it was last read. The update itself
// stops only at the sound speed (collide_stream.cpp); this tells, at a cost
// of one pass per `every` updates, when a run went past the advised Mach
// number (its compressibility error, doc/accuracy.md) long before that.
#pragma once

#include "lb/boundary_links.hpp"
#include "utils/vector.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pyoif::lb {

/** The fastest fluid node of one pass: padded index and lattice speed^2. */
struct FastNode {
  std::size_t node = 0;
  double u2 = -1.0; ///< negative: no fluid node
};

/** The fastest fluid node over `runs` of populations f (read at f[read[q] + n];
 *  float storage holds deviations from the rest density rho0), with the
 *  velocity of the Guo scheme (j + F/2) / rho for a uniform force density
 *  `force` (lattice units; the coupling's local forces are left out: they
 *  shift a node's speed by far less than the limits watched). */
template <typename Real>
FastNode fastest_node(const Real* f, const std::ptrdiff_t* read, const std::vector<FluidRun>& runs,
                      double rho0, const Vec3& force);

/** What the watch saw since it was last read (MD-independent: lattice units). */
struct SpeedWatch {
  /// a pass every `every` updates (0: off); the Python fluid sets it
  /// (lbmd.lb.SPEED_WATCH_EVERY, LBFluid(speed_watch_every=...))
  int every = 100;
  bool seen = false;
  double mach = 0.0;          ///< the largest |u| / c_s seen
  Vec3i node = Vec3i::Zero(); ///< its global lattice node
  std::uint64_t update = 0;   ///< the update after which it was seen

  /** Keeps (mach, node, update) if faster than what was seen. */
  void note(double mach_now, const Vec3i& node_now, std::uint64_t update_now) {
    if (!seen || mach_now > mach) {
      seen = true;
      mach = mach_now;
      node = node_now;
      update = update_now;
    }
  }
};

} // namespace pyoif::lb
