// Harmonic bond: V(r) = k/2 (r - r_0)^2, broken (an error) beyond r_cut when r_cut > 0.
#pragma once

#include "interactions/bonded/bond_loop.hpp"
#include "utils/vector.hpp"

#include <array>
#include <cmath>

namespace pyoif {

struct HarmonicBond {
  static constexpr const char* name = "HarmonicBond";
  static constexpr int n_particles = 2;
  static constexpr int per_bond_stride = 0;
  double k = 0.0, r_0 = 0.0, r_cut = 0.0;

  /** x[1] is given relative to x[0] by the minimum image. Returns false when
   *  the bond is stretched beyond r_cut. */
  bool forces(const BondInput<2>& in, std::array<Vec3, 2>& f, double& energy) const {
    const Vec3 d = in.x[0] - in.x[1];
    const double r = d.norm();
    if (r_cut > 0.0 && r > r_cut)
      return false;
    const double dr = r - r_0;
    energy = 0.5 * k * dr * dr;
    // F_0 = -k (r - r_0) d/r ; guard r = 0 (force zero by symmetry when r_0 = 0)
    f[0] = (r > 0.0) ? Vec3(-k * dr / r * d) : Vec3::Zero();
    f[1] = -f[0];
    return true;
  }
};

} // namespace pyoif
