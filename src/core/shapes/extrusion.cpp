#include "shapes/extrusion.hpp"

#include "shapes/direction.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>
#include <utility>

namespace pyoif::shapes {

namespace {
using V2 = Eigen::Vector2d;

double cross(const V2& u, const V2& v) {
  return u[0] * v[1] - u[1] * v[0];
}
int sign(double x) {
  return (x > 0.0) - (x < 0.0);
}
double box_distance2(const V2& p, const V2& lo, const V2& hi) {
  const double dx = std::max({lo[0] - p[0], 0.0, p[0] - hi[0]});
  const double dy = std::max({lo[1] - p[1], 0.0, p[1] - hi[1]});
  return dx * dx + dy * dy;
}
std::string point(const V2& p) {
  std::ostringstream s;
  s.precision(10);
  s << "(" << p[0] << ", " << p[1] << ")";
  return s.str();
}
constexpr int leaf_size = 4;
} // namespace

Extrusion::Extrusion(const std::vector<Polygon>& polygons, double z0, double z1, int direction,
                     const std::vector<std::string>& names)
    : m_z0(z0), m_z1(z1), m_direction(checked_direction(direction, "Extrusion")) {
  if (!(std::isfinite(z0) && std::isfinite(z1) && z0 < z1))
    throw InputError("Extrusion: parameter 'z' must be [z0, z1] with z0 < z1, got [" +
                     std::to_string(z0) + ", " + std::to_string(z1) + "]");
  if (polygons.empty())
    throw InputError("Extrusion: parameter 'polygons' must hold at least one polygon, got none");
  auto label = [&](std::size_t k) {
    return k < names.size() && !names[k].empty() ? names[k] : "polygon " + std::to_string(k);
  };
  std::map<std::pair<double, double>, int> vertex_ids;
  auto vertex_of = [&](const V2& p) {
    const auto key = std::make_pair(p[0], p[1]);
    const auto it = vertex_ids.find(key);
    if (it != vertex_ids.end())
      return it->second;
    const int id = static_cast<int>(m_vertices.size());
    vertex_ids.emplace(key, id);
    m_vertices.emplace_back();
    return id;
  };
  V2 lo = V2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  std::vector<double> areas; // |area| / (box diagonal)^2, checked after the crossings
  for (std::size_t k = 0; k < polygons.size(); ++k) {
    const Polygon& poly = polygons[k];
    // drop repeated vertices (a closing vertex equal to the first one too)
    std::vector<int> keep;
    for (Eigen::Index i = 0; i < poly.rows(); ++i) {
      const V2 p = poly.row(i).transpose();
      if (!p.allFinite())
        throw InputError("Extrusion: " + label(k) + ", vertex " + std::to_string(i) +
                         " is not finite");
      if (keep.empty() || p != V2(poly.row(keep.back()).transpose()))
        keep.push_back(static_cast<int>(i));
    }
    while (keep.size() > 1 &&
           V2(poly.row(keep.back()).transpose()) == V2(poly.row(keep[0]).transpose()))
      keep.pop_back();
    if (keep.size() < 3)
      throw InputError("Extrusion: " + label(k) + " is degenerate: it has " +
                       std::to_string(keep.size()) + " distinct vertices, at least 3 needed");
    double area = 0.0;
    V2 plo = V2::Constant(std::numeric_limits<double>::infinity()), phi = -plo;
    for (std::size_t i = 0; i < keep.size(); ++i) {
      const V2 p = poly.row(keep[i]).transpose();
      const V2 q = poly.row(keep[(i + 1) % keep.size()]).transpose();
      area += 0.5 * cross(p, q);
      plo = plo.cwiseMin(p);
      phi = phi.cwiseMax(p);
    }
    areas.push_back(std::abs(area) / (phi - plo).squaredNorm());
    // all vertices on one line (before the crossing check, which would call
    // the edges overlapping)
    const V2 p0 = poly.row(keep[0]).transpose();
    V2 far = p0;
    for (const int i : keep)
      if ((V2(poly.row(i).transpose()) - p0).squaredNorm() > (far - p0).squaredNorm())
        far = poly.row(i).transpose();
    double off_line = 0.0;
    for (const int i : keep)
      off_line = std::max(off_line, std::abs(cross(far - p0, V2(poly.row(i).transpose()) - p0)));
    if (!(off_line > 1e-12 * (far - p0).squaredNorm()))
      throw InputError("Extrusion: " + label(k) +
                       " is degenerate: its vertices lie on one line (no area)");
    lo = lo.cwiseMin(plo);
    hi = hi.cwiseMax(phi);
    for (std::size_t i = 0; i < keep.size(); ++i) {
      const std::size_t j = (i + 1) % keep.size();
      Edge e;
      e.a = poly.row(keep[i]).transpose();
      e.b = poly.row(keep[j]).transpose();
      e.inv_len2 = 1.0 / (e.b - e.a).squaredNorm();
      e.solid_left = false;
      e.node_a = vertex_of(e.a);
      e.node_b = vertex_of(e.b);
      e.polygon = static_cast<int>(k);
      e.ia = keep[i];
      e.ib = keep[j];
      const int id = static_cast<int>(m_edges.size());
      m_vertices[e.node_a].edges.push_back(id);
      m_vertices[e.node_b].edges.push_back(id);
      m_edges.push_back(e);
    }
  }
  m_lo = Vec3(lo[0], lo[1], z0);
  m_hi = Vec3(hi[0], hi[1], z1);
  m_order.resize(m_edges.size());
  std::iota(m_order.begin(), m_order.end(), 0);
  m_nodes.reserve(2 * m_edges.size() / leaf_size + 2);
  build(0, static_cast<int>(m_edges.size()));
  check_intersections(names); // a bow tie is reported as crossing, not as degenerate
  for (std::size_t k = 0; k < areas.size(); ++k)
    if (!(areas[k] > 1e-12))
      throw InputError("Extrusion: " + label(k) +
                       " is degenerate: its area is zero (collinear vertices)");
  // The solid side of each edge: the even-odd parity just beside its midpoint,
  // counted along a ray (+x, or +y for a horizontal edge) over the other edges.
  for (std::size_t i = 0; i < m_edges.size(); ++i) {
    Edge& e = m_edges[i];
    const V2 m = 0.5 * (e.a + e.b);
    const V2 d = e.b - e.a;
    const int axis = d[1] != 0.0 ? 0 : 1;
    const bool odd = crossings(m, axis, static_cast<int>(i)) % 2 == 1;
    // the +x side is the left one for a downward edge; +y the left one for a rightward edge
    const bool ray_side_is_left = axis == 0 ? d[1] < 0.0 : d[0] > 0.0;
    e.solid_left = odd == ray_side_is_left;
  }
}

int Extrusion::build(int first, int count) {
  const int id = static_cast<int>(m_nodes.size());
  m_nodes.emplace_back();
  V2 lo = V2::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  V2 clo = lo, chi = hi; // box of the midpoints
  for (int k = first; k < first + count; ++k) {
    const Edge& e = m_edges[m_order[k]];
    lo = lo.cwiseMin(e.a).cwiseMin(e.b);
    hi = hi.cwiseMax(e.a).cwiseMax(e.b);
    const V2 c = 0.5 * (e.a + e.b);
    clo = clo.cwiseMin(c);
    chi = chi.cwiseMax(c);
  }
  m_nodes[id].lo = lo;
  m_nodes[id].hi = hi;
  m_nodes[id].first = first;
  m_nodes[id].count = count;
  m_nodes[id].right = -1;
  if (count <= leaf_size)
    return id;
  const int axis = (chi[0] - clo[0]) >= (chi[1] - clo[1]) ? 0 : 1;
  const int half = count / 2;
  std::nth_element(m_order.begin() + first, m_order.begin() + first + half,
                   m_order.begin() + first + count, [&](int i, int j) {
                     return m_edges[i].a[axis] + m_edges[i].b[axis] <
                            m_edges[j].a[axis] + m_edges[j].b[axis];
                   });
  m_nodes[id].count = 0;
  build(first, half);
  const int right = build(first + half, count - half);
  m_nodes[id].right = right;
  return id;
}

std::string Extrusion::where(int edge, const std::vector<std::string>& names) const {
  const Edge& e = m_edges[edge];
  const std::size_t k = static_cast<std::size_t>(e.polygon);
  const std::string poly =
      k < names.size() && !names[k].empty() ? names[k] : "polygon " + std::to_string(k);
  return poly + " (edge from vertex " + std::to_string(e.ia) + " " + point(e.a) + " to vertex " +
         std::to_string(e.ib) + " " + point(e.b) + ")";
}

void Extrusion::check_intersections(const std::vector<std::string>& names) const {
  auto fail = [&](int i, int j, const std::string& how) {
    throw InputError("Extrusion: " + where(i, names) + " " + how + " " + where(j, names) +
                     ": polygons must not cross, overlap or touch along an edge (a hole is a "
                     "polygon inside another; overlapping outlines must be merged first)");
  };
  // c on the segment ab (c collinear with a, b) strictly between its ends
  auto strictly_on = [](const V2& a, const V2& b, const V2& c) {
    return c != a && c != b && c[0] >= std::min(a[0], b[0]) && c[0] <= std::max(a[0], b[0]) &&
           c[1] >= std::min(a[1], b[1]) && c[1] <= std::max(a[1], b[1]);
  };
  std::vector<int> stack;
  for (int i = 0; i < static_cast<int>(m_edges.size()); ++i) {
    const Edge& e = m_edges[i];
    const V2 elo = e.a.cwiseMin(e.b), ehi = e.a.cwiseMax(e.b);
    stack.assign(1, 0);
    while (!stack.empty()) {
      const Node& n = m_nodes[stack.back()];
      const int id = stack.back();
      stack.pop_back();
      if ((n.lo.array() > ehi.array()).any() || (n.hi.array() < elo.array()).any())
        continue;
      if (n.count == 0) {
        stack.push_back(id + 1);
        stack.push_back(n.right);
        continue;
      }
      for (int k = n.first; k < n.first + n.count; ++k) {
        const int j = m_order[k];
        if (j <= i)
          continue;
        const Edge& f = m_edges[j];
        if ((e.a == f.a && e.b == f.b) || (e.a == f.b && e.b == f.a))
          fail(i, j, "coincides with");
        const int o1 = sign(cross(e.b - e.a, f.a - e.a));
        const int o2 = sign(cross(e.b - e.a, f.b - e.a));
        const int o3 = sign(cross(f.b - f.a, e.a - f.a));
        const int o4 = sign(cross(f.b - f.a, e.b - f.a));
        if (o1 * o2 < 0 && o3 * o4 < 0)
          fail(i, j, "crosses");
        if ((o1 == 0 && strictly_on(e.a, e.b, f.a)) || (o2 == 0 && strictly_on(e.a, e.b, f.b)) ||
            (o3 == 0 && strictly_on(f.a, f.b, e.a)) || (o4 == 0 && strictly_on(f.a, f.b, e.b)))
          fail(i, j, "touches");
      }
    }
  }
}

int Extrusion::crossings(const V2& m, int axis, int skip) const {
  // edges straddling the line through m normal to `other` (half-open rule),
  // crossing it beyond m along `axis`
  const int other = 1 - axis;
  int count = 0;
  std::vector<int> stack(1, 0);
  while (!stack.empty()) {
    const int id = stack.back();
    stack.pop_back();
    const Node& n = m_nodes[id];
    if (n.lo[other] > m[other] || n.hi[other] < m[other] || n.hi[axis] <= m[axis])
      continue;
    if (n.count == 0) {
      stack.push_back(id + 1);
      stack.push_back(n.right);
      continue;
    }
    for (int k = n.first; k < n.first + n.count; ++k) {
      const int j = m_order[k];
      if (j == skip)
        continue;
      const Edge& e = m_edges[j];
      if ((e.a[other] > m[other]) == (e.b[other] > m[other]))
        continue;
      const double at =
          e.a[axis] + (m[other] - e.a[other]) * (e.b[axis] - e.a[axis]) / (e.b[other] - e.a[other]);
      if (at > m[axis])
        ++count;
    }
  }
  return count;
}

bool Extrusion::vertex_inside(int vertex, const V2& p) const {
  // p's nearest surface point is this vertex: p lies in the sector between two
  // consecutive edges around it (the segment from p to the vertex crosses no
  // edge). The sector counter-clockwise from the ray that precedes p's
  // direction is solid when that ray has the solid on its left.
  const V2 v = [&] {
    const Edge& e = m_edges[m_vertices[vertex].edges[0]];
    return e.node_a == vertex ? e.a : e.b;
  }();
  const double angle = std::atan2(p[1] - v[1], p[0] - v[0]);
  double best = std::numeric_limits<double>::infinity();
  bool inside = false;
  for (const int j : m_vertices[vertex].edges) {
    const Edge& e = m_edges[j];
    const bool from_a = e.node_a == vertex;
    const V2 ray = from_a ? V2(e.b - e.a) : V2(e.a - e.b);
    double turn = angle - std::atan2(ray[1], ray[0]); // counter-clockwise from the ray to p
    if (turn < 0.0)
      turn += 6.283185307179586; // 2 pi
    if (turn < best) {
      best = turn;
      inside = from_a ? e.solid_left : !e.solid_left;
    }
  }
  return inside;
}

void Extrusion::distance_2d(double x, double y, double& dist, Eigen::Vector2d& normal) const {
  const V2 p(x, y);
  double best_d2 = std::numeric_limits<double>::infinity();
  int best = 0;
  double best_t = 0.0;
  V2 best_q = p;
  // branch and bound over the hierarchy, nearer child first
  std::array<std::pair<int, double>, 128> stack;
  int top = 0;
  stack[top++] = {0, box_distance2(p, m_nodes[0].lo, m_nodes[0].hi)};
  while (top > 0) {
    const auto [id, d2] = stack[--top];
    if (d2 >= best_d2)
      continue;
    const Node& n = m_nodes[id];
    if (n.count == 0) {
      const int l = id + 1, r = n.right;
      const double dl = box_distance2(p, m_nodes[l].lo, m_nodes[l].hi);
      const double dr = box_distance2(p, m_nodes[r].lo, m_nodes[r].hi);
      if (dl <= dr) {
        stack[top++] = {r, dr};
        stack[top++] = {l, dl};
      } else {
        stack[top++] = {l, dl};
        stack[top++] = {r, dr};
      }
      continue;
    }
    for (int k = n.first; k < n.first + n.count; ++k) {
      const int j = m_order[k];
      const Edge& e = m_edges[j];
      const double t = (p - e.a).dot(e.b - e.a) * e.inv_len2;
      const V2 q = t <= 0.0 ? e.a : (t >= 1.0 ? e.b : V2(e.a + t * (e.b - e.a)));
      const double qd2 = (p - q).squaredNorm();
      if (qd2 < best_d2) {
        best_d2 = qd2;
        best = j;
        best_t = t;
        best_q = q;
      }
    }
  }
  const Edge& e = m_edges[best];
  const double d = std::sqrt(best_d2);
  if (!(d > 0.0)) {
    // on the outline: the edge's outward normal
    const V2 left = V2(-(e.b - e.a)[1], (e.b - e.a)[0]).normalized();
    dist = 0.0;
    normal = e.solid_left ? V2(-left) : left;
    return;
  }
  bool inside;
  if (best_t <= 0.0)
    inside = vertex_inside(e.node_a, p);
  else if (best_t >= 1.0)
    inside = vertex_inside(e.node_b, p);
  else
    inside = (cross(e.b - e.a, p - e.a) > 0.0) == e.solid_left;
  dist = inside ? -d : d;
  normal = (inside ? -1.0 : 1.0) * (p - best_q) / d;
}

void Extrusion::calc_dist(const Vec3& pos, double& dist, Vec3& normal) const {
  double e;
  Eigen::Vector2d n2;
  distance_2d(pos[0], pos[1], e, n2);
  const bool above = pos[2] - m_z1 >= m_z0 - pos[2];
  const double s = above ? pos[2] - m_z1 : m_z0 - pos[2];
  const double nz = above ? 1.0 : -1.0;
  double d;
  Vec3 n;
  if (e > 0.0 && s > 0.0) {
    d = std::hypot(e, s);
    n = Vec3(e * n2[0], e * n2[1], s * nz) / d;
  } else if (e >= s) { // beside the wall (outside or inside), or on the surface
    d = e;
    n = Vec3(n2[0], n2[1], 0.0);
  } else { // above or below the layout, or nearer a cap inside
    d = s;
    n = Vec3(0.0, 0.0, nz);
  }
  dist = m_direction * d;
  normal = m_direction * n;
}

} // namespace pyoif::shapes
