// Base class of all shapes. A shape is a region of space (the solid: a wall's
// far side, a sphere's interior...). Used by particle constraints and, in the
// lattice-Boltzmann code, to flag boundary nodes.
#pragma once

#include "utils/vector.hpp"

#include <string>

namespace pyoif::shapes {

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
};

}  // namespace pyoif::shapes
