// The lattice's geometry, made from the boundaries' shapes: the flag field
// (0 fluid, b + 1 solid of boundary b, ghost layer included), the runs of
// fluid nodes the update sweeps, the fluid-solid links of halfway
// bounce-back (Ladd 1994) and the place runs every fix-up after an update
// is made of (bounce-back and the periodic halo). Pure functions of the
// shapes and a subdomain's padded box: no populations, no communication
// (the ghosts' flags are those the neighbouring rank gives its nodes).
#pragma once

#include "lb/lb_lattice.hpp"
#include "shapes/shape.hpp"
#include "utils/vector.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace pyoif::lb {

/** A boundary: nodes whose centre lies in the shape (dist <= 0) are solid,
 *  moving with `velocity` (MD units). */
struct BoundarySpec {
  std::shared_ptr<const shapes::Shape> shape;
  Vec3 velocity = Vec3::Zero();
};

/** A subdomain with its ghost layer: padded node index n = (z * Py + y) *
 *  Px + x with x, y, z in [0, N + 1]; node (i, j, k) of the global lattice
 *  `global` lies at padded (i - origin + 1, ...). x innermost: fluid runs
 *  follow x, the usual flow direction of a channel, so channels whose
 *  walls are normal to y or z still have long runs. */
struct PaddedBox {
  Vec3i global, origin, extent, pad;
  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * pad[1] + y) * pad[0] + x;
  }
  std::size_t n_padded() const { return static_cast<std::size_t>(pad[0]) * pad[1] * pad[2]; }
};

/** Pairs of places in the populations that a fix-up after the update copies
 *  between (with a term subtracted), as runs: `length` places `step` apart
 *  from `first` and from `second`. Walls and periodic faces give runs of
 *  whole rows along x (step 1), so the fix-ups are vectorised copies
 *  instead of a list of scattered single places; the faces normal to x give
 *  columns along y (step: a row), one descriptor each instead of one per
 *  place (their order does not matter: no place is written twice, none read
 *  after another pair wrote it). */
struct PlaceRun {
  std::size_t first, second;
  std::size_t length;
  double term;
  std::size_t step = 1;
};

/** Single pairs (length 1) merged into runs; sorts them by `first`. */
std::vector<PlaceRun> merge_place_runs(std::vector<PlaceRun> pairs);

/** f[to] = f[from] - term for every pair of the runs, into `first`
 *  (into_first) or into `second` (in double, rounded to Real once). */
template <typename Real>
void apply_place_runs(Real* f, const std::vector<PlaceRun>& runs, bool into_first) {
  for (const PlaceRun& r : runs) {
    // the two sides of a run are disjoint places (ghosts and domain nodes;
    // slots q and -q)
    Real* __restrict to = f + (into_first ? r.first : r.second);
    const Real* __restrict from = f + (into_first ? r.second : r.first);
    // term 0 in the halo: x - 0.0 is x, a float too (through double and back)
    if (r.step == 1) {
      for (std::size_t i = 0; i < r.length; ++i)
        to[i] = static_cast<Real>(from[i] - r.term);
    } else {
      // a cache line per place: the lines `ahead` places on are requested
      // (the hardware prefetchers do not follow a stride of a lattice row)
      constexpr std::size_t ahead = 8;
      const std::size_t step = r.step;
      for (std::size_t i = 0; i < r.length; ++i) {
        if (i + ahead < r.length) {
          __builtin_prefetch(from + (i + ahead) * step, 0, 3);
          __builtin_prefetch(to + (i + ahead) * step, 1, 3);
        }
        to[i * step] = static_cast<Real>(from[i * step] - r.term);
      }
    }
  }
}

/** The flags of every padded node, ghosts included, from the shapes at the
 *  node's global position (wrapped periodically): 0 fluid, b + 1 inside
 *  boundary b, the first boundary containing a node winning. */
std::vector<std::uint16_t> flag_nodes(const std::vector<BoundarySpec>& boundaries,
                                      const PaddedBox& box, double agrid);

/** A run of consecutive fluid nodes along x (padded index of the first)
 *  that relax with one relaxation parameter (SweepParams::relaxation). */
struct FluidRun {
  std::size_t start;
  int length;
  std::uint16_t relaxation = 0;
};

/** A fluid node's link to a solid neighbour. */
struct BoundaryLink {
  std::size_t node, solid; ///< fluid node, padded index of the solid neighbour
  int q, boundary;         ///< direction fluid -> solid, boundary index
  double wall_term;        ///< 6 w_q rho0 c_q . u_wall (lattice units)
};

/** What the update and the boundary forces read of the flags. */
struct FluidGeometry {
  std::vector<FluidRun> runs; ///< in memory order
  std::vector<BoundaryLink> links;
  /// the links as the update uses them: first = slot q of the solid node,
  /// second = slot -q of the fluid node, term = the wall term
  std::vector<PlaceRun> bounce_back;
  std::size_t n_fluid = 0; ///< this subdomain's fluid nodes
};

/** The runs and links of the subdomain's own nodes. neighbour_offset[q]:
 *  padded index of x + c_q less that of x; stride: the populations' (slot
 *  q of node n is q * stride + n); tau and agrid turn the boundaries'
 *  velocities into lattice units; density: rho0 of the wall term. */
FluidGeometry fluid_geometry(const std::vector<std::uint16_t>& flag, const PaddedBox& box,
                             const std::array<std::ptrdiff_t, d3q19::Q>& neighbour_offset,
                             const std::vector<BoundarySpec>& boundaries, double tau, double agrid,
                             double density, std::size_t stride);

} // namespace pyoif::lb
