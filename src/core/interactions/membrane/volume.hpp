// Volume conservation of a cell, the model's eq. 7 (doc/model.md). The cell's
// volume is V = sum over its triangles of a.(b x c) / 6 (positions relative
// to any common point; positive when the triangles are ordered with (b - a)
// x (c - a) pointing out of the cell), and its gradient with respect to a
// node is the sum over the node's triangles of N / 6, N = (b - a) x (c - a)
// = 2 S n. The force on each vertex of each triangle,
//   F = -kv (|V| - V0) / V0 * s N / 6,   s = the sign of the oriented V,
// is so exactly -grad of E = kv/2 (|V| - V0)^2 / V0, whichever way the
// triangles are ordered (outward, or the inward order of PyOIF's files).
#pragma once

#include "interactions/membrane/lanes.hpp"

#include <cmath>

namespace pyoif::membrane {

struct VolumeParams {
  double kv = 0.0;
  double volume0 = 0.0; ///< the cell's relaxed volume V0
};

/** -1 where the oriented volume is negative (inward triangle order), else +1. */
template <class T> inline T orientation_sign(T volume) {
  return select<T>(volume < T{}, splat<T>(-1.0), splat<T>(1.0));
}

/** The cell's factor of eq. 7: a node's volume force is this factor times
 *  the sum of N over its triangles. Zero where kv is. */
template <class T> inline T volume_factor(T volume, T sign, T kv, T volume0) {
  const Mask<T> on = kv != T{};
  const T v0 = select<T>(on, volume0, splat<T>(1.0));
  return select<T>(on, -kv * ((sign * volume - v0) / v0) * sign / 6.0, T{});
}

inline double volume_energy(double volume, double kv, double volume0) {
  if (kv == 0.0)
    return 0.0;
  const double dv = std::abs(volume) - volume0;
  return 0.5 * kv * dv * dv / volume0;
}

} // namespace pyoif::membrane
