// Base class of all shapes. A shape is a region of space (the solid: a wall's
// far side, a sphere's interior...). Used by particle constraints and, in the
// lattice-Boltzmann code, to flag boundary nodes.
#pragma once

#include "utils/vector.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

namespace pyoif::shapes {

/** Euclidean distance of pos from the axis-aligned box [lo, hi] (0 inside). */
inline double box_distance(const Vec3& pos, const Vec3& lo, const Vec3& hi) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double out = pos[k] < lo[k] ? lo[k] - pos[k] : (pos[k] > hi[k] ? pos[k] - hi[k] : 0.0);
    d2 += out * out;
  }
  return std::sqrt(d2);
}

class Shape {
public:
  virtual ~Shape() = default;
  /** Signed distance `dist` of `pos` from the surface: positive outside the
   *  shape (where particles and fluid may be), negative inside. `normal` is the
   *  unit outward normal of the surface at the closest surface point, so that
   *  pos - dist * normal is that point (for dist != 0). */
  virtual void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const = 0;
  /** True where the shape occupies space (dist <= 0). */
  bool is_inside(const Vec3& pos) const {
    double dist;
    Vec3 n;
    calc_dist(pos, dist, n);
    return dist <= 0.0;
  }
  virtual std::string name() const = 0;
  /** An axis-aligned box [lo, hi] that contains the whole solid; false for
   *  unbounded solids (walls, complements). Outside the box the signed
   *  distance is at least box_distance(pos, lo, hi), which lets the
   *  constraints and unions skip the exact distance of far points. */
  virtual bool bounding_box(Vec3& /*lo*/, Vec3& /*hi*/) const { return false; }
  /** Grows whenever the shape changes after construction (only a Union
   *  can: its add, remove, clear), so that a constraint's user (System)
   *  notices that forces computed before no longer hold. */
  virtual std::uint64_t version() const { return 0; }
  /** Signed distances of n points for the constraints' loop: dist[i] is the
   *  exact signed distance where it is below `range` (> 0) and otherwise any
   *  value >= range. The default skips the exact distance of points farther
   *  than range from the bounding box; shapes with a cheap distance override
   *  it with one tight loop (no virtual call per point). */
  virtual void signed_distances(const Vec3* pos, std::size_t n, double range, double* dist) const {
    Vec3 lo, hi, normal;
    const bool bounded = bounding_box(lo, hi);
    for (std::size_t i = 0; i < n; ++i) {
      if (bounded) {
        const double lower_bound = box_distance(pos[i], lo, hi);
        if (lower_bound >= range) {
          dist[i] = lower_bound;
          continue;
        }
      }
      calc_dist(pos[i], dist[i], normal);
    }
  }
  /** True when pos is certainly farther than `range` (> 0) from the solid. */
  bool farther_than(const Vec3& pos, double range) const {
    Vec3 lo, hi;
    return bounding_box(lo, hi) && box_distance(pos, lo, hi) >= range;
  }
};

} // namespace pyoif::shapes
