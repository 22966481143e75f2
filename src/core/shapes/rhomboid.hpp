// Rhomboid(corner, a, b, c, direction): the parallelepiped
// {corner + s a + t b + u c : s, t, u in [0, 1]} (direction = +1) or its
// complement (direction = -1). ESPResSo 4.2: shapes.Rhomboid(corner=, a=, b=,
// c=, direction=). Outside: the exact distance to the solid (faces, edges,
// corners); inside: minus the distance to the nearest face.
#pragma once

#include "shapes/shape.hpp"

#include <Eigen/Dense>
#include <array>

namespace pyoif::shapes {

class Rhomboid : public Shape {
public:
  Rhomboid(const Vec3& corner, const Vec3& a, const Vec3& b, const Vec3& c, int direction = 1);
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override;
  std::string name() const override { return "Rhomboid"; }

  const Vec3& corner() const { return m_corner; }
  const Vec3& a() const { return m_a; }
  const Vec3& b() const { return m_b; }
  const Vec3& c() const { return m_c; }
  int direction() const { return m_direction; }
  bool bounding_box(Vec3& lo, Vec3& hi) const override {
    lo = m_lo;
    hi = m_hi;
    return m_direction == 1;
  }

private:
  /** One face: the parallelogram origin + s u + t v, s, t in [0, 1]. */
  struct Face {
    Vec3 origin, u, v, outward;   ///< outward: unit normal pointing away from the solid
    Eigen::Matrix2d gram_inverse; ///< inverse of the Gram matrix of (u, v)
  };
  /** Closest point of the face to pos; `interior` when it is the foot of the
   *  perpendicular (not on an edge or corner). */
  static Vec3 closest_on_face(const Face& f, const Vec3& pos, bool& interior);

  Vec3 m_corner, m_a, m_b, m_c;
  int m_direction;
  std::array<Face, 6> m_faces;
  Eigen::Matrix3d m_to_skew;   ///< maps pos - corner to its (s, t, u) coordinates
  Vec3 m_lo, m_hi;             ///< axis-aligned box of the 8 corners
  bool m_axis_aligned = false; ///< a cuboid with edges along the axes: [m_lo, m_hi]
};

} // namespace pyoif::shapes
