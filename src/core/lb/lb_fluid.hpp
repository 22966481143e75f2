// PLACEHOLDER owned by the lattice-Boltzmann work: the interface the system
// and the integrator rely on. The LB implementation replaces this file but
// keeps these members.
#pragma once

#include "system/box_geometry.hpp"
#include "utils/vector.hpp"

namespace pyoif::lb {

class LBFluid {
public:
  double agrid() const { return m_agrid; }
  double tau() const { return m_tau; }
  /** Throws InputError when the fluid does not fit the box or the time step. */
  void validate(const BoxGeometry& box, double time_step) const;
  /** One lattice update: collide (with the forces accumulated since the last
   *  update), stream, boundaries; then the force field is cleared. */
  void step();
  Vec3 total_momentum() const;
  double total_mass() const;

private:
  double m_agrid = 1.0, m_tau = 1.0;
};

}  // namespace pyoif::lb
