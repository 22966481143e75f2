// The D3Q19 velocity set: 19 discrete velocities c_q (rest, 6 faces, 12
// edges) with weights w_q and lattice sound speed c_s^2 = 1/3 (Qian,
// d'Humieres & Lallemand 1992). Ordering as in Duenweg, Schiller & Ladd,
// Phys. Rev. E 76, 036704 (2007): q = 2k-1 and q = 2k (k = 1..9) are opposite,
// so populations come in pairs (q, q+1) and c_{q+1} = -c_q for odd q.
#pragma once

#include <array>

namespace pyoif::lb::d3q19 {

constexpr int Q = 19;
constexpr int n_pairs = 9;

constexpr std::array<std::array<int, 3>, Q> c = {{{0, 0, 0},
                                                  {1, 0, 0},
                                                  {-1, 0, 0},
                                                  {0, 1, 0},
                                                  {0, -1, 0},
                                                  {0, 0, 1},
                                                  {0, 0, -1},
                                                  {1, 1, 0},
                                                  {-1, -1, 0},
                                                  {1, -1, 0},
                                                  {-1, 1, 0},
                                                  {1, 0, 1},
                                                  {-1, 0, -1},
                                                  {1, 0, -1},
                                                  {-1, 0, 1},
                                                  {0, 1, 1},
                                                  {0, -1, -1},
                                                  {0, 1, -1},
                                                  {0, -1, 1}}};

constexpr double w0 = 1.0 / 3.0, w_face = 1.0 / 18.0, w_edge = 1.0 / 36.0;
constexpr std::array<double, Q> w = {w0,     w_face, w_face, w_face, w_face, w_face, w_face,
                                     w_edge, w_edge, w_edge, w_edge, w_edge, w_edge, w_edge,
                                     w_edge, w_edge, w_edge, w_edge, w_edge};

constexpr double cs2 = 1.0 / 3.0;

/** The opposite direction: c_{opposite(q)} = -c_q. */
constexpr int opposite(int q) {
  return q == 0 ? 0 : (q % 2 == 1 ? q + 1 : q - 1);
}

} // namespace pyoif::lb::d3q19
