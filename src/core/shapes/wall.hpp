// Wall: the half-space behind the plane n.x = dist (the shape), n its unit
// normal pointing into the allowed region. ESPResSo: shapes.Wall(normal=, dist=).
#pragma once

#include "shapes/shape.hpp"

namespace pyoif::shapes {

class Wall : public Shape {
public:
  Wall(const Vec3& normal, double dist) : m_normal(normal.normalized()), m_dist(dist) {}
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override {
    dist = pos.dot(m_normal) - m_dist;
    normal = m_normal;
  }
  void signed_distances(const Vec3* pos, std::size_t n, double /*range*/,
                        double* dist) const override {
    for (std::size_t i = 0; i < n; ++i)
      dist[i] = pos[i].dot(m_normal) - m_dist;
  }
  std::string name() const override { return "Wall"; }
  const Vec3& normal() const { return m_normal; }
  double dist() const { return m_dist; }

private:
  Vec3 m_normal;
  double m_dist;
};

} // namespace pyoif::shapes
