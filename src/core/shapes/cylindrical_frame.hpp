// Cylindrical coordinates (r, z) about an axis through a centre, shared by the
// axisymmetric shapes (Cylinder, SimplePore). For an axisymmetric solid the
// closest surface point of pos lies in pos's own meridional half-plane, so
// these shapes reduce the 3D distance to a 2D one in (r, z).
#pragma once

#include "utils/errors.hpp"
#include "utils/vector.hpp"

#include <cmath>
#include <string>

namespace pyoif::shapes {

class CylindricalFrame {
public:
  CylindricalFrame(const Vec3& center, const Vec3& axis, const char* owner) : m_center(center) {
    const double len = axis.norm();
    if (!(len > 0.0) || !std::isfinite(len))
      throw InputError(std::string(owner) + ": parameter 'axis' must be a non-zero vector");
    m_e_z = axis / len;
    // A fixed unit vector normal to the axis, used as e_r for points on the axis.
    const Vec3 trial = std::abs(m_e_z.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
    m_e_r_on_axis = (trial - trial.dot(m_e_z) * m_e_z).normalized();
  }

  /** Splits pos - center into z (along the axis), r >= 0 and the unit radial
   *  direction e_r (a fixed normal of the axis where r == 0). */
  void decompose(const Vec3& pos, double& r, double& z, Vec3& e_r) const {
    const Vec3 rel = pos - m_center;
    z = rel.dot(m_e_z);
    Vec3 radial = rel - z * m_e_z;
    // Project once more: near the axis the first projection is dominated by
    // rounding and may keep a component along the axis.
    radial -= radial.dot(m_e_z) * m_e_z;
    r = radial.norm();
    e_r = r > 0.0 ? Vec3(radial / r) : m_e_r_on_axis;
  }

  const Vec3& center() const { return m_center; }
  const Vec3& e_z() const { return m_e_z; }

private:
  Vec3 m_center, m_e_z, m_e_r_on_axis;
};

} // namespace pyoif::shapes
