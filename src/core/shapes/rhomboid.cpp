#include "shapes/rhomboid.hpp"

#include "shapes/direction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pyoif::shapes {

namespace {
/** Closest point of the segment q + t w, t in [0, 1], to pos. */
Vec3 closest_on_segment(const Vec3& q, const Vec3& w, const Vec3& pos) {
  const double t = std::clamp((pos - q).dot(w) / w.squaredNorm(), 0.0, 1.0);
  return q + t * w;
}
} // namespace

Rhomboid::Rhomboid(const Vec3& corner, const Vec3& a, const Vec3& b, const Vec3& c, int direction)
    : m_corner(corner), m_a(a), m_b(b), m_c(c),
      m_direction(checked_direction(direction, "Rhomboid")) {
  const double volume = a.dot(b.cross(c));
  const double scale = a.norm() * b.norm() * c.norm();
  // |a.(b x c)| / (|a||b||c|) is the sine-like measure of how far the edge
  // vectors are from coplanar; 1 for a cuboid, 0 for a flat one.
  if (!(scale > 0.0) || !(std::abs(volume) > 1e-10 * scale))
    throw InputError("Rhomboid: parameters 'a', 'b', 'c' must be non-zero and not coplanar "
                     "(the parallelepiped must have a volume)");
  Eigen::Matrix3d edges;
  edges << a, b, c;
  m_to_skew = edges.inverse();
  m_lo = m_hi = corner;
  for (int i = 1; i < 8; ++i) {
    const Vec3 p = corner + ((i & 1) ? a : Vec3::Zero()) + ((i & 2) ? b : Vec3::Zero()) +
                   ((i & 4) ? c : Vec3::Zero());
    m_lo = m_lo.cwiseMin(p);
    m_hi = m_hi.cwiseMax(p);
  }
  // edges along three different axes: the solid is the box [m_lo, m_hi]
  auto axis_of = [](const Vec3& e) {
    int axis = -1;
    for (int k = 0; k < 3; ++k)
      if (e[k] != 0.0)
        axis = axis == -1 ? k : 3;
    return axis;
  };
  const int ia = axis_of(a), ib = axis_of(b), ic = axis_of(c);
  m_axis_aligned = ia >= 0 && ia < 3 && ib >= 0 && ib < 3 && ic >= 0 && ic < 3 && ia != ib &&
                   ib != ic && ia != ic;

  const Vec3 centre = corner + 0.5 * (a + b + c);
  const std::array<std::array<Vec3, 3>, 3> spans = {{{a, b, c}, {b, c, a}, {c, a, b}}};
  std::size_t k = 0;
  for (const auto& span : spans) {
    const Vec3& u = span[0];
    const Vec3& v = span[1];
    const Vec3& w = span[2]; // the edge that leaves the face pair
    for (const Vec3& origin : {corner, Vec3(corner + w)}) {
      Face f;
      f.origin = origin;
      f.u = u;
      f.v = v;
      f.outward = u.cross(v).normalized();
      const Vec3 face_centre = origin + 0.5 * (u + v);
      if (f.outward.dot(face_centre - centre) < 0.0)
        f.outward = -f.outward;
      Eigen::Matrix2d gram;
      gram << u.dot(u), u.dot(v), u.dot(v), v.dot(v);
      f.gram_inverse = gram.inverse();
      m_faces[k++] = f;
    }
  }
}

Vec3 Rhomboid::closest_on_face(const Face& f, const Vec3& pos, bool& interior) {
  const Vec3 rel = pos - f.origin;
  const Eigen::Vector2d st = f.gram_inverse * Eigen::Vector2d(rel.dot(f.u), rel.dot(f.v));
  if (st[0] >= 0.0 && st[0] <= 1.0 && st[1] >= 0.0 && st[1] <= 1.0) {
    interior = true;
    return f.origin + st[0] * f.u + st[1] * f.v;
  }
  // The parallelogram is convex: when the unconstrained minimum lies outside
  // it, the constrained one lies on its boundary, one of the four edges.
  interior = false;
  const std::array<Vec3, 4> candidates = {
      closest_on_segment(f.origin, f.u, pos), closest_on_segment(f.origin, f.v, pos),
      closest_on_segment(f.origin + f.u, f.v, pos), closest_on_segment(f.origin + f.v, f.u, pos)};
  Vec3 best = candidates[0];
  for (std::size_t i = 1; i < candidates.size(); ++i)
    if ((candidates[i] - pos).squaredNorm() < (best - pos).squaredNorm())
      best = candidates[i];
  return best;
}

void Rhomboid::calc_dist(const Vec3& pos, double& dist, Vec3& normal) const {
  const Vec3 skew = m_to_skew * (pos - m_corner);
  const bool inside = (skew.array() > 0.0).all() && (skew.array() < 1.0).all();
  if (inside) {
    // Inside a convex solid the nearest surface point is the foot on the
    // nearest face plane.
    double d = std::numeric_limits<double>::infinity();
    std::size_t best_face = 0;
    for (std::size_t k = 0; k < m_faces.size(); ++k) {
      const double plane_distance = (m_faces[k].origin - pos).dot(m_faces[k].outward);
      if (plane_distance < d) {
        d = plane_distance;
        best_face = k;
      }
    }
    dist = -m_direction * d;
    normal = m_direction * m_faces[best_face].outward;
    return;
  }
  if (m_axis_aligned) {
    // a cuboid along the axes: its closest point is pos clamped to the box
    // (the general search below gives the same point, at several times the cost)
    const Vec3 closest = pos.cwiseMax(m_lo).cwiseMin(m_hi);
    const double d = (pos - closest).norm();
    if (d > 0.0) {
      dist = m_direction * d;
      normal = m_direction * (pos - closest) / d;
      return;
    }
  }
  // Outside: the closest point of the (convex) solid is the closest point over
  // the six faces.
  double best_d2 = std::numeric_limits<double>::infinity();
  Vec3 closest = pos;
  bool closest_interior = false;
  std::size_t best_face = 0;
  for (std::size_t k = 0; k < m_faces.size(); ++k) {
    bool interior;
    const Vec3 q = closest_on_face(m_faces[k], pos, interior);
    const double d2 = (q - pos).squaredNorm();
    // On ties prefer a perpendicular foot: its normal is the exact face normal.
    if (d2 < best_d2 || (d2 == best_d2 && interior && !closest_interior)) {
      best_d2 = d2;
      closest = q;
      closest_interior = interior;
      best_face = k;
    }
  }
  const double d = std::sqrt(best_d2);
  // At an edge or a corner the normal is along pos - closest; on a face (or
  // exactly on the surface) it is the face normal.
  const Vec3 outward =
      (closest_interior || !(d > 0.0)) ? m_faces[best_face].outward : Vec3((pos - closest) / d);
  dist = m_direction * d;
  normal = m_direction * outward;
}

} // namespace pyoif::shapes
