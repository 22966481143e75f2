// SimplePore(center, axis, length, radius, smoothing_radius): a slab of
// thickness `length` normal to `axis`, centred on `center`, pierced by a
// cylindrical channel of radius `radius` whose mouths are rounded by torus
// segments of radius `smoothing_radius`. The shape is the slab material; the
// channel and both half-spaces beyond the slab are free.
// ESPResSo 4.2: shapes.SimplePore(center=, axis=, length=, radius=, smoothing_radius=).
//
// The distance is exact on both sides: in the meridional (r, z) half-plane
// the surface is the channel wall r = R (|z| <= h - s), the quarter circle of
// radius s about (R + s, h - s) and the face |z| = h (r >= R + s), joined
// with continuous tangents, so the closest surface point is the
// perpendicular foot on one of these three pieces.
#pragma once

#include "shapes/cylindrical_frame.hpp"
#include "shapes/shape.hpp"

namespace pyoif::shapes {

class SimplePore : public Shape {
public:
  SimplePore(const Vec3& center, const Vec3& axis, double length, double radius,
             double smoothing_radius);
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override;
  std::string name() const override { return "SimplePore"; }

  const Vec3& center() const { return m_frame.center(); }
  const Vec3& axis() const { return m_axis; }
  double length() const { return m_length; }
  double radius() const { return m_radius; }
  double smoothing_radius() const { return m_smoothing_radius; }

private:
  CylindricalFrame m_frame;
  Vec3 m_axis;
  double m_length, m_radius, m_smoothing_radius;
  double m_half_length;
  double m_torus_r, m_torus_z; ///< centre of the smoothing circle in (r, |z|)
};

} // namespace pyoif::shapes
