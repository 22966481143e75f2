// Outward unit normals of membrane nodes, for the membrane-collision
// contacts (the model's eq. 9): the area-weighted mean of the normals of the
// node's triangles, sum of N = (b - a) x (c - a) (|N| = 2 S), normalised and
// pointing out of the cell whatever the triangles' order (the sign of the
// cell's oriented volume decides, volume.hpp). Written in the membrane pass
// of every step, before any pair force, so the contacts see the normals of
// the current positions (upstream PyOIF computed them from three chosen
// neighbours in a bond that could run after the pair forces).
#pragma once

#include "interactions/membrane/lanes.hpp"

namespace pyoif::membrane {

/** sign * sum / |sum| (sign * sum, zero, for a zero sum) of the sums x, y, z
 *  of N over a node's triangles; T: double, or Lanes for four cells. */
template <class T> struct OutwardNormal {
  T x, y, z;
  OutwardNormal(T sx, T sy, T sz, T sign) {
    const T len = sqrt_of(sx * sx + sy * sy + sz * sz);
    const T scale = select<T>(len > T{}, sign / len, sign);
    x = sx * scale, y = sy * scale, z = sz * scale;
  }
};

} // namespace pyoif::membrane
