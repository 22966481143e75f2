// Simulation box: lengths and periodicity per axis, folding and minimum image.
#pragma once

#include "utils/errors.hpp"
#include "utils/vector.hpp"

#include <array>
#include <cmath>
#include <string>

namespace pyoif {

class BoxGeometry {
public:
  BoxGeometry() = default;
  BoxGeometry(const Vec3& length, const std::array<bool, 3>& periodic) {
    set_length(length);
    m_periodic = periodic;
  }

  const Vec3& length() const { return m_length; }
  void set_length(const Vec3& length) {
    for (int d = 0; d < 3; ++d)
      if (!(length[d] > 0.0) || !std::isfinite(length[d]))
        throw InputError("box_l: every component must be a finite positive number, got " +
                         std::to_string(length[d]) + " on axis " + std::to_string(d));
    m_length = length;
  }
  const std::array<bool, 3>& periodic() const { return m_periodic; }
  void set_periodic(const std::array<bool, 3>& p) { m_periodic = p; }
  double volume() const { return m_length.prod(); }
  /** Per axis the distance from the box beyond which a position's image
   *  counter (an int) would overflow when folded: 1e9 box lengths. Input
   *  beyond it is refused; a particle that flies that far has blown up. */
  Vec3 image_range() const { return 1e9 * m_length; }

  /** Vector from b to a, shortest over periodic images. */
  Vec3 minimum_image(const Vec3& a, const Vec3& b) const {
    Vec3 d = a - b;
    // Most separations (bonds, pairs) are well inside half a box: test first,
    // round only when needed (the hot path of every bond loop).
    for (int i = 0; i < 3; ++i)
      if (m_periodic[i] && std::abs(d[i]) > 0.5 * m_length[i])
        d[i] -= m_length[i] * std::round(d[i] / m_length[i]);
    return d;
  }

  /** Fold pos into [0, L) on periodic axes, counting the box images crossed. */
  void fold(Vec3& pos, Vec3i& image) const {
    for (int i = 0; i < 3; ++i) {
      if (!m_periodic[i])
        continue;
      const double shifts = std::floor(pos[i] / m_length[i]);
      if (shifts != 0.0) {
        pos[i] -= shifts * m_length[i];
        image[i] += static_cast<int>(shifts);
        // guard against round-off putting pos exactly at L
        if (pos[i] >= m_length[i]) {
          pos[i] -= m_length[i];
          image[i] += 1;
        }
      }
    }
  }
  Vec3 folded(Vec3 pos) const {
    Vec3i img = Vec3i::Zero();
    fold(pos, img);
    return pos;
  }
  Vec3 unfolded(const Vec3& pos, const Vec3i& image) const {
    return pos + image.cast<double>().cwiseProduct(m_length);
  }

private:
  Vec3 m_length = Vec3::Ones();
  std::array<bool, 3> m_periodic = {true, true, true};
};

} // namespace pyoif
