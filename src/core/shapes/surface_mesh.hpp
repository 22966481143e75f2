// SurfaceMesh(vertices, triangles, direction): the volume enclosed by a
// closed, manifold, consistently oriented triangulated surface (direction =
// +1) or its complement (direction = -1). The signed distance is the exact
// distance to the nearest triangle, found through an axis-aligned bounding-box
// tree over the triangles (closest-point query pruned by box distance); its
// sign comes from the angle-weighted pseudo-normal of the nearest feature
// (face, edge or vertex): J. A. Bærentzen and H. Aanæs, "Signed distance
// computation using the angle weighted pseudonormal", IEEE Trans. Vis. Comput.
// Graph. 11 (2005) 243-253. That sign is exact for any closed manifold
// surface, convex or not, at any distance.
//
// The constructor refuses (InputError) an empty mesh, indices out of range,
// non-finite coordinates, degenerate (zero-area) triangles, open surfaces (an
// edge of one triangle), non-manifold edges (three or more triangles) and
// vertices (triangles in separate fans: bodies touching at a point), and
// inconsistent orientation (two neighbours that run through their shared edge
// the same way), naming the first bad triangle or edge with its vertex ids
// and coordinates. A mesh whose triangles all face inward (negative enclosed
// volume) is turned outward; inverted() tells so.
#pragma once

#include "shapes/shape.hpp"

#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <vector>

namespace pyoif::shapes {

class SurfaceMesh : public Shape {
public:
  using Triangle = std::array<int, 3>;
  SurfaceMesh(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
              int direction = 1);
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override;
  std::string name() const override { return "SurfaceMesh"; }
  bool bounding_box(Vec3& lo, Vec3& hi) const override {
    lo = m_lo;
    hi = m_hi;
    return m_direction == 1;
  }

  int direction() const { return m_direction; }
  /** True when the input faced inward and the triangles were turned around. */
  bool inverted() const { return m_inverted; }
  /** The triangles as used: outward (counter-clockwise seen from outside). */
  const std::vector<Triangle>& triangles() const { return m_triangles; }
  const std::vector<Vec3>& vertices() const { return m_vertices; }
  /** Enclosed volume (> 0). */
  double volume() const { return m_volume; }
  std::size_t n_tree_nodes() const { return m_nodes.size(); }

private:
  /** Where on a triangle its closest point to a query lies. */
  enum class Feature : std::uint8_t { Face, EdgeAB, EdgeBC, EdgeCA, VertexA, VertexB, VertexC };
  struct Node {
    Vec3 lo, hi;
    int left = -1; ///< child indices (internal node); -1 for a leaf
    int right = -1;
    int first = 0; ///< leaf: its triangles are m_order[first, first + count)
    int count = 0;
  };
  int build(int first, int count, std::vector<Vec3>& centroids, int depth);
  static Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                                  Feature& feature);
  /** The angle-weighted pseudo-normal of a triangle's feature (not normalised). */
  Vec3 pseudo_normal(int triangle, Feature feature) const;

  std::vector<Vec3> m_vertices;
  std::vector<Triangle> m_triangles;
  std::vector<Vec3> m_face_normals;                ///< unit outward normal per triangle
  std::vector<Vec3> m_vertex_normals;              ///< angle-weighted sums of face normals
  std::vector<std::array<Vec3, 3>> m_edge_normals; ///< per triangle: edges ab, bc, ca
  std::vector<int> m_order;                        ///< triangle ids in tree-leaf order
  std::vector<std::array<Vec3, 3>> m_corners;      ///< their corners, in the same order
  std::vector<Node> m_nodes;
  int m_direction;
  bool m_inverted = false;
  double m_volume = 0.0;
  Vec3 m_lo, m_hi;
};

} // namespace pyoif::shapes
