#include "shapes/cylinder.hpp"

#include <algorithm>
#include <cmath>

namespace pyoif::shapes {

Cylinder::Cylinder(const Vec3& center, const Vec3& axis, double radius, double length,
                   int direction, bool open)
    : m_frame(center, axis, "Cylinder"), m_axis(axis), m_radius(radius), m_length(length),
      m_half_length(0.5 * length), m_direction(checked_direction(direction, "Cylinder")),
      m_open(open) {
  if (!(radius > 0.0) || !std::isfinite(radius))
    throw InputError("Cylinder: parameter 'radius' must be > 0");
  if (!(length > 0.0) || !std::isfinite(length))
    throw InputError("Cylinder: parameter 'length' must be > 0");
}

void Cylinder::calc_dist(const Vec3& pos, double& dist, Vec3& normal) const {
  double r, z;
  Vec3 e_r;
  m_frame.decompose(pos, r, z, e_r);
  // Mirror symmetry about the mid-plane: work with |z|, flip e_z back below.
  const double az = std::abs(z);
  const Vec3 e_z = z >= 0.0 ? m_frame.e_z() : Vec3(-m_frame.e_z());
  const double R = m_radius, h = m_half_length;

  // Unsigned distance d to the closest surface feature and the outward normal
  // of the solid cylinder there, (n_r, n_z) in the local (e_r, e_z) basis.
  double d, n_r, n_z;
  const bool outside = az >= h || r >= R;
  if (outside) {
    if (az >= h && (m_open || r >= R)) {
      // Rim circle (r = R, |z| = h): closed cylinders reach it only from
      // beyond both the mantle and the cap plane, open ones from any point
      // beyond the cap plane.
      const double dr = r - R, dz = az - h;
      d = std::hypot(dr, dz);
      if (d > 0.0) {
        n_r = dr / d;
        n_z = dz / d;
      } else { // exactly on the rim: the bisector of mantle and cap normals
        n_r = n_z = std::sqrt(0.5);
      }
    } else if (az >= h) { // closed, r < R: above the cap
      d = az - h;
      n_r = 0.0;
      n_z = 1.0;
    } else { // r >= R, |z| < h: beside the mantle
      d = r - R;
      n_r = 1.0;
      n_z = 0.0;
    }
  } else if (!m_open && h - az < R - r) { // inside, the cap is nearer
    d = h - az;
    n_r = 0.0;
    n_z = 1.0;
  } else { // inside, the mantle is nearer
    d = R - r;
    n_r = 1.0;
    n_z = 0.0;
  }
  const double signed_solid = outside ? d : -d;
  dist = m_direction * signed_solid;
  normal = m_direction * (n_r * e_r + n_z * e_z);
}

bool Cylinder::bounding_box(Vec3& lo, Vec3& hi) const {
  if (m_direction != 1 || m_open)
    return false;
  // extent along k: the axis part h |e_z,k| plus the disc's R sqrt(1 - e_z,k^2)
  const Vec3& e = m_frame.e_z();
  for (int k = 0; k < 3; ++k) {
    const double half =
        m_half_length * std::abs(e[k]) + m_radius * std::sqrt(std::max(0.0, 1.0 - e[k] * e[k]));
    lo[k] = m_frame.center()[k] - half;
    hi[k] = m_frame.center()[k] + half;
  }
  return true;
}

} // namespace pyoif::shapes
