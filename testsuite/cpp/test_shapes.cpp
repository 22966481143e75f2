// Shapes: signed distance and outward normal against hand-computed points
// (inside, outside, on faces, edges, corners, rims and the pore's rounding),
// for both directions; then, on random points, the properties every exact
// signed distance has: |normal| = 1, the point pos - dist * normal lies on the
// surface, and the distance is 1-Lipschitz.
#include "shapes/cylinder.hpp"
#include "shapes/rhomboid.hpp"
#include "shapes/simple_pore.hpp"
#include "shapes/sphere.hpp"
#include "shapes/union.hpp"
#include "shapes/wall.hpp"
#include "utils/errors.hpp"
#include "utils/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

using namespace pyoif;
using namespace pyoif::shapes;

namespace {

constexpr double tol = 1e-12;

struct DistNormal {
  double dist;
  Vec3 normal;
};

DistNormal eval(const Shape& s, const Vec3& pos) {
  DistNormal r{0.0, Vec3::Zero()};
  s.calc_dist(pos, r.dist, r.normal);
  return r;
}

/** Distance and normal at pos equal the expected ones (normal given up to
 *  length, normalised here). */
void expect_point(const Shape& s, const Vec3& pos, double dist, const Vec3& normal) {
  SCOPED_TRACE(s.name() + " at (" + std::to_string(pos[0]) + ", " + std::to_string(pos[1]) + ", " +
               std::to_string(pos[2]) + ")");
  const auto r = eval(s, pos);
  EXPECT_NEAR(r.dist, dist, tol);
  const Vec3 n = normal.normalized();
  EXPECT_NEAR((r.normal - n).norm(), 0.0, tol)
      << "normal " << r.normal.transpose() << " expected " << n.transpose();
  EXPECT_NEAR(r.normal.norm(), 1.0, tol);
}

/** As expect_point, for direction = +1 and for the hollow twin (-1), whose
 *  distance and normal are the negatives. */
void expect_both(const Shape& s, const Shape& hollow, const Vec3& pos, double dist,
                 const Vec3& normal) {
  expect_point(s, pos, dist, normal);
  expect_point(hollow, pos, -dist, -normal);
}

} // namespace

TEST(Wall, DistanceAndNormal) {
  const Wall w(Vec3(0, 0, 2), 1.5); // plane z = 1.5, free side z > 1.5
  expect_point(w, Vec3(3, -4, 4.0), 2.5, Vec3(0, 0, 1));
  expect_point(w, Vec3(3, -4, 1.0), -0.5, Vec3(0, 0, 1));
}

TEST(Sphere, DistanceAndNormal) {
  const Vec3 c(1, 2, 3);
  const Sphere s(c, 2.0), hollow(c, 2.0, -1);
  expect_both(s, hollow, Vec3(1, 2, 6), 1.0, Vec3(0, 0, 1));
  expect_both(s, hollow, Vec3(1, 2, 3.5), -1.5, Vec3(0, 0, 1));
  expect_both(s, hollow, c + Vec3(3, 4, 0), 3.0, Vec3(3, 4, 0));
  expect_both(s, hollow, c + Vec3(0, -2, 0), 0.0, Vec3(0, -1, 0));
  const auto centre = eval(s, c); // every direction is closest; any unit normal
  EXPECT_NEAR(centre.dist, -2.0, tol);
  EXPECT_NEAR(centre.normal.norm(), 1.0, tol);
  EXPECT_TRUE(s.is_inside(c));
  EXPECT_FALSE(hollow.is_inside(c));
}

TEST(Cylinder, ClosedDistanceAndNormal) {
  // Axis along z (given with length 2), radius 1, length 4: |z| <= 2.
  const Cylinder s(Vec3::Zero(), Vec3(0, 0, 2), 1.0, 4.0);
  const Cylinder hollow(Vec3::Zero(), Vec3(0, 0, 2), 1.0, 4.0, -1);
  expect_both(s, hollow, Vec3(3, 0, 0), 2.0, Vec3(1, 0, 0));          // beside the mantle
  expect_both(s, hollow, Vec3(0, -3, 1.5), 2.0, Vec3(0, -1, 0));      // beside the mantle
  expect_both(s, hollow, Vec3(0, 0, 5), 3.0, Vec3(0, 0, 1));          // above the cap
  expect_both(s, hollow, Vec3(0.5, 0, -3), 1.0, Vec3(0, 0, -1));      // below the cap
  expect_both(s, hollow, Vec3(4, 0, 6), 5.0, Vec3(3, 0, 4));          // off the rim: 3-4-5
  expect_both(s, hollow, Vec3(0, -4, -6), 5.0, Vec3(0, -3, -4));      // off the lower rim
  expect_both(s, hollow, Vec3(0.5, 0, 0), -0.5, Vec3(1, 0, 0));       // inside, mantle nearer
  expect_both(s, hollow, Vec3(0, 0, 1.8), -0.2, Vec3(0, 0, 1));       // inside, cap nearer
  expect_both(s, hollow, Vec3(0.9, 0, -1.95), -0.05, Vec3(0, 0, -1)); // near the rim inside
  expect_both(s, hollow, Vec3(0.95, 0, 1.9), -0.05, Vec3(1, 0, 0));
  expect_both(s, hollow, Vec3(0, 1, 0.3), 0.0, Vec3(0, 1, 0)); // on the mantle
  const auto rim = eval(s, Vec3(1, 0, 2));                     // on the rim: any unit normal
  EXPECT_NEAR(rim.dist, 0.0, tol);
  EXPECT_NEAR(rim.normal.norm(), 1.0, tol);
}

TEST(Cylinder, TiltedAxis) {
  // Axis (1, 1, 0), centre (1, 2, 3): mantle and cap distances in the rotated frame.
  const Vec3 c(1, 2, 3), e = Vec3(1, 1, 0).normalized(), p = Vec3(0, 0, 1);
  const Cylinder s(c, Vec3(1, 1, 0), 0.5, 2.0);
  expect_point(s, c + 0.3 * e + 2.0 * p, 1.5, p);
  expect_point(s, c - 4.0 * e + 0.2 * p, 3.0, -e);
  const auto on_axis = eval(s, c + 0.1 * e); // on the axis: any unit normal normal to it
  EXPECT_NEAR(on_axis.dist, -0.5, tol);
  EXPECT_NEAR(on_axis.normal.norm(), 1.0, tol);
  EXPECT_NEAR(on_axis.normal.dot(e), 0.0, tol);
}

TEST(Cylinder, OpenHasNoCaps) {
  const Cylinder s(Vec3::Zero(), Vec3(0, 0, 1), 1.0, 4.0, 1, true);
  const Cylinder tube(Vec3::Zero(), Vec3(0, 0, 1), 1.0, 4.0, -1, true);
  // Inside: always measured to the mantle, even next to the open end.
  expect_both(s, tube, Vec3(0.5, 0, 1.9), -0.5, Vec3(1, 0, 0));
  expect_both(s, tube, Vec3(0, 0.8, -1.99), -0.2, Vec3(0, 1, 0));
  // Beyond an open end: to the rim circle.
  expect_both(s, tube, Vec3(0.5, 0, 5), std::sqrt(0.25 + 9.0), Vec3(-0.5, 0, 3));
  expect_both(s, tube, Vec3(4, 0, -6), 5.0, Vec3(3, 0, -4));
  // Beside the mantle.
  expect_both(s, tube, Vec3(0, 2.5, 1.0), 1.5, Vec3(0, 1, 0));
}

TEST(Rhomboid, CuboidFacesEdgesCorners) {
  // [1, 3] x [1, 4] x [1, 5]
  const Vec3 o(1, 1, 1), a(2, 0, 0), b(0, 3, 0), c(0, 0, 4);
  const Rhomboid s(o, a, b, c), hollow(o, a, b, c, -1);
  expect_both(s, hollow, Vec3(5, 2, 2), 2.0, Vec3(1, 0, 0));                    // face
  expect_both(s, hollow, Vec3(2, 2, -0.5), 1.5, Vec3(0, 0, -1));                // face
  expect_both(s, hollow, Vec3(5, 6, 2), std::sqrt(8.0), Vec3(1, 1, 0));         // edge
  expect_both(s, hollow, Vec3(2, 0, 7), std::sqrt(5.0), Vec3(0, -1, 2));        // edge
  expect_both(s, hollow, Vec3(0, 0, 0), std::sqrt(3.0), Vec3(-1, -1, -1));      // corner
  expect_both(s, hollow, Vec3(4, 6, 7), std::sqrt(1.0 + 4 + 4), Vec3(1, 2, 2)); // corner
  expect_both(s, hollow, Vec3(1.5, 2, 3), -0.5, Vec3(-1, 0, 0));                // inside
  expect_both(s, hollow, Vec3(2, 3.8, 3), -0.2, Vec3(0, 1, 0));                 // inside
  expect_both(s, hollow, Vec3(2, 2, 4.9), -0.1, Vec3(0, 0, 1));                 // inside
  expect_both(s, hollow, Vec3(3, 2, 3), 0.0, Vec3(1, 0, 0));                    // on a face
}

TEST(Rhomboid, ObliqueIsExact) {
  // Sheared: in the xy plane the parallelogram (0,0), (1,0), (2,1), (1,1); z in [0, 1].
  const Vec3 o = Vec3::Zero(), a(1, 0, 0), b(1, 1, 0), c(0, 0, 1);
  const Rhomboid s(o, a, b, c), hollow(o, a, b, c, -1);
  // Closest to the slanted face x = y (foot (0.35, 0.35) inside it); clamping
  // the skew coordinates would give the corner (1, 1) at distance 1.513.
  expect_both(s, hollow, Vec3(-0.5, 1.2, 0.5), 0.85 * std::sqrt(2.0), Vec3(-1, 1, 0));
  // Beyond the acute vertical edge at (2, 1): closest to the edge.
  expect_both(s, hollow, Vec3(3, 1, 0.5), 1.0, Vec3(1, 0, 0));
  // Beyond the obtuse edge at (0, 0), in the wedge between the outward normals.
  expect_both(s, hollow, Vec3(-0.3, -0.1, 0.5), std::sqrt(0.1), Vec3(-0.3, -0.1, 0));
  // Inside: nearest is the slanted face x - y = 0 at (0.4 / sqrt 2).
  expect_both(s, hollow, Vec3(0.9, 0.5, 0.5), -0.4 / std::sqrt(2.0), Vec3(-1, 1, 0));
}

TEST(SimplePore, DistanceAndNormal) {
  // Slab |z| <= 2, channel radius 1, rounding radius 0.5: torus circle centre
  // (r, |z|) = (1.5, 1.5).
  const SimplePore s(Vec3::Zero(), Vec3(0, 0, 3), 4.0, 1.0, 0.5);
  expect_point(s, Vec3(0.5, 0, 0), 0.5, Vec3(-1, 0, 0));    // in the channel
  expect_point(s, Vec3(0, -0.25, 1), 0.75, Vec3(0, 1, 0));  // in the channel
  expect_point(s, Vec3(1.5, 0, 0.5), -0.5, Vec3(-1, 0, 0)); // material, channel wall nearer
  expect_point(s, Vec3(3, 0, 1.5), -0.5, Vec3(0, 0, 1));    // material, face nearer
  expect_point(s, Vec3(0, 3, -1.8), -0.2, Vec3(0, 0, -1));  // material, lower face
  expect_point(s, Vec3(3, 0, -3), 1.0, Vec3(0, 0, -1));     // beyond the slab
  expect_point(s, Vec3(0, 2.5, 2.25), 0.25, Vec3(0, 0, 1)); // beyond, just past the rounding
  // The rounding: points along the ray (-0.6, 0.8) from the circle centre.
  expect_point(s, Vec3(0.9, 0, 2.3), 0.5, Vec3(-0.6, 0, 0.8));
  expect_point(s, Vec3(1.2, 0, 1.9), 0.0, Vec3(-0.6, 0, 0.8));
  expect_point(s, Vec3(1.35, 0, 1.7), -0.25, Vec3(-0.6, 0, 0.8));
  expect_point(s, Vec3(0, 0.9, -2.3), 0.5, Vec3(0, -0.6, -0.8));
  // Above the channel: to the rounded mouth.
  expect_point(s, Vec3(0.3, 0, 2.7), std::sqrt(2 * 1.44) - 0.5, Vec3(-1, 0, 1));
  // On the axis: radius away from the channel wall, any normal normal to the axis.
  const auto axis = eval(s, Vec3(0, 0, 0.3));
  EXPECT_NEAR(axis.dist, 1.0, tol);
  EXPECT_NEAR(axis.normal.norm(), 1.0, tol);
  EXPECT_NEAR(axis.normal.z(), 0.0, tol);
}

TEST(SimplePore, SharpEdgesWithoutSmoothing) {
  const SimplePore s(Vec3(0, 0, 1), Vec3(0, 0, -1), 2.0, 1.0, 0.0);         // slab 0 <= z <= 2
  expect_point(s, Vec3(0.5, 0, 3), std::hypot(0.5, 1.0), Vec3(-0.5, 0, 1)); // to the edge
  expect_point(s, Vec3(3, 0, 2.5), 0.5, Vec3(0, 0, 1));
  expect_point(s, Vec3(1.1, 0, 1.0), -0.1, Vec3(-1, 0, 0));
}

TEST(Union, SmallestDistanceAndItsNormal) {
  auto sphere = std::make_shared<Sphere>(Vec3(0, 0, 5), 1.0);
  auto wall = std::make_shared<Wall>(Vec3(0, 0, 1), 0.0);
  Union u;
  double d;
  Vec3 n;
  u.calc_dist(Vec3::Zero(), d, n);
  EXPECT_TRUE(std::isinf(d) && d > 0); // empty: occupies nothing
  u.add(sphere);
  u.add(wall);
  EXPECT_EQ(u.size(), 2u);
  expect_point(u, Vec3(0, 0, 1.5), 1.5, Vec3(0, 0, 1));  // wall nearer
  expect_point(u, Vec3(0, 0, 3.5), 0.5, Vec3(0, 0, -1)); // sphere nearer
  expect_point(u, Vec3(3, 0, 5), 2.0, Vec3(1, 0, 0));
  expect_point(u, Vec3(0, 0, -1), -1.0, Vec3(0, 0, 1)); // inside the wall
  EXPECT_TRUE(u.is_inside(Vec3(0, 0, 5.5)));
  u.remove(sphere);
  expect_point(u, Vec3(0, 0, 3.5), 3.5, Vec3(0, 0, 1));
  EXPECT_THROW(u.remove(sphere), InputError);
  auto self = std::make_shared<Union>();
  auto outer = std::make_shared<Union>();
  outer->add(self);
  EXPECT_THROW(self->add(outer), InputError); // would recurse forever
  EXPECT_THROW(self->add(self), InputError);
  u.clear();
  EXPECT_EQ(u.size(), 0u);
}

TEST(Shapes, BadParametersThrow) {
  EXPECT_THROW(Sphere(Vec3::Zero(), 0.0), InputError);
  EXPECT_THROW(Sphere(Vec3::Zero(), 1.0, 0), InputError);
  EXPECT_THROW(Cylinder(Vec3::Zero(), Vec3::Zero(), 1.0, 1.0), InputError);
  EXPECT_THROW(Cylinder(Vec3::Zero(), Vec3::UnitZ(), -1.0, 1.0), InputError);
  EXPECT_THROW(Cylinder(Vec3::Zero(), Vec3::UnitZ(), 1.0, 0.0), InputError);
  EXPECT_THROW(Cylinder(Vec3::Zero(), Vec3::UnitZ(), 1.0, 1.0, 2), InputError);
  EXPECT_THROW(Rhomboid(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)), InputError);
  EXPECT_THROW(Rhomboid(Vec3::Zero(), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3::Zero()), InputError);
  EXPECT_THROW(SimplePore(Vec3::Zero(), Vec3::UnitZ(), 2.0, 1.0, 1.5), InputError);
  EXPECT_THROW(SimplePore(Vec3::Zero(), Vec3::UnitZ(), 2.0, 0.0, 0.5), InputError);
  EXPECT_THROW(SimplePore(Vec3::Zero(), Vec3::UnitZ(), 2.0, 1.0, -0.1), InputError);
}

// ---- properties on random points --------------------------------------------

namespace {

Vec3 random_point(std::uint64_t i, double half_width) {
  const random::Key key{12345, 99, i, 0};
  return Vec3(half_width * (2.0 * random::uniform(key, 0) - 1.0),
              half_width * (2.0 * random::uniform(key, 1) - 1.0),
              half_width * (2.0 * random::uniform(key, 2) - 1.0));
}

struct Case {
  const char* label;
  std::shared_ptr<Shape> shape;
  bool closest_on_surface; ///< pos - dist * normal has distance 0 (not for unions)
  bool lipschitz;          ///< dist is 1-Lipschitz (not for open cylinders)
};

std::vector<Case> random_cases() {
  const Vec3 tilted = Vec3(1, -2, 0.5);
  std::vector<Case> cases;
  for (int dir : {1, -1}) {
    cases.push_back(
        {"sphere", std::make_shared<Sphere>(Vec3(0.3, -0.2, 0.1), 1.7, dir), true, true});
    cases.push_back({"cylinder",
                     std::make_shared<Cylinder>(Vec3(0.2, 0.1, -0.3), tilted, 1.1, 2.4, dir), true,
                     true});
    cases.push_back({"open cylinder",
                     std::make_shared<Cylinder>(Vec3(0.2, 0.1, -0.3), tilted, 1.1, 2.4, dir, true),
                     true, false});
    cases.push_back({"rhomboid",
                     std::make_shared<Rhomboid>(Vec3(-1, -0.5, -1), Vec3(2, 0.3, 0),
                                                Vec3(0.8, 1.5, 0.2), Vec3(-0.4, 0.3, 1.8), dir),
                     true, true});
  }
  cases.push_back(
      {"pore", std::make_shared<SimplePore>(Vec3(0.1, 0, 0.2), tilted, 2.0, 0.8, 0.6), true, true});
  cases.push_back({"sharp pore",
                   std::make_shared<SimplePore>(Vec3::Zero(), Vec3(0, 1, 1), 1.5, 1.0, 0.0), true,
                   true});
  auto u = std::make_shared<Union>();
  u->add(std::make_shared<Sphere>(Vec3(1, 1, 1), 1.0));
  u->add(std::make_shared<Rhomboid>(Vec3(-2, -2, -2), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 1)));
  cases.push_back({"union", u, false, true});
  return cases;
}

} // namespace

TEST(Shapes, RandomPointsNormalIsUnitAndClosestPointOnSurface) {
  for (const auto& cs : random_cases()) {
    SCOPED_TRACE(cs.label);
    int inside = 0;
    for (std::uint64_t i = 0; i < 4000; ++i) {
      const Vec3 pos = random_point(i, 3.0);
      const auto r = eval(*cs.shape, pos);
      ASSERT_TRUE(std::isfinite(r.dist));
      ASSERT_NEAR(r.normal.norm(), 1.0, tol) << "at " << pos.transpose();
      inside += r.dist < 0.0;
      if (!cs.closest_on_surface)
        continue;
      const Vec3 closest = pos - r.dist * r.normal;
      const auto on = eval(*cs.shape, closest);
      ASSERT_LT(std::abs(on.dist), 1e-10) << "pos " << pos.transpose() << " dist " << r.dist;
    }
    std::printf("%-16s %d of 4000 random points inside\n", cs.label, inside);
    // Both signs must be sampled, or the checks above prove little.
    EXPECT_GT(inside, 40);
    EXPECT_LT(inside, 3960);
  }
}

TEST(Shapes, RandomPointsDistanceIsOneLipschitz) {
  for (const auto& cs : random_cases()) {
    if (!cs.lipschitz)
      continue;
    SCOPED_TRACE(cs.label);
    double worst = 0.0;
    for (std::uint64_t i = 0; i < 4000; ++i) {
      const Vec3 x = random_point(i, 3.0);
      // Partners both near (resolves kinks) and far.
      const double scale = (i % 2) ? 0.05 : 2.0;
      const Vec3 y = x + scale * random_point(i + 100000, 1.0);
      const double dx = eval(*cs.shape, x).dist, dy = eval(*cs.shape, y).dist;
      const double ratio = std::abs(dx - dy) / (x - y).norm();
      worst = std::max(worst, ratio);
    }
    std::printf("%-16s largest |d(x) - d(y)| / |x - y| = %.12f\n", cs.label, worst);
    EXPECT_LE(worst, 1.0 + 1e-9);
    // Exact distances attain slope 1 (along a normal); a squashed one would not.
    EXPECT_GT(worst, 0.99);
  }
}

TEST(Shapes, DistanceGrowsAlongTheNormal) {
  // Moving by a small step along the normal away from a smooth surface changes
  // the signed distance by the step (the normal is the distance's gradient).
  for (const auto& cs : random_cases()) {
    SCOPED_TRACE(cs.label);
    int checked = 0, agree = 0;
    for (std::uint64_t i = 0; i < 2000; ++i) {
      const Vec3 pos = random_point(i, 3.0);
      const auto r = eval(*cs.shape, pos);
      const double step = 1e-6;
      const auto fwd = eval(*cs.shape, pos + step * r.normal);
      if (std::abs(r.dist) < 1e-3)
        continue;
      ++checked;
      agree += std::abs((fwd.dist - r.dist) / step - 1.0) < 1e-5;
    }
    // A handful may sit on a medial surface (two closest features).
    EXPECT_GT(agree, 0.97 * checked) << agree << " of " << checked;
  }
}

TEST(Shapes, BoundingBoxesContainTheSolid) {
  // Outside its bounding box a shape's distance is at least the box's: the
  // constraints and unions skip far points on that promise. Checked on the
  // random cases (oblique rhomboid, tilted cylinder, sphere, union of them)
  // plus an axis-aligned cuboid, which takes the clamped-box fast path.
  auto cases = random_cases();
  cases.push_back({"cuboid",
                   std::make_shared<Rhomboid>(Vec3(-1, -0.5, 0.2), Vec3(0, 1.5, 0), Vec3(2, 0, 0),
                                              Vec3(0, 0, 1.1)),
                   true, true});
  int bounded = 0;
  for (const auto& cs : cases) {
    SCOPED_TRACE(cs.label);
    Vec3 lo, hi;
    if (!cs.shape->bounding_box(lo, hi))
      continue;
    ++bounded;
    int outside_box = 0;
    for (std::uint64_t i = 0; i < 4000; ++i) {
      const Vec3 pos = random_point(i, 3.0);
      const double box = box_distance(pos, lo, hi);
      const double dist = eval(*cs.shape, pos).dist;
      if (box > 0.0) {
        ++outside_box;
        ASSERT_GE(dist, box - 1e-12) << "at " << pos.transpose();
      }
      EXPECT_EQ(cs.shape->farther_than(pos, 0.5), box >= 0.5);
    }
    EXPECT_GT(outside_box, 400); // the box is tight enough for both cases to occur
    EXPECT_LT(outside_box, 3990);
  }
  // sphere, cylinder, rhomboid (direction +1), union, cuboid; complements,
  // open cylinders and pores are unbounded
  EXPECT_EQ(bounded, 5);
}

TEST(Union, SkippingFarMembersChangesNothing) {
  // the union skips members whose box is farther than the best distance so
  // far; the result must be the plain minimum over the members, bit for bit
  auto u = std::make_shared<Union>();
  std::vector<std::shared_ptr<Shape>> members;
  for (int k = 0; k < 6; ++k) {
    const Vec3 o(-2.5 + k, 0.3 * k - 1.0, -0.5 * (k % 3));
    members.push_back(k % 2 ? std::shared_ptr<Shape>(std::make_shared<Rhomboid>(
                                  o, Vec3(0.8, 0, 0), Vec3(0, 1.2, 0), Vec3(0, 0, 0.9)))
                            : std::shared_ptr<Shape>(std::make_shared<Sphere>(o, 0.6)));
    u->add(members.back());
  }
  u->add(std::make_shared<Wall>(Vec3(0, 0, 1), -2.5)); // unbounded: never skipped
  members.push_back(u->shapes().back());
  for (std::uint64_t i = 0; i < 4000; ++i) {
    const Vec3 pos = random_point(i, 3.0);
    double best = std::numeric_limits<double>::infinity();
    Vec3 best_normal = Vec3::UnitX();
    for (const auto& m : members) {
      const auto r = eval(*m, pos);
      if (r.dist < best) {
        best = r.dist;
        best_normal = r.normal;
      }
    }
    const auto r = eval(*u, pos);
    ASSERT_EQ(r.dist, best) << "at " << pos.transpose();
    ASSERT_EQ(r.normal, best_normal);
  }
}

TEST(Shapes, BatchDistancesExactWithinRange) {
  // signed_distances (the constraints' loop) must give the exact distance
  // below the range and a value >= range beyond it, for every shape (walls
  // take their own tight loop, bounded shapes skip far points by their box)
  auto cases = random_cases();
  cases.push_back({"wall", std::make_shared<Wall>(Vec3(0.3, -1, 0.4), 0.7), true, true});
  constexpr std::size_t n = 4000;
  std::vector<Vec3> points(n);
  for (std::uint64_t i = 0; i < n; ++i)
    points[i] = random_point(i, 3.0);
  int total_within = 0, total_beyond = 0;
  for (const auto& cs : cases) {
    SCOPED_TRACE(cs.label);
    for (const double range : {0.25, 1.0}) {
      std::vector<double> dist(n);
      cs.shape->signed_distances(points.data(), n, range, dist.data());
      int within = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const double exact = eval(*cs.shape, points[i]).dist;
        if (exact < range) {
          ++within;
          ASSERT_EQ(dist[i], exact) << "at " << points[i].transpose();
        } else {
          ASSERT_GE(dist[i], range) << "at " << points[i].transpose();
        }
      }
      total_within += within;
      total_beyond += static_cast<int>(n) - within;
    }
  }
  // both branches occur often (complements have nearly all points within)
  EXPECT_GT(total_within, 20000);
  EXPECT_GT(total_beyond, 20000);
}
