#include "shapes/surface_mesh.hpp"

#include "shapes/direction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <tuple>

namespace pyoif::shapes {

namespace {

constexpr int leaf_size = 4;

std::string describe_vertex(const std::vector<Vec3>& v, int i) {
  std::ostringstream s;
  s.precision(10);
  s << i << " (" << v[i][0] << ", " << v[i][1] << ", " << v[i][2] << ")";
  return s.str();
}

/** Squared distance of p from the box [lo, hi] (0 inside). */
double box_distance2(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double out = p[k] < lo[k] ? lo[k] - p[k] : (p[k] > hi[k] ? p[k] - hi[k] : 0.0);
    d2 += out * out;
  }
  return d2;
}

/** Interior angle of the triangle at vertex a (between a->b and a->c). */
double angle_at(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 u = b - a, v = c - a;
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

} // namespace

SurfaceMesh::SurfaceMesh(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                         int direction)
    : m_vertices(vertices), m_triangles(triangles),
      m_direction(checked_direction(direction, "SurfaceMesh")) {
  const int nv = static_cast<int>(m_vertices.size());
  const int nt = static_cast<int>(m_triangles.size());
  if (nv == 0 || nt == 0)
    throw InputError("SurfaceMesh: the mesh is empty (" + std::to_string(nv) + " vertices, " +
                     std::to_string(nt) +
                     " triangles); a closed surface needs at least 4 "
                     "triangles");
  for (int i = 0; i < nv; ++i)
    if (!m_vertices[i].allFinite())
      throw InputError("SurfaceMesh: vertex " + std::to_string(i) + " is not finite");
  for (int t = 0; t < nt; ++t) {
    const Triangle& tri = m_triangles[t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] < 0 || tri[k] >= nv)
        throw InputError("SurfaceMesh: triangle " + std::to_string(t) + " has vertex index " +
                         std::to_string(tri[k]) + ", expected 0.." + std::to_string(nv - 1));
    const Vec3 &a = m_vertices[tri[0]], &b = m_vertices[tri[1]], &c = m_vertices[tri[2]];
    const double longest2 =
        std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    const double twice_area = (b - a).cross(c - a).norm();
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] || !(longest2 > 0.0) ||
        !(twice_area > 1e-12 * longest2))
      throw InputError("SurfaceMesh: triangle " + std::to_string(t) +
                       " is degenerate (no area): vertices " + describe_vertex(m_vertices, tri[0]) +
                       ", " + describe_vertex(m_vertices, tri[1]) + ", " +
                       describe_vertex(m_vertices, tri[2]));
  }

  // Edges: every undirected edge must belong to exactly two triangles that run
  // through it in opposite directions (closed, manifold, consistently oriented).
  struct HalfEdge {
    int lo, hi, triangle, local;
    bool forward; ///< the triangle runs lo -> hi
  };
  std::vector<HalfEdge> half_edges;
  half_edges.reserve(3 * static_cast<std::size_t>(nt));
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int from = m_triangles[t][k], to = m_triangles[t][(k + 1) % 3];
      half_edges.push_back({std::min(from, to), std::max(from, to), t, k, from < to});
    }
  std::sort(half_edges.begin(), half_edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.lo, x.hi, x.triangle, x.local) < std::tie(y.lo, y.hi, y.triangle, y.local);
  });
  std::vector<std::array<int, 3>> neighbour(nt, {-1, -1, -1});
  for (std::size_t i = 0; i < half_edges.size();) {
    std::size_t j = i;
    while (j < half_edges.size() && half_edges[j].lo == half_edges[i].lo &&
           half_edges[j].hi == half_edges[i].hi)
      ++j;
    const HalfEdge& e = half_edges[i];
    const std::string edge = "edge between vertices " + describe_vertex(m_vertices, e.lo) +
                             " and " + describe_vertex(m_vertices, e.hi);
    if (j - i == 1)
      throw InputError("SurfaceMesh: the surface is open (not watertight): " + edge +
                       " belongs to only one triangle (" + std::to_string(e.triangle) +
                       "); a closed surface has every edge in exactly two triangles");
    if (j - i > 2) {
      std::string list;
      for (std::size_t k = i; k < j; ++k)
        list += (k > i ? ", " : "") + std::to_string(half_edges[k].triangle);
      throw InputError("SurfaceMesh: the surface is non-manifold: " + edge + " belongs to " +
                       std::to_string(j - i) + " triangles (" + list +
                       "); every edge must be in exactly two");
    }
    const HalfEdge& f = half_edges[i + 1];
    if (e.forward == f.forward)
      throw InputError("SurfaceMesh: inconsistent orientation: triangles " +
                       std::to_string(e.triangle) + " and " + std::to_string(f.triangle) +
                       " run through their shared " + edge +
                       " in the same direction; neighbours must run through it in opposite "
                       "directions (all counter-clockwise seen from outside)");
    neighbour[e.triangle][e.local] = f.triangle;
    neighbour[f.triangle][f.local] = e.triangle;
    i = j;
  }
  // Around each vertex its triangles must form one fan (a disc): two closed
  // surfaces that touch at a vertex share no edge but make it non-manifold.
  // Union-find over triangle corners, joined across the shared edges.
  std::vector<int> parent(3 * static_cast<std::size_t>(nt));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) {
    while (parent[x] != x)
      x = parent[x] = parent[parent[x]];
    return x;
  };
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const Triangle& other = m_triangles[neighbour[t][k]];
      for (int end = 0; end < 2; ++end) {
        const int corner = (k + end) % 3;
        const int vertex = m_triangles[t][corner];
        const int at = other[0] == vertex ? 0 : (other[1] == vertex ? 1 : 2);
        parent[root(3 * t + corner)] = root(3 * neighbour[t][k] + at);
      }
    }
  std::vector<int> fan(nv, -1);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int vertex = m_triangles[t][k];
      const int r = root(3 * t + k);
      if (fan[vertex] == -1)
        fan[vertex] = r;
      else if (fan[vertex] != r)
        throw InputError("SurfaceMesh: the surface is non-manifold at vertex " +
                         describe_vertex(m_vertices, vertex) +
                         ": its triangles form separate fans (surfaces that touch at a point); "
                         "every vertex must have one ring of triangles");
    }

  for (const Triangle& tri : m_triangles) {
    const Vec3 &a = m_vertices[tri[0]], &b = m_vertices[tri[1]], &c = m_vertices[tri[2]];
    m_volume += a.dot(b.cross(c)) / 6.0;
  }
  if (m_volume < 0.0) {
    for (Triangle& tri : m_triangles)
      std::swap(tri[1], tri[2]);
    // local edge k ran tri[k] -> tri[k+1]; after the swap (0 2 1) edge ab
    // is the old ca, bc the old bc reversed, ca the old ab
    for (auto& nb : neighbour)
      std::swap(nb[0], nb[2]);
    m_volume = -m_volume;
    m_inverted = true;
  }
  Vec3 extent_lo = m_vertices[m_triangles[0][0]], extent_hi = extent_lo;
  for (const Triangle& tri : m_triangles)
    for (int k = 0; k < 3; ++k) {
      extent_lo = extent_lo.cwiseMin(m_vertices[tri[k]]);
      extent_hi = extent_hi.cwiseMax(m_vertices[tri[k]]);
    }
  m_lo = extent_lo;
  m_hi = extent_hi;
  const double size = (m_hi - m_lo).norm();
  if (!(m_volume > 1e-12 * size * size * size))
    throw InputError("SurfaceMesh: the surface encloses no volume");

  // Pseudo-normals (Bærentzen & Aanæs 2005): face normals; an edge's is the
  // sum of its two faces' normals; a vertex's the sum of its faces' normals
  // weighted by the face's angle at the vertex.
  m_face_normals.resize(nt);
  m_vertex_normals.assign(nv, Vec3::Zero());
  m_edge_normals.resize(nt);
  for (int t = 0; t < nt; ++t) {
    const Triangle& tri = m_triangles[t];
    const Vec3 &a = m_vertices[tri[0]], &b = m_vertices[tri[1]], &c = m_vertices[tri[2]];
    m_face_normals[t] = (b - a).cross(c - a).normalized();
    m_vertex_normals[tri[0]] += angle_at(a, b, c) * m_face_normals[t];
    m_vertex_normals[tri[1]] += angle_at(b, c, a) * m_face_normals[t];
    m_vertex_normals[tri[2]] += angle_at(c, a, b) * m_face_normals[t];
  }
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      m_edge_normals[t][k] = m_face_normals[t] + m_face_normals[neighbour[t][k]];

  // The tree: median splits along the longest axis of the centroids' box.
  std::vector<Vec3> centroids(nt);
  for (int t = 0; t < nt; ++t) {
    const Triangle& tri = m_triangles[t];
    centroids[t] = (m_vertices[tri[0]] + m_vertices[tri[1]] + m_vertices[tri[2]]) / 3.0;
  }
  m_order.resize(nt);
  std::iota(m_order.begin(), m_order.end(), 0);
  m_nodes.reserve(2 * static_cast<std::size_t>(nt / leaf_size + 1));
  build(0, nt, centroids, 0);
  m_corners.resize(nt);
  for (int i = 0; i < nt; ++i)
    for (int k = 0; k < 3; ++k)
      m_corners[i][k] = m_vertices[m_triangles[m_order[i]][k]];
}

int SurfaceMesh::build(int first, int count, std::vector<Vec3>& centroids, int depth) {
  const int index = static_cast<int>(m_nodes.size());
  m_nodes.emplace_back();
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  Vec3 clo = lo, chi = hi;
  for (int i = first; i < first + count; ++i) {
    const Triangle& tri = m_triangles[m_order[i]];
    for (int k = 0; k < 3; ++k) {
      lo = lo.cwiseMin(m_vertices[tri[k]]);
      hi = hi.cwiseMax(m_vertices[tri[k]]);
    }
    clo = clo.cwiseMin(centroids[m_order[i]]);
    chi = chi.cwiseMax(centroids[m_order[i]]);
  }
  m_nodes[index].lo = lo;
  m_nodes[index].hi = hi;
  if (count <= leaf_size || depth > 60) {
    m_nodes[index].first = first;
    m_nodes[index].count = count;
    return index;
  }
  int axis;
  (chi - clo).maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(m_order.begin() + first, m_order.begin() + first + half,
                   m_order.begin() + first + count,
                   [&](int x, int y) { return centroids[x][axis] < centroids[y][axis]; });
  const int left = build(first, half, centroids, depth + 1);
  const int right = build(first + half, count - half, centroids, depth + 1);
  m_nodes[index].left = left;
  m_nodes[index].right = right;
  return index;
}

// Ericson, Real-Time Collision Detection (2005), 5.1.5: the Voronoi regions of
// the triangle's vertices, edges and face, in that order.
Vec3 SurfaceMesh::closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                                      Feature& feature) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    feature = Feature::VertexA;
    return a;
  }
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    feature = Feature::VertexB;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    feature = Feature::EdgeAB;
    return a + (d1 / (d1 - d3)) * ab;
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    feature = Feature::VertexC;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    feature = Feature::EdgeCA;
    return a + (d2 / (d2 - d6)) * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    feature = Feature::EdgeBC;
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  feature = Feature::Face;
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

Vec3 SurfaceMesh::pseudo_normal(int t, Feature feature) const {
  const Triangle& tri = m_triangles[t];
  switch (feature) {
  case Feature::Face:
    return m_face_normals[t];
  case Feature::EdgeAB:
    return m_edge_normals[t][0];
  case Feature::EdgeBC:
    return m_edge_normals[t][1];
  case Feature::EdgeCA:
    return m_edge_normals[t][2];
  case Feature::VertexA:
    return m_vertex_normals[tri[0]];
  case Feature::VertexB:
    return m_vertex_normals[tri[1]];
  case Feature::VertexC:
    return m_vertex_normals[tri[2]];
  }
  return m_face_normals[t];
}

void SurfaceMesh::calc_dist(const Vec3& pos, double& dist, Vec3& normal) const {
  double best2 = std::numeric_limits<double>::infinity();
  Vec3 closest = pos;
  int best_triangle = 0;
  Feature best_feature = Feature::Face;
  // depth-first, nearer child first; a subtree whose box is no nearer than the
  // best triangle so far cannot hold a nearer one
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = m_nodes[stack[--top]];
    if (box_distance2(pos, node.lo, node.hi) >= best2)
      continue;
    if (node.left < 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const auto& corners = m_corners[i];
        // the distance from the triangle's plane is a lower bound of that
        // from the triangle, and costs one dot product
        const double plane = (pos - corners[0]).dot(m_face_normals[m_order[i]]);
        if (plane * plane >= best2)
          continue;
        Feature feature;
        const Vec3 q = closest_on_triangle(pos, corners[0], corners[1], corners[2], feature);
        const double d2 = (q - pos).squaredNorm();
        if (d2 < best2) {
          best2 = d2;
          closest = q;
          best_triangle = m_order[i];
          best_feature = feature;
        }
      }
      continue;
    }
    const double dl = box_distance2(pos, m_nodes[node.left].lo, m_nodes[node.left].hi);
    const double dr = box_distance2(pos, m_nodes[node.right].lo, m_nodes[node.right].hi);
    const bool left_first = dl <= dr;
    const int near = left_first ? node.left : node.right;
    const int far = left_first ? node.right : node.left;
    if ((left_first ? dr : dl) < best2)
      stack[top++] = far;
    if ((left_first ? dl : dr) < best2)
      stack[top++] = near;
  }
  const Vec3 pseudo = pseudo_normal(best_triangle, best_feature);
  const Vec3 rel = pos - closest;
  const double d = std::sqrt(best2);
  // Bærentzen & Aanæs 2005, theorem 1: pos lies outside where pos - closest
  // points to the side of the closest feature's pseudo-normal
  const double sign = rel.dot(pseudo) >= 0.0 ? 1.0 : -1.0;
  if (best_feature == Feature::Face || !(d > 0.0)) {
    normal = pseudo.normalized();
  } else {
    normal = sign * rel / d;
  }
  dist = m_direction * sign * d;
  normal *= m_direction;
}

} // namespace pyoif::shapes
