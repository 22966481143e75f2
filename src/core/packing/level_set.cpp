#include "packing/level_set.hpp"

#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>

namespace pyoif::packing {

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0)
    return a; // vertex region a
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3)
    return b; // vertex region b
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0)
    return a + ab * (d1 / (d1 - d3)); // edge ab
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6)
    return c; // vertex region c
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0)
    return a + ac * (d2 / (d2 - d6)); // edge ac
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))); // edge bc
  const double denom = 1.0 / (va + vb + vc);                    // inside the face
  return a + ab * (vb * denom) + ac * (vc * denom);
}

double winding_number(const Vec3& p, const std::vector<Vec3>& nodes,
                      const std::vector<std::array<int, 3>>& triangles) {
  double sum = 0.0;
  for (const auto& t : triangles) {
    const Vec3 a = nodes[t[0]] - p, b = nodes[t[1]] - p, c = nodes[t[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * M_PI);
}

LevelSet::LevelSet(const std::vector<Vec3>& nodes, const std::vector<std::array<int, 3>>& triangles,
                   double spacing, double band)
    : m_h(spacing), m_inv_h(1.0 / spacing), m_band(band) {
  require(!nodes.empty() && !triangles.empty(), "level set: the surface has no nodes or triangles");
  require(spacing > 0.0 && band > 0.0, "level set: spacing and band must be > 0");
  Vec3 lo = nodes[0], hi = nodes[0];
  for (const Vec3& x : nodes) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  m_lo = lo - Vec3::Constant(band + spacing);
  for (int d = 0; d < 3; ++d)
    m_n[d] = static_cast<int>(std::ceil((hi[d] + band + spacing - m_lo[d]) / spacing)) + 1;
  m_hi = m_lo + spacing * Vec3(m_n[0] - 1, m_n[1] - 1, m_n[2] - 1);
  const std::size_t n_points = static_cast<std::size_t>(m_n[0]) * m_n[1] * m_n[2];
  require(n_points < 200'000'000u, "level set: grid too large; use a coarser spacing");
  m_phi.assign(n_points, static_cast<float>(band));
  auto point = [&](int i, int j, int k) -> Vec3 { return m_lo + spacing * Vec3(i, j, k); };
  auto index_range = [&](double a, double b, int d, int& first, int& last) {
    first = std::max(0, static_cast<int>(std::floor((a - m_lo[d]) / spacing)));
    last = std::min(m_n[d] - 1, static_cast<int>(std::ceil((b - m_lo[d]) / spacing)));
  };

  // unsigned distance within the band: each triangle updates the grid points
  // of its box grown by the band
  for (const auto& t : triangles) {
    const Vec3 &a = nodes[t[0]], &b = nodes[t[1]], &c = nodes[t[2]];
    const Vec3 tlo = a.cwiseMin(b).cwiseMin(c) - Vec3::Constant(band);
    const Vec3 thi = a.cwiseMax(b).cwiseMax(c) + Vec3::Constant(band);
    int r[3][2];
    for (int d = 0; d < 3; ++d)
      index_range(tlo[d], thi[d], d, r[d][0], r[d][1]);
    for (int k = r[2][0]; k <= r[2][1]; ++k)
      for (int j = r[1][0]; j <= r[1][1]; ++j)
        for (int i = r[0][0]; i <= r[0][1]; ++i) {
          const Vec3 p = point(i, j, k);
          const float dist = static_cast<float>((p - closest_point_on_triangle(p, a, b, c)).norm());
          float& slot = m_phi[(static_cast<std::size_t>(k) * m_n[1] + j) * m_n[0] + i];
          slot = std::min(slot, dist);
        }
  }

  // the sign: a ray along z through each column crosses the surface an even
  // number of times; grid points after an odd number of crossings are
  // inside. The column is shifted by a tiny irrational fraction of the
  // spacing so that it misses the mesh's edges and vertices.
  std::vector<std::vector<int>> column_triangles(static_cast<std::size_t>(m_n[0]) * m_n[1]);
  for (std::size_t ti = 0; ti < triangles.size(); ++ti) {
    const auto& t = triangles[ti];
    const Vec3 &a = nodes[t[0]], &b = nodes[t[1]], &c = nodes[t[2]];
    int r[2][2];
    for (int d = 0; d < 2; ++d)
      index_range(std::min({a[d], b[d], c[d]}), std::max({a[d], b[d], c[d]}), d, r[d][0], r[d][1]);
    for (int j = r[1][0]; j <= r[1][1]; ++j)
      for (int i = r[0][0]; i <= r[0][1]; ++i)
        column_triangles[static_cast<std::size_t>(j) * m_n[0] + i].push_back(static_cast<int>(ti));
  }
  const double shift_x = 1.2345679e-6 * spacing, shift_y = 2.7182818e-6 * spacing;
  std::vector<double> crossings;
  for (int j = 0; j < m_n[1]; ++j)
    for (int i = 0; i < m_n[0]; ++i) {
      const double x = m_lo[0] + i * spacing + shift_x, y = m_lo[1] + j * spacing + shift_y;
      crossings.clear();
      for (int ti : column_triangles[static_cast<std::size_t>(j) * m_n[0] + i]) {
        const auto& t = triangles[ti];
        const Vec3 &a = nodes[t[0]], &b = nodes[t[1]], &c = nodes[t[2]];
        // barycentric coordinates of (x, y) in the triangle's projection
        const double det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        if (det == 0.0)
          continue; // a triangle seen edge-on: the ray crosses its neighbours
        const double u = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det;
        const double v = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det;
        if (u < 0.0 || v < 0.0 || u + v > 1.0)
          continue;
        crossings.push_back(a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]));
      }
      std::sort(crossings.begin(), crossings.end());
      std::size_t below = 0;
      for (int k = 0; k < m_n[2]; ++k) {
        const double z = m_lo[2] + k * spacing;
        while (below < crossings.size() && crossings[below] < z)
          ++below;
        if (below % 2 == 1) {
          float& slot = m_phi[(static_cast<std::size_t>(k) * m_n[1] + j) * m_n[0] + i];
          slot = -slot;
        }
      }
    }
}

} // namespace pyoif::packing
