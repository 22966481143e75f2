#include "packing/rigid_packer.hpp"

#include "packing/mesh_check.hpp"

#include "utils/errors.hpp"
#include "utils/random.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace pyoif::packing {

int RigidPacker::add_type(const std::vector<Vec3>& nodes,
                          const std::vector<std::array<int, 3>>& triangles, double spacing) {
  BodyType t;
  t.nodes = nodes;
  t.triangles = triangles;
  Vec3 lo = nodes.at(0), hi = nodes.at(0);
  for (const Vec3& x : nodes) {
    t.reach = std::max(t.reach, x.norm());
    t.gyration2 += x.squaredNorm();
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  t.gyration2 /= static_cast<double>(nodes.size());
  t.thinnest = (hi - lo).minCoeff();
  require(t.thinnest > 0.0, "pack_cells: a cell type's mesh is flat");
  // the band covers the whole interior, so that a node deep inside another
  // cell still feels which way is out
  t.level_set =
      std::make_unique<LevelSet>(nodes, triangles, spacing, 0.5 * t.thinnest + 2 * spacing);
  // patches: the nodes binned on a grid of 1/6 of the cell's largest extent (measured: 10 % faster
  // than 1/8, 1/4 and 1/12 slower)
  const double bin = std::max((hi - lo).maxCoeff() / 6.0, 1e-12);
  std::map<std::array<int, 3>, std::vector<int>> bins;
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    std::array<int, 3> key;
    for (int d = 0; d < 3; ++d)
      key[d] = static_cast<int>(std::floor((nodes[k][d] - lo[d]) / bin));
    bins[key].push_back(static_cast<int>(k));
  }
  t.patch_start.push_back(0);
  for (const auto& [key, members] : bins) {
    Vec3 centre = Vec3::Zero();
    for (int k : members)
      centre += nodes[k];
    centre /= static_cast<double>(members.size());
    double radius = 0.0;
    for (int k : members)
      radius = std::max(radius, (nodes[k] - centre).norm());
    t.patch_nodes.insert(t.patch_nodes.end(), members.begin(), members.end());
    t.patch_start.push_back(static_cast<int>(t.patch_nodes.size()));
    t.patch_centre.push_back(centre);
    t.patch_radius.push_back(radius);
  }
  m_types.push_back(std::move(t));
  return static_cast<int>(m_types.size()) - 1;
}

void RigidPacker::set_bodies(const std::vector<int>& types, const std::vector<Vec3>& centres,
                             const std::vector<Eigen::Quaterniond>& orientations) {
  require(types.size() == centres.size() && types.size() == orientations.size(),
          "pack_cells: types, centres and orientations differ in length");
  for (int t : types)
    require(t >= 0 && t < static_cast<int>(m_types.size()), "pack_cells: unknown cell type index");
  m_type = types;
  m_centre = centres;
  m_orientation = orientations;
  for (auto& q : m_orientation)
    q.normalize();
  m_first_node.assign(types.size() + 1, 0);
  for (std::size_t b = 0; b < types.size(); ++b)
    m_first_node[b + 1] = m_first_node[b] + m_types[types[b]].nodes.size();
  m_nodes.resize(m_first_node.back());
}

Vec3 RigidPacker::min_image(Vec3 d, const PackerSettings& s) const {
  for (int k = 0; k < 3; ++k)
    if (s.periodic[k])
      d[k] -= s.box[k] * std::round(d[k] / s.box[k]);
  return d;
}

void RigidPacker::world_nodes(double scale) {
  m_rotation.resize(m_type.size());
  for (std::size_t b = 0; b < m_type.size(); ++b) {
    const Eigen::Matrix3d r = m_orientation[b].toRotationMatrix();
    m_rotation[b] = r;
    const Eigen::Matrix3d sr = scale * r;
    const auto& nodes = m_types[m_type[b]].nodes;
    Vec3* out = m_nodes.data() + m_first_node[b];
    for (std::size_t k = 0; k < nodes.size(); ++k)
      out[k] = m_centre[b] + sr * nodes[k];
  }
}

void RigidPacker::find_pairs(double scale, double clearance, const PackerSettings& s) {
  // linked cells of the bodies' centres, at least as wide as two reaches
  // plus the clearance
  double reach = 0.0;
  for (const auto& t : m_types)
    reach = std::max(reach, t.reach);
  const double width = 2.0 * scale * reach + clearance;
  std::array<int, 3> n;
  for (int k = 0; k < 3; ++k)
    n[k] = std::max(1, static_cast<int>(s.box[k] / width));
  auto cell_of = [&](const Vec3& c) {
    std::array<int, 3> idx;
    for (int k = 0; k < 3; ++k) {
      double x = c[k] / s.box[k];
      if (s.periodic[k])
        x -= std::floor(x);
      idx[k] = std::clamp(static_cast<int>(x * n[k]), 0, n[k] - 1);
    }
    return idx;
  };
  const std::size_t n_cells = static_cast<std::size_t>(n[0]) * n[1] * n[2];
  std::vector<std::vector<int>> members(n_cells);
  std::vector<std::array<int, 3>> where(m_type.size());
  for (std::size_t b = 0; b < m_type.size(); ++b) {
    where[b] = cell_of(m_centre[b]);
    members[(static_cast<std::size_t>(where[b][2]) * n[1] + where[b][1]) * n[0] + where[b][0]]
        .push_back(static_cast<int>(b));
  }
  m_pairs.clear();
  std::set<std::size_t> neighbours;
  for (std::size_t i = 0; i < m_type.size(); ++i) {
    // the distinct neighbouring cells (fewer than 27 where an axis has
    // fewer than 3 cells)
    neighbours.clear();
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          std::array<int, 3> c{where[i][0] + dx, where[i][1] + dy, where[i][2] + dz};
          bool outside = false;
          for (int k = 0; k < 3; ++k) {
            if (c[k] < 0 || c[k] >= n[k]) {
              if (!s.periodic[k]) {
                outside = true;
                break;
              }
              c[k] = (c[k] + n[k]) % n[k];
            }
          }
          if (!outside)
            neighbours.insert((static_cast<std::size_t>(c[2]) * n[1] + c[1]) * n[0] + c[0]);
        }
    const double ri = scale * m_types[m_type[i]].reach;
    for (std::size_t cell : neighbours)
      for (int j : members[cell]) {
        if (j <= static_cast<int>(i))
          continue;
        const Vec3 d = min_image(m_centre[i] - m_centre[j], s);
        const double range = ri + scale * m_types[m_type[j]].reach + clearance;
        if (d.squaredNorm() < range * range)
          m_pairs.push_back({static_cast<int>(i), j, d});
      }
  }
}

void RigidPacker::push_apart(int a, int b, const Vec3& shift_ab, double scale, double clearance) {
  // a's nodes relative to b's centre (b's image nearest to a), in b's frame
  const BodyType& tb = m_types[m_type[b]];
  const Eigen::Matrix3d to_b = m_rotation[b].transpose() / scale;
  const BodyType& ta = m_types[m_type[a]];
  const Vec3* nodes = m_nodes.data() + m_first_node[a];
  const Vec3 lo = tb.level_set->lower(), hi = tb.level_set->upper();
  // the level set is 1-Lipschitz up to its interpolation error (a spacing)
  const double margin = clearance + scale * tb.level_set->spacing();
  const Eigen::Matrix3d to_b_from_a = to_b * scale * m_rotation[a];
  const Vec3 shift_in_b = to_b * shift_ab;
  for (std::size_t patch = 0; patch + 1 < ta.patch_start.size(); ++patch) {
    const Vec3 centre = to_b_from_a * ta.patch_centre[patch] + shift_in_b;
    if (scale * (tb.level_set->sample(centre, nullptr) - ta.patch_radius[patch]) > margin)
      continue;
    for (int p = ta.patch_start[patch]; p < ta.patch_start[patch + 1]; ++p) {
      const std::size_t k = static_cast<std::size_t>(ta.patch_nodes[p]);
      const Vec3 arm_a = nodes[k] - m_centre[a];
      const Vec3 rel = arm_a + shift_ab; // from b's centre
      const Vec3 body = to_b * rel;
      if ((body.array() < lo.array()).any() || (body.array() > hi.array()).any())
        continue;
      Vec3 grad;
      const double phi = scale * tb.level_set->sample(body, &grad);
      if (phi >= clearance)
        continue;
      const double norm = grad.norm();
      if (norm == 0.0)
        continue;
      const double overlap = clearance - phi;
      const Vec3 f = (overlap / norm) * (m_rotation[b] * grad);
      m_force[a] += f;
      m_torque[a] += arm_a.cross(f);
      m_force[b] -= f;
      m_torque[b] -= rel.cross(f);
      ++m_contacts[a];
      ++m_contacts[b];
      m_body_overlap[a] += overlap;
      m_body_overlap[b] += overlap;
      m_body_worst[a] = std::max(m_body_worst[a], overlap);
      m_body_worst[b] = std::max(m_body_worst[b], overlap);
      m_overlap_sum += overlap;
      ++m_overlap_count;
      m_worst = std::max(m_worst, overlap);
    }
  }
}

void RigidPacker::push_from_walls(int b, double scale, const PackerSettings& s) {
  const BodyType& t = m_types[m_type[b]];
  const Vec3* nodes = m_nodes.data() + m_first_node[b];
  const std::size_t count = t.nodes.size();
  const double reach = scale * t.reach;
  auto push = [&](const Vec3& node, double overlap, const Vec3& direction) {
    const Vec3 f = overlap * direction;
    m_force[b] += f;
    m_torque[b] += (node - m_centre[b]).cross(f);
    ++m_contacts[b];
    m_overlap_sum += overlap;
    ++m_overlap_count;
    m_worst_wall = std::max(m_worst_wall, overlap);
  };
  const double wc = s.wall_clearance;
  // the shapes see the nodes folded into the box along the periodic axes,
  // as the engine's walls do: a cell hanging across a periodic face meets
  // the walls at the box's other end (a device's channel walls that end
  // at the box face)
  bool wraps = false;
  for (int k = 0; k < 3; ++k)
    wraps |= s.periodic[k] &&
             (m_centre[b][k] - reach - wc < 0.0 || m_centre[b][k] + reach + wc > s.box[k]);
  const Vec3* at = nodes;
  if (wraps) {
    m_folded.assign(nodes, nodes + count);
    for (Vec3& x : m_folded)
      x = fold_into_box(x, s);
    at = m_folded.data();
  }
  for (const auto& shape : m_boundaries) {
    double d_centre;
    Vec3 normal;
    shape->calc_dist(m_centre[b], d_centre, normal);
    if (!wraps && d_centre > reach + wc)
      continue;
    m_dist.resize(count);
    shape->signed_distances(at, count, wc, m_dist.data());
    for (std::size_t k = 0; k < count; ++k) {
      if (m_dist[k] >= wc)
        continue;
      double d;
      shape->calc_dist(at[k], d, normal);
      push(nodes[k], wc - d, normal);
    }
  }
  // the box faces of non-periodic axes and the region's faces
  for (int axis = 0; axis < 3; ++axis) {
    double lo = -HUGE_VAL, hi = HUGE_VAL, margin = 0.0;
    if (!s.periodic[axis]) {
      lo = 0.0;
      hi = s.box[axis];
      margin = wc;
    }
    if (s.has_region && (s.region_lo[axis] > 0.0 || s.region_hi[axis] < s.box[axis])) {
      lo = std::max(lo, s.region_lo[axis]);
      hi = std::min(hi, s.region_hi[axis]);
    }
    if (!std::isfinite(lo) && !std::isfinite(hi))
      continue;
    if (m_centre[b][axis] - reach > lo + margin && m_centre[b][axis] + reach < hi - margin)
      continue;
    Vec3 e = Vec3::Zero();
    e[axis] = 1.0;
    for (std::size_t k = 0; k < count; ++k) {
      const double x = nodes[k][axis];
      if (x < lo + margin)
        push(nodes[k], lo + margin - x, e);
      else if (x > hi - margin)
        push(nodes[k], x - (hi - margin), -e);
    }
  }
}

PackerResult RigidPacker::run(const PackerSettings& s) {
  require(!m_type.empty(), "pack_cells: no cells to pack");
  require(s.start_scale > 0.0 && s.start_scale <= 1.0, "pack_cells: start scale must be in (0, 1]");
  require(s.final_scale >= s.start_scale && s.final_scale <= 1.0,
          "pack_cells: final scale must be in [start scale, 1]");
  double reach = 0.0;
  for (const auto& t : m_types)
    reach = std::max(reach, t.reach);
  for (int k = 0; k < 3; ++k)
    require(!s.periodic[k] || s.box[k] > 2.0 * (2.0 * reach + s.clearance),
            "pack_cells: the box is shorter than two cells (" + format_number(2.0 * reach) +
                " wide) plus their clearance along periodic axis " + std::to_string(k) +
                "; a cell would touch its own periodic image");
  PackerResult result;
  double scale = s.start_scale;
  const std::size_t n = m_type.size();
  m_force.assign(n, Vec3::Zero());
  m_torque.assign(n, Vec3::Zero());
  m_contacts.assign(n, 0);
  m_velocity.assign(n, Vec3::Zero());
  m_body_overlap.assign(n, 0.0);
  m_body_worst.assign(n, 0.0);
  m_spin.assign(n, Vec3::Zero());
  // the last iteration that made progress (see stall_iterations)
  int progress_it = 0;
  double progress_scale = scale, progress_worst = HUGE_VAL;
  for (int it = 0; it < s.max_iterations; ++it) {
    world_nodes(scale);
    if (it % 4 == 0)
      find_pairs(scale, s.clearance + 0.5 * scale * reach, s); // kept for 4 iterations
    std::fill(m_force.begin(), m_force.end(), Vec3::Zero());
    std::fill(m_torque.begin(), m_torque.end(), Vec3::Zero());
    std::fill(m_contacts.begin(), m_contacts.end(), 0);
    std::fill(m_body_overlap.begin(), m_body_overlap.end(), 0.0);
    std::fill(m_body_worst.begin(), m_body_worst.end(), 0.0);
    m_worst = m_worst_wall = 0.0;
    m_overlap_sum = 0.0;
    m_overlap_count = 0;
    for (auto& p : m_pairs) {
      // the shift may change as the bodies move: recompute it
      p.shift = min_image(m_centre[p.i] - m_centre[p.j], s);
      push_apart(p.i, p.j, p.shift, scale, s.clearance);
      push_apart(p.j, p.i, -p.shift, scale, s.clearance);
    }
    for (std::size_t b = 0; b < n; ++b)
      push_from_walls(static_cast<int>(b), scale, s);
    const double worst = std::max(m_worst, m_worst_wall);
    result.iterations = it + 1;
    result.scale = scale;
    result.worst_overlap = m_worst;
    result.worst_wall_overlap = m_worst_wall;
    if (scale >= s.final_scale && worst <= s.final_tolerance * s.clearance) {
      result.converged = true;
      break;
    }
    if (scale > 1.001 * progress_scale || worst < (1.0 - s.stall_overlap_drop) * progress_worst) {
      progress_it = it;
      progress_scale = scale;
      progress_worst = worst;
    } else if (s.stall_iterations > 0 && it - progress_it >= s.stall_iterations) {
      result.jammed = true;
      break;
    }
    // overdamped step with momentum (heavy ball, restarted where it
    // opposes the push, as in FIRE: Bitzek et al., Phys. Rev. Lett. 97,
    // 170201 (2006)): each body moves by `step` x the mean overlap of its
    // contacts plus `momentum` x its last move (and turns by the matching
    // angle), at most a tenth of its thinnest width
    for (std::size_t b = 0; b < n; ++b) {
      if (m_contacts[b] == 0) {
        m_velocity[b].setZero();
        m_spin[b].setZero();
        continue;
      }
      const BodyType& t = m_types[m_type[b]];
      const double max_step = 0.1 * scale * t.thinnest;
      Vec3 push = s.step * m_force[b] / m_contacts[b];
      const double mean_overlap = m_body_overlap[b] / m_contacts[b];
      if (m_body_worst[b] > s.clearance && push.norm() < 0.25 * mean_overlap) {
        // deep inside another cell with pushes that cancel (two cells about
        // one centre): a random kick breaks the symmetry
        const random::Key key{s.seed, static_cast<std::uint64_t>(random::Stream::packing),
                              static_cast<std::uint64_t>(it), b};
        const Vec3 kick(random::normal(key, 0), random::normal(key, 1), random::normal(key, 2));
        push += 0.5 * mean_overlap * kick.normalized();
      }
      const Vec3 twist = s.step * m_torque[b] / (m_contacts[b] * scale * scale * t.gyration2);
      m_velocity[b] =
          m_velocity[b].dot(push) > 0.0 ? Vec3(s.momentum * m_velocity[b] + push) : push;
      m_spin[b] = m_spin[b].dot(twist) > 0.0 ? Vec3(s.momentum * m_spin[b] + twist) : twist;
      if (m_velocity[b].norm() > max_step)
        m_velocity[b] *= max_step / m_velocity[b].norm();
      const double max_turn = max_step / (scale * t.reach);
      if (m_spin[b].norm() > max_turn)
        m_spin[b] *= max_turn / m_spin[b].norm();
      const Vec3& move = m_velocity[b];
      const Vec3& turn = m_spin[b];
      m_centre[b] += move;
      for (int k = 0; k < 3; ++k)
        if (s.periodic[k])
          m_centre[b][k] -= s.box[k] * std::floor(m_centre[b][k] / s.box[k]);
      const double angle = turn.norm();
      if (angle > 0.0)
        m_orientation[b] =
            (Eigen::Quaterniond(Eigen::AngleAxisd(angle, turn / angle)) * m_orientation[b])
                .normalized();
    }
    // grow the faster the smaller the worst overlap
    const double mean = m_overlap_count ? m_overlap_sum / m_overlap_count : 0.0;
    const double room = 1.0 - mean / (s.grow_tolerance * s.clearance);
    if (scale < s.final_scale && room > 0.0)
      scale = std::min(s.final_scale, scale * (1.0 + s.growth * room));
  }
  return result;
}

PackingCheck RigidPacker::check(const PackerSettings& s) const {
  // exact: the meshes at their positions, scale 1. Only nodes within
  // `search` of another cell's level set are looked at (patches farther
  // than that skipped whole); the node distances reported are exact below
  // `search`, and `search` where none is closer.
  PackingCheck out;
  const double search = s.clearance + 1.0;
  out.min_node_distance = search;
  std::vector<Vec3> nodes(m_first_node.back());
  std::vector<Eigen::Matrix3d> rot(m_type.size());
  for (std::size_t b = 0; b < m_type.size(); ++b) {
    rot[b] = m_orientation[b].toRotationMatrix();
    const auto& ref = m_types[m_type[b]].nodes;
    for (std::size_t k = 0; k < ref.size(); ++k)
      nodes[m_first_node[b] + k] = m_centre[b] + rot[b] * ref[k];
  }
  std::vector<Vec3> other;
  for (std::size_t i = 0; i < m_type.size(); ++i) {
    const BodyType& ti = m_types[m_type[i]];
    for (std::size_t j = 0; j < m_type.size(); ++j) {
      if (i == j)
        continue;
      const Vec3 shift = min_image(m_centre[i] - m_centre[j], s); // c_i - image of c_j
      const BodyType& tj = m_types[m_type[j]];
      if (shift.norm() > ti.reach + tj.reach + search)
        continue;
      ++out.pairs_tested;
      const Vec3 cj = m_centre[i] - shift; // the image of j's centre nearest to i
      other.resize(tj.nodes.size());
      for (std::size_t k = 0; k < other.size(); ++k)
        other[k] = cj + rot[j] * tj.nodes[k];
      const Eigen::Matrix3d to_j = rot[j].transpose();
      for (std::size_t patch = 0; patch + 1 < ti.patch_start.size(); ++patch) {
        const Vec3 centre = to_j * (m_centre[i] + rot[i] * ti.patch_centre[patch] - cj);
        if (tj.level_set->sample(centre, nullptr) - ti.patch_radius[patch] >
            search + tj.level_set->spacing())
          continue;
        for (int q = ti.patch_start[patch]; q < ti.patch_start[patch + 1]; ++q) {
          const Vec3& x = nodes[m_first_node[i] + q];
          const double phi = tj.level_set->sample(to_j * (x - cj), nullptr);
          if (phi > search)
            continue;
          for (std::size_t r = 0; r + 1 < tj.patch_start.size(); ++r) {
            const Vec3 pc = cj + rot[j] * tj.patch_centre[r];
            if ((x - pc).norm() - tj.patch_radius[r] >= out.min_node_distance)
              continue;
            for (int u = tj.patch_start[r]; u < tj.patch_start[r + 1]; ++u)
              out.min_node_distance = std::min(out.min_node_distance, (x - other[u]).norm());
          }
          if (phi < 3.0 * tj.level_set->spacing() && winding_number(x, other, tj.triangles) > 0.5)
            ++out.nodes_inside_cells;
        }
      }
    }
  }
  out.min_wall_distance = min_wall_distance(std::move(nodes), m_boundaries, s);
  return out;
}

} // namespace pyoif::packing
