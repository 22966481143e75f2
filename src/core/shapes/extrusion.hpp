// Extrusion(polygons, z0, z1, direction): a 2D layout (closed polygons in the
// xy plane) extruded between the planes z = z0 and z = z1. The solid is
// S x [z0, z1] where S is the interior of the polygons by the even-odd rule:
// a polygon inside another is a hole, one inside a hole an island
// (direction = +1); direction = -1 gives its complement (a channel drawn as
// polygons, closed by floor and ceiling, with the fluid inside).
//
// Polygons must not cross, overlap or touch along an edge (checked: the
// constructor names the polygon and its vertices); they may share single
// vertices (pixel masks: diagonal pixels).
//
// The signed distance is exact: with e the signed 2D distance to the nearest
// edge (negative inside S) and s = max(z0 - z, z - z1), outside
// sqrt(max(e,0)^2 + max(s,0)^2), inside max(e, s). The nearest edge comes
// from a bounding-volume hierarchy over the edges (O(log n) per query); the
// side of a point follows from the nearest edge (its solid side, found once
// per edge by a ray crossing count) or, when the nearest point is a vertex,
// from the sector of the vertex's edges the point lies in.
#pragma once

#include "shapes/shape.hpp"

#include <Eigen/Dense>
#include <array>
#include <string>
#include <vector>

namespace pyoif::shapes {

class Extrusion : public Shape {
public:
  using Polygon = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
  /** names[k] (optional) names polygon k in error messages ("LWPOLYLINE 2A"). */
  Extrusion(const std::vector<Polygon>& polygons, double z0, double z1, int direction = 1,
            const std::vector<std::string>& names = {});
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override;
  std::string name() const override { return "Extrusion"; }
  bool bounding_box(Vec3& lo, Vec3& hi) const override {
    lo = m_lo;
    hi = m_hi;
    return m_direction == 1;
  }

  double z0() const { return m_z0; }
  double z1() const { return m_z1; }
  int direction() const { return m_direction; }
  std::size_t num_edges() const { return m_edges.size(); }

  /** Signed 2D distance of (x, y) from the layout's outline (negative inside
   *  S) and the 2D outward normal. */
  void distance_2d(double x, double y, double& dist, Eigen::Vector2d& normal) const;

private:
  using V2 = Eigen::Vector2d;
  struct Edge {
    V2 a, b;             ///< from a to b
    double inv_len2;     ///< 1 / |b - a|^2
    bool solid_left;     ///< S lies to the left of a -> b
    int node_a, node_b;  ///< vertex nodes of a and b
    int polygon, ia, ib; ///< for messages: polygon index, vertex indices as given
  };
  struct Node {
    V2 lo, hi;
    int first, count; ///< leaf: m_order[first, first + count); inner: count = 0
    int right;        ///< inner: right child (the left child is the next node)
  };
  /** The edges that meet at one point (two, or four at a pinch). */
  struct Vertex {
    std::vector<int> edges;
  };

  int build(int first, int count);
  void check_intersections(const std::vector<std::string>& names) const;
  int crossings(const V2& m, int axis, int skip) const;
  bool vertex_inside(int vertex, const V2& p) const;
  std::string where(int edge, const std::vector<std::string>& names) const;

  std::vector<Edge> m_edges;
  std::vector<int> m_order;
  std::vector<Node> m_nodes;
  std::vector<Vertex> m_vertices;
  double m_z0, m_z1;
  int m_direction;
  Vec3 m_lo, m_hi;
};

} // namespace pyoif::shapes
