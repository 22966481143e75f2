// The populations of one (sub)lattice and the parity of the in-place update.
//
// Storage: structure of arrays, population q of padded node n at
// f[q * stride + n] (the padded node index and the neighbour offsets c_q are
// the lattice's: LBFluid), one 64-byte aligned block.
//
// One lattice, updated in place with the AA access pattern (Bailey, Myre,
// Walsh, Lilja & Saar, ICPP 2009): every node reads and writes the same 19
// memory places within one update, so there is no second lattice and no
// write-allocate traffic, and nodes never race under OpenMP.
//   even update: read f_q at the node itself, collide, write f*_q into the
//     node's own slot of the opposite direction -q ("swapped" state);
//   odd update: read the incoming f_q from slot -q of node x - c_q, collide,
//     push f*_q into slot q of node x + c_q ("normal" state again).
// In the normal state the pre-collision f_q of node x is at (q, x); in the
// swapped state it is at (-q, x - c_q), see slot(). Every node access goes
// through slot(), so users never see the difference.
//
// Precision: the populations are stored as double, or as float when
// single_precision. Every function that touches them is a template on the
// stored type (Real), chosen once per call by visit(), outside the node
// loops. In single precision the array holds the deviations
// g_q = f_q - w_q rho0 from the rest state at the reference density rho0
// (Skordos, Phys. Rev. E 48, 4823 (1993)): a fluid near rest stores values
// near 0, so float keeps ~7 digits of the small non-equilibrium parts
// instead of ~7 digits of w_q rho0, and the collision computes in float on
// them (collide_stream.cpp). Copies and bounce-back (f_-q = f_q - wall term,
// w_q = w_-q) act on the deviations unchanged; everything that needs a full
// population adds w_q rho0 back (full(), LBFluid::moments_of).
#pragma once

#include "lb/lb_lattice.hpp"

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

namespace pyoif::lb {

class PopulationStorage {
public:
  PopulationStorage() = default;
  ~PopulationStorage();
  PopulationStorage(const PopulationStorage&) = delete;
  PopulationStorage& operator=(const PopulationStorage&) = delete;

  /** Q * stride zeroed values (stride: n_nodes rounded up to 8, so that
   *  every stream starts 64-byte aligned in double), the normal state.
   *  neighbour_offset[q]: padded index of x + c_q less that of x. */
  void allocate(std::size_t n_nodes, const std::array<std::ptrdiff_t, d3q19::Q>& neighbour_offset,
                bool single_precision, double rest_density);
  /** Values per stream (bound of every padded index). */
  std::size_t stride() const { return m_stride; }
  bool single_precision() const { return m_single; }
  /** Bytes per stored value. */
  std::size_t value_bytes() const { return m_single ? sizeof(float) : sizeof(double); }

  /** After an odd number of updates (see top). */
  bool swapped() const { return m_swapped; }
  /** The update's end: swapped after an even update, normal after an odd one. */
  void set_swapped(bool swapped) { m_swapped = swapped; }
  /** Per population q, the offset that locates it in a layout (normal:
   *  q * stride; swapped: -q * stride - c_q). */
  const std::ptrdiff_t* read_offset_in(bool swapped) const {
    return swapped ? m_read_swapped.data() : m_read_normal.data();
  }
  const std::ptrdiff_t* read_offset() const { return read_offset_in(m_swapped); }
  /** Offset of the pre-collision population q of padded node n (fluid
   *  node, or a domain node of any kind in the normal state). */
  std::size_t slot(int q, std::size_t n) const {
    return static_cast<std::size_t>(read_offset()[q] + static_cast<std::ptrdiff_t>(n));
  }

  /** body(f) with f the populations as double* or float* (their stored
   *  type): the one branch on the precision, outside the caller's loops. */
  template <class Body> decltype(auto) visit(Body&& body) const {
    if (m_single)
      return std::forward<Body>(body)(static_cast<float*>(m_data));
    return std::forward<Body>(body)(static_cast<double*>(m_data));
  }
  /** The stored value at `slot` (in single precision a deviation). */
  double at(std::size_t slot) const {
    return m_single ? double(static_cast<const float*>(m_data)[slot])
                    : static_cast<const double*>(m_data)[slot];
  }
  /** Stores v at `slot` (rounded to float in single precision). */
  void set_at(std::size_t slot, double v) {
    if (m_single)
      static_cast<float*>(m_data)[slot] = static_cast<float>(v);
    else
      static_cast<double*>(m_data)[slot] = v;
  }
  /** What the array holds less the population: w_q rho0 in single
   *  precision (deviation storage), 0 in double. */
  double rest(int q) const { return m_single ? d3q19::w[q] * m_rest_density : 0.0; }
  /** The full population q at `slot`. */
  double full(int q, std::size_t slot) const { return at(slot) + rest(q); }
  /** Stores the full population v of direction q at `slot`. */
  void set_full(int q, std::size_t slot, double v) { set_at(slot, v - rest(q)); }

  /** Rewrites a swapped lattice in the normal layout (rare: geometry
   *  changes). for_each_node(body) calls body(n) for every padded node n
   *  that holds populations (the fluid nodes), the same order each call. */
  template <class ForEachNode> void normalize(ForEachNode&& for_each_node);

private:
  void clear();

  void* m_data = nullptr;
  std::size_t m_stride = 0;
  bool m_single = false;
  double m_rest_density = 0.0;
  bool m_swapped = false;
  std::array<std::ptrdiff_t, d3q19::Q> m_read_normal{}, m_read_swapped{};
};

template <class ForEachNode> void PopulationStorage::normalize(ForEachNode&& for_each_node) {
  if (!m_swapped)
    return;
  // pre-collision populations of every listed node, gathered from their
  // swapped places, then written back at (q, node); the others hold none
  constexpr int Q = d3q19::Q;
  std::vector<double> gathered;
  for_each_node([&](std::size_t n) {
    for (int q = 0; q < Q; ++q)
      gathered.push_back(at(slot(q, n)));
  });
  m_swapped = false;
  clear();
  std::size_t k = 0;
  for_each_node([&](std::size_t n) {
    for (int q = 0; q < Q; ++q)
      set_at(slot(q, n), gathered[k++]);
  });
}

} // namespace pyoif::lb
