// Cylinder(center, axis, radius, length, direction, open): the finite solid
// cylinder r <= radius, |z| <= length/2 about `axis` through `center`
// (direction = +1), or its complement (direction = -1: a closed can or, with
// open = true, a tube the fluid fills). ESPResSo 4.2 semantics:
// shapes.Cylinder(center=, axis=, radius=, length=, direction=, open=).
//
// Closed: outside, the exact distance to the solid (mantle, flat caps, rim
// circles); inside, minus the distance to the nearest of mantle and caps.
// Open (no caps): the surface is the mantle; a point between the cap planes
// is measured to the mantle, a point beyond them to the nearer rim circle,
// and it counts as outside the solid. The distance then jumps across the cap
// planes inside the tube, as in ESPResSo: an open cylinder is meant to run
// through the periodic box (length >= box length along its axis).
#pragma once

#include "shapes/cylindrical_frame.hpp"
#include "shapes/direction.hpp"
#include "shapes/shape.hpp"

namespace pyoif::shapes {

class Cylinder : public Shape {
public:
  Cylinder(const Vec3& center, const Vec3& axis, double radius, double length, int direction = 1,
           bool open = false);
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override;
  std::string name() const override { return "Cylinder"; }

  const Vec3& center() const { return m_frame.center(); }
  const Vec3& axis() const { return m_axis; }
  double radius() const { return m_radius; }
  double length() const { return m_length; }
  int direction() const { return m_direction; }
  bool open() const { return m_open; }
  bool bounding_box(Vec3& lo, Vec3& hi) const override;

private:
  CylindricalFrame m_frame;
  Vec3 m_axis; ///< as given (not normalised), for read-back
  double m_radius, m_length, m_half_length;
  int m_direction;
  bool m_open;
};

} // namespace pyoif::shapes
