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

namespace pyoif::membrane {

/** A cell's volume term (eq. 7); T: double, or Lanes for four cells. */
template <class T = double> struct VolumeParams {
  T kv{};
  T volume0{}; ///< the cell's relaxed volume V0 (> 0 where kv is not 0)
};

/** -1 where the oriented volume is negative (inward triangle order), else +1. */
template <class T> inline T orientation_sign(T volume) {
  return select<T>(volume < T{}, splat<T>(-1.0), splat<T>(1.0));
}

/** The cell's factor of eq. 7: a node's volume force is this factor times
 *  the sum of N over its triangles. Zero where kv is. With energy (not
 *  null), the cell's energy kv/2 (|V| - V0)^2 / V0. */
template <class T>
inline T volume_factor(const VolumeParams<T>& p, T volume, T sign, T* energy = nullptr) {
  const Mask<T> on = p.kv != T{};
  const T v0 = select<T>(on, p.volume0, splat<T>(1.0));
  const T dv = sign * volume - v0;
  if (energy)
    *energy = select<T>(on, 0.5 * p.kv * dv * dv / v0, T{});
  return select<T>(on, -p.kv * (dv / v0) * sign / 6.0, T{});
}

} // namespace pyoif::membrane
