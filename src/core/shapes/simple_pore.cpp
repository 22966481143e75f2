#include "shapes/simple_pore.hpp"

#include <cmath>
#include <limits>

namespace pyoif::shapes {

SimplePore::SimplePore(const Vec3& center, const Vec3& axis, double length, double radius,
                       double smoothing_radius)
    : m_frame(center, axis, "SimplePore"), m_axis(axis), m_length(length), m_radius(radius),
      m_smoothing_radius(smoothing_radius), m_half_length(0.5 * length),
      m_torus_r(radius + smoothing_radius), m_torus_z(0.5 * length - smoothing_radius) {
  if (!(radius > 0.0) || !std::isfinite(radius))
    throw InputError("SimplePore: parameter 'radius' must be > 0");
  if (!(length > 0.0) || !std::isfinite(length))
    throw InputError("SimplePore: parameter 'length' must be > 0");
  if (!(smoothing_radius >= 0.0) || !(smoothing_radius <= 0.5 * length))
    throw InputError("SimplePore: parameter 'smoothing_radius' must be in [0, length/2]");
}

void SimplePore::calc_dist(const Vec3& pos, double& dist, Vec3& normal) const {
  double r, z;
  Vec3 e_r;
  m_frame.decompose(pos, r, z, e_r);
  const double az = std::abs(z);
  const Vec3 e_z = z >= 0.0 ? m_frame.e_z() : Vec3(-m_frame.e_z());
  const double R = m_radius, h = m_half_length, s = m_smoothing_radius;
  const double cr = m_torus_r, cz = m_torus_z;

  // Inside the material: within the slab, off the channel and not in the
  // corner regions cut away by the rounding.
  const double to_torus_centre = std::hypot(r - cr, az - cz);
  const bool in_corner_cut = r < cr && az > cz && to_torus_centre > s;
  const bool inside = az < h && r > R && !in_corner_cut;

  // Unsigned distance to each surface piece whose perpendicular foot exists,
  // with the outward normal of the material there, (n_r, n_z).
  double d = std::numeric_limits<double>::infinity(), n_r = 0.0, n_z = 1.0;
  if (az <= cz) { // channel wall r = R; the material is at r > R
    d = std::abs(r - R);
    n_r = -1.0;
    n_z = 0.0;
  }
  if (r >= cr && std::abs(az - h) < d) { // slab face |z| = h
    d = std::abs(az - h);
    n_r = 0.0;
    n_z = 1.0;
  }
  if (r <= cr && az >= cz) { // rounding: quarter circle about (cr, cz), radius s
    const double dt = std::abs(to_torus_centre - s);
    if (dt < d) {
      d = dt;
      if (to_torus_centre > 0.0) {
        // The material fills the circle's side of the arc, the cut-away
        // corner lies beyond it: the outward normal points away from the
        // circle's centre.
        n_r = (r - cr) / to_torus_centre;
        n_z = (az - cz) / to_torus_centre;
      } else {
        n_r = -std::sqrt(0.5);
        n_z = std::sqrt(0.5);
      }
    }
  }
  dist = inside ? -d : d;
  normal = n_r * e_r + n_z * e_z;
}

} // namespace pyoif::shapes
