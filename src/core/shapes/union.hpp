// Union of shapes: a point is in the union when it is in any member; the
// signed distance is the smallest of the members' distances and the normal is
// that member's. ESPResSo 4.2: shapes.Union() with add/remove/clear/size.
// An empty union occupies no space: distance +infinity, normal e_x.
#pragma once

#include "shapes/shape.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <limits>
#include <memory>
#include <vector>

namespace pyoif::shapes {

class Union : public Shape {
public:
  void calc_dist(const Vec3& pos, double& dist, Vec3& normal) const override {
    dist = std::numeric_limits<double>::infinity();
    normal = Vec3::UnitX();
    for (const auto& member : m_shapes) {
      double d;
      Vec3 n;
      member->calc_dist(pos, d, n);
      if (d < dist) {
        dist = d;
        normal = n;
      }
    }
  }
  std::string name() const override { return "Union"; }

  void add(std::shared_ptr<Shape> shape) {
    if (!shape)
      throw InputError("Union.add: parameter 'shape' must be a shape, got None");
    if (contains_union(*shape, this))
      throw InputError("Union.add: a union cannot contain itself");
    m_shapes.push_back(std::move(shape));
  }
  void remove(const std::shared_ptr<Shape>& shape) {
    const auto it = std::find(m_shapes.begin(), m_shapes.end(), shape);
    if (it == m_shapes.end())
      throw InputError("Union.remove: the shape is not a member of this union");
    m_shapes.erase(it);
  }
  void clear() { m_shapes.clear(); }
  std::size_t size() const { return m_shapes.size(); }
  const std::vector<std::shared_ptr<Shape>>& shapes() const { return m_shapes; }

private:
  /** True when `shape` is `target` or a union holding it (directly or deeper):
   *  adding it would make calc_dist recurse forever. */
  static bool contains_union(const Shape& shape, const Union* target) {
    if (&shape == target)
      return true;
    if (const auto* u = dynamic_cast<const Union*>(&shape))
      for (const auto& member : u->m_shapes)
        if (contains_union(*member, target))
          return true;
    return false;
  }

  std::vector<std::shared_ptr<Shape>> m_shapes;
};

} // namespace pyoif::shapes
