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
    for (std::size_t k = 0; k < m_shapes.size(); ++k) {
      const Member box = member_box(k);
      // outside a member's box its distance is at least the box's: a member
      // that cannot come closer than the best so far is skipped (same result)
      if (box.bounded) {
        const double lower = box_distance(pos, box.lo, box.hi);
        if (lower > 0.0 && lower >= dist)
          continue;
      }
      double d;
      Vec3 n;
      m_shapes[k]->calc_dist(pos, d, n);
      if (d < dist) {
        dist = d;
        normal = n;
      }
    }
  }
  std::string name() const override { return "Union"; }
  bool bounding_box(Vec3& lo, Vec3& hi) const override {
    if (m_shapes.empty())
      return false;
    for (std::size_t k = 0; k < m_boxes.size(); ++k) {
      const Member box = member_box(k);
      if (!box.bounded)
        return false;
      lo = k ? Vec3(lo.cwiseMin(box.lo)) : box.lo;
      hi = k ? Vec3(hi.cwiseMax(box.hi)) : box.hi;
    }
    return true;
  }

  void add(std::shared_ptr<Shape> shape) {
    if (!shape)
      throw InputError("Union.add: parameter 'shape' must be a shape, got None");
    if (contains_union(*shape, this))
      throw InputError("Union.add: a union cannot contain itself");
    Member box;
    box.bounded = shape->bounding_box(box.lo, box.hi);
    box.live = dynamic_cast<const Union*>(shape.get()) != nullptr;
    m_shapes.push_back(std::move(shape));
    m_boxes.push_back(box);
    ++m_version;
  }
  void remove(const std::shared_ptr<Shape>& shape) {
    const auto it = std::find(m_shapes.begin(), m_shapes.end(), shape);
    if (it == m_shapes.end())
      throw InputError("Union.remove: the shape is not a member of this union");
    m_boxes.erase(m_boxes.begin() + (it - m_shapes.begin()));
    m_version += 1 + (*it)->version(); // the sum in version() must not fall
    m_shapes.erase(it);
  }
  void clear() {
    for (const auto& shape : m_shapes)
      m_version += shape->version();
    ++m_version;
    m_shapes.clear();
    m_boxes.clear();
  }
  /** Own changes plus the members' (each only grows). */
  std::uint64_t version() const override {
    std::uint64_t v = m_version;
    for (const auto& shape : m_shapes)
      v += shape->version();
    return v;
  }
  std::size_t size() const { return m_shapes.size(); }
  const std::vector<std::shared_ptr<Shape>>& shapes() const { return m_shapes; }

private:
  std::uint64_t m_version = 0; ///< own changes (add, remove, clear)
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

  /// members' boxes, kept from add: shapes do not change once made, except
  /// unions (add, remove, clear), whose boxes are looked up when used (live)
  struct Member {
    bool bounded = false, live = false;
    Vec3 lo, hi;
  };
  Member member_box(std::size_t k) const {
    if (!m_boxes[k].live)
      return m_boxes[k];
    Member box;
    box.live = true;
    box.bounded = m_shapes[k]->bounding_box(box.lo, box.hi);
    return box;
  }
  std::vector<std::shared_ptr<Shape>> m_shapes;
  std::vector<Member> m_boxes;
};

} // namespace pyoif::shapes
