// Sphere(center, radius, direction): the ball |x - center| <= radius
// (direction = +1) or its complement, a spherical cavity (direction = -1).
// ESPResSo: shapes.Sphere(center=, radius=, direction=).
#pragma once

#include "shapes/direction.hpp"
#include "shapes/shape.hpp"

#include <cmath>

namespace pyoif::shapes {

class Sphere : public Shape {
public:
  Sphere(const Vec3& center, double radius, int direction = 1)
      : m_center(center), m_radius(radius), m_direction(checked_direction(direction, "Sphere")) {
    if (!(radius > 0.0) || !std::isfinite(radius))
      throw InputError("Sphere: parameter 'radius' must be > 0");
  }
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override {
    const Vec3 rel = pos - m_center;
    const double len = rel.norm();
    // At the centre every direction is closest; take e_x.
    const Vec3 radial = len > 0.0 ? Vec3(rel / len) : Vec3::UnitX();
    dist = m_direction * (len - m_radius);
    normal = m_direction * radial;
  }
  std::string name() const override { return "Sphere"; }
  bool bounding_box(Vec3& lo, Vec3& hi) const override {
    if (m_direction != 1)
      return false;
    lo = m_center - Vec3::Constant(m_radius);
    hi = m_center + Vec3::Constant(m_radius);
    return true;
  }
  const Vec3& center() const { return m_center; }
  double radius() const { return m_radius; }
  int direction() const { return m_direction; }

private:
  Vec3 m_center;
  double m_radius;
  int m_direction;
};

} // namespace pyoif::shapes
