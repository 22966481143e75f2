#include "lb/speed_watch.hpp"

#include "lb/lb_lattice.hpp"

#include <algorithm>
#include <type_traits>

namespace pyoif::lb {

template <typename Real>
FastNode fastest_node(const Real* f, const std::ptrdiff_t* read, const std::vector<FluidRun>& runs,
                      double rho0, const Vec3& force) {
  using namespace d3q19;
  FastNode fastest;
  const double fx = 0.5 * force[0], fy = 0.5 * force[1], fz = 0.5 * force[2];
  // blocks of nodes: the moments vectorised over a block (as the update's
  // collision), the largest speed picked from the block's results
  constexpr int block = 32;
  alignas(64) double u2[block];
  for (const FluidRun& r : runs) {
    const std::size_t end = r.start + r.length;
    for (std::size_t b0 = r.start; b0 < end; b0 += block) {
      const int len = static_cast<int>(std::min<std::size_t>(block, end - b0));
      const Real* in[Q];
      for (int q = 0; q < Q; ++q)
        in[q] = f + read[q] + static_cast<std::ptrdiff_t>(b0);
#pragma GCC ivdep
      for (int i = 0; i < len; ++i) {
        double rho = std::is_same_v<Real, float> ? rho0 : 0.0, jx = fx, jy = fy, jz = fz;
#pragma GCC unroll 19
        for (int q = 0; q < Q; ++q) {
          const double v = in[q][i];
          rho += v;
          if (c[q][0])
            jx += c[q][0] * v;
          if (c[q][1])
            jy += c[q][1] * v;
          if (c[q][2])
            jz += c[q][2] * v;
        }
        u2[i] = (jx * jx + jy * jy + jz * jz) / (rho * rho);
      }
      for (int i = 0; i < len; ++i)
        // a NaN is the update's to report (it stops the run); not a speed
        if (u2[i] > fastest.u2)
          fastest = {b0 + static_cast<std::size_t>(i), u2[i]};
    }
  }
  return fastest;
}

template FastNode fastest_node<float>(const float*, const std::ptrdiff_t*,
                                      const std::vector<FluidRun>&, double, const Vec3&);
template FastNode fastest_node<double>(const double*, const std::ptrdiff_t*,
                                       const std::vector<FluidRun>&, double, const Vec3&);

} // namespace pyoif::lb
