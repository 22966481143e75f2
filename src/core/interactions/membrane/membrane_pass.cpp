// The membrane component's pass (membrane_model.hpp): one driver for every
// cell, a template over the scalar type. T = double evaluates one cell, T =
// Lanes four cells of one topology at once, one per vector lane, with the
// same operations in the same order, so the two agree bit for bit. With four
// cells in the lanes a node's x of the four cells is one vector: the gathers
// of the triangle and edge passes are plain vector loads and the force
// scatters vector adds (doc/performance.md, tenth round).
#include "interactions/membrane/area.hpp"
#include "interactions/membrane/bending.hpp"
#include "interactions/membrane/membrane_model.hpp"
#include "interactions/membrane/normals.hpp"
#include "interactions/membrane/stretching.hpp"
#include "interactions/membrane/viscosity.hpp"
#include "interactions/membrane/volume.hpp"
#include "utils/errors.hpp"

#include <algorithm>
#include <sstream>
#include <type_traits>

namespace pyoif::membrane {

template <> Model::Workspace<double>& Model::workspace<double>() {
  return m_plain;
}
template <> Model::Workspace<Lanes>& Model::workspace<Lanes>() {
  return m_lanes;
}

namespace {

/** Edges per block of the edge pass. An edge's chain from the node loads
 *  through the square roots and the division to its force factors is about
 *  130 cycles long; as one loop per edge it ran at that latency (the body
 *  did not fit the core's reorder window twice). Two loops per block (the
 *  factors, then the forces) let the iterations overlap. */
constexpr int kEdgeBlock = 16;

/** Limits past which a cell is broken, not merely deformed: a pair of
 *  triangles turned by more than 150 degrees from its relaxed angle
 *  (cos^2 150 = 3/4) is an inverted triangle; a volume below a quarter or
 *  above four times V0 has collapsed or exploded (a red blood cell keeps
 *  its volume within a few per cent). */
constexpr double inverted_cos2 = 0.75;
constexpr double volume_collapsed = 0.25, volume_exploded = 4.0;

/** Stretching, explicit viscosity and bending of every edge of the
 *  topology, added to the node forces f; x, v: the nodes' positions and
 *  velocities; explicit_visc: per lane 1 where the cell's viscosity is
 *  explicit (in this pass), 0 where it is implicit (viscosity.hpp). With
 *  energies (non-null) the edges' stretching and bending energies are summed
 *  into them. Returns the lanes with a zero-length edge or (bending) a
 *  degenerate wing triangle. */
template <class T, bool neo, bool visc, bool bend, class Node>
Mask<T> edge_pass(const Topology& t, const Node* x, const Node* v, T explicit_visc, Node* f,
                  T* stretching_energy_sum, T* bending_energy_sum, bool shape_checks) {
  struct Factors {
    T e[3], n1[3], n2[3], coefficient;
    BendingFactors<T> bending;
  };
  Factors blk[kEdgeBlock];
  Mask<T> bad = no_lane<T>();
  const int n_edges = static_cast<int>(t.edge_b.size());
  const int *const eb = t.edge_b.data(), *const ea = t.edge_a.data(), *const ec = t.edge_c.data(),
                   *const ed = t.edge_d.data();
  for (int first = 0; first < n_edges; first += kEdgeBlock) {
    const int nb = std::min(kEdgeBlock, n_edges - first);
    for (int i = 0; i < nb; ++i) {
      const int k = first + i;
      Factors& out = blk[i];
      const Node& xb = x[eb[k]];
      T e[3], u[3] = {}, w[3] = {}, dv[3] = {};
      for (int d = 0; d < 3; ++d) {
        e[d] = x[ec[k]].c[d] - xb.c[d];
        if constexpr (bend) {
          u[d] = x[ea[k]].c[d] - xb.c[d];
          w[d] = x[ed[k]].c[d] - xb.c[d];
        }
        if constexpr (visc)
          dv[d] = v[ec[k]].c[d] - v[eb[k]].c[d];
        out.e[d] = e[d];
      }
      const StretchingParams& stretch = t.stretching[k];
      const T l2 = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
      bad |= not_positive(l2);
      const T l = sqrt_of(l2);
      const T lambda = l * stretch.inv_l0;
      // the four quotients of the edge: 1 / l^2, 1 / kappa's denominator,
      // the deviation's tangent, 1 / (|n1|^2 |n2|^2)
      T den[4] = {l2, splat<T>(1.0), splat<T>(1.0), splat<T>(1.0)};
      if constexpr (neo)
        den[1] = neo_hookean_denominator(lambda);
      auto edge_coefficient = [&](const FourReciprocals<T>& r) {
        T c = stretching_coefficient<neo>(stretch, l, lambda, r.inv[0], r.inv[1],
                                          stretching_energy_sum);
        if constexpr (visc)
          c += explicit_visc * viscosity_coefficient(t.viscosity[k], e, dv, r.inv[0]);
        return c;
      };
      if constexpr (bend) {
        const BendingParams& bending = t.bending[k];
        const Wings<T> wings(e, u, w);
        bad |= not_positive(wings.n1_2) | not_positive(wings.n2_2);
        const Deviation<T> dev(bending, wings.y(l, w), wings.x());
        // an inverted triangle: the pair turned by more than 150 degrees
        // from its relaxed angle (cos^2 150 = 3/4; (sine, cosine) have the
        // length |n1| |n2|), a fold no smooth membrane makes
        if (shape_checks)
          bad |= (dev.cosine < T{}) &
                 (dev.cosine * dev.cosine > inverted_cos2 * (wings.n1_2 * wings.n2_2));
        const Mask<T> small = dev.small();
        den[2] = select<T>(small, dev.cosine, splat<T>(1.0));
        den[3] = wings.n1_2 * wings.n2_2;
        const FourReciprocals<T> r(den);
        const T dphi = bending_deviation(dev, small, dev.sine * r.inv[2]);
        out.bending = BendingFactors<T>(bending, dphi, l, r.inv[3], wings, r.inv[0], e, u, w,
                                        bending_energy_sum);
        for (int d = 0; d < 3; ++d) {
          out.n1[d] = wings.n1[d];
          out.n2[d] = wings.n2[d];
        }
        out.coefficient = edge_coefficient(r);
      } else {
        out.coefficient = edge_coefficient(FourReciprocals<T>(den));
      }
    }
    for (int i = 0; i < nb; ++i) {
      const int k = first + i;
      const Factors& in = blk[i];
      Node &fb = f[eb[k]], &fc = f[ec[k]];
      for (int d = 0; d < 3; ++d) {
        const T fe = in.coefficient * in.e[d]; // stretching and viscosity: fe on B, -fe on C
        if constexpr (bend) {
          T fa_, fb_, fc_, fd_;
          in.bending.forces(fe, in.n1[d], in.n2[d], fa_, fb_, fc_, fd_);
          fb.c[d] += fb_;
          fc.c[d] += fc_;
          f[ea[k]].c[d] += fa_;
          f[ed[k]].c[d] += fd_;
        } else {
          fb.c[d] += fe;
          fc.c[d] += -fe;
        }
      }
    }
  }
  return bad;
}

/** edge_pass for the terms the topology has (one instantiation each). */
template <class T, class Node>
Mask<T> edge_pass_for(const Topology& t, const Node* x, const Node* v, T explicit_visc, bool visc,
                      Node* f, T* stretching_sum, T* bending_sum, bool shape_checks) {
  auto with = [&](auto neo, auto visc_, auto bend) {
    return edge_pass<T, decltype(neo)::value, decltype(visc_)::value, decltype(bend)::value>(
        t, x, v, explicit_visc, f, stretching_sum, bending_sum, shape_checks);
  };
  using yes = std::true_type;
  using no = std::false_type;
  auto by_bend = [&](auto neo, auto visc_) {
    return t.bend ? with(neo, visc_, yes{}) : with(neo, visc_, no{});
  };
  if (t.neo)
    return visc ? by_bend(yes{}, yes{}) : by_bend(yes{}, no{});
  return visc ? by_bend(no{}, yes{}) : by_bend(no{}, no{});
}

} // namespace

template <class T, bool with_reports>
void Model::evaluate_group(const Group& group, const ParticleStore& p, const BoxGeometry& box,
                           double time, Vec3* force, Vec3* normal,
                           std::vector<CellReport>* reports) {
  using Node = typename Workspace<T>::Node;
  constexpr int kLanes = lanes_of<T>;
  const Topology& t = m_topologies[m_cells[group.cell[0]].topology];
  Workspace<T>& ws = workspace<T>();
  const int n = t.n_nodes, n_tri = static_cast<int>(t.tri_v0.size());
  if (static_cast<int>(ws.x.size()) < n)
    for (auto* a : {&ws.x, &ws.v, &ws.f, &ws.nsum, &ws.vsum})
      a->resize(n);
  if (static_cast<int>(ws.g.size()) < n_tri) {
    ws.g.resize(n_tri);
    ws.coef.resize(n_tri);
  }
  Node *const x = ws.x.data(), *const v = ws.v.data(), *const f = ws.f.data();
  Node *const nsum = ws.nsum.data(), *const vsum = t.separate_sums ? ws.vsum.data() : nsum;

  // gather, cell by cell (lane by lane), and the cells' parameters
  GlobalAreaParams<T> global{};
  VolumeParams<T> vol{};
  for (int j = 0; j < kLanes; ++j) {
    const Cell& cell = m_cells[group.cell[j]];
    set_lane(global.kag, j, cell.global_area.kag);
    set_lane(global.area0, j, cell.global_area.area0);
    set_lane(vol.kv, j, cell.volume.kv);
    set_lane(vol.volume0, j, cell.volume.volume0);
    gather(cell, j, p, box, x, t.visc ? v : nullptr);
  }
  const bool volume_forces = t.closed && any_lane<T>(vol.kv != T{});
  const bool node_sums = t.normals || volume_forces;
  for (int k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d) {
      f[k].c[d] = T{};
      nsum[k].c[d] = T{};
      if (t.separate_sums)
        vsum[k].c[d] = T{};
    }

  // triangle pass: per triangle N, its area and volume term and the
  // centroid allocation's scale (area.hpp), the local area coefficient, the
  // global area's direction factor (the cell's factor applies once the
  // cell's area is known), the cell's area and volume, and per node the
  // sums of N of its closed and of its normals' triangles. A closed
  // triangle of no area is an error where the cell has global terms.
  T area_sum{}, volume_sum{}, local_area_energy_sum{};
  T* const local_area_energy = with_reports ? &local_area_energy_sum : nullptr;
  const Mask<T> closed_terms = (global.kag != T{}) | (vol.kv != T{});
  Mask<T> bad = no_lane<T>();
  if (n_tri > 0) {
    const Node origin = x[t.origin];
    for (int q = 0; q < n_tri; ++q) {
      const Node &a = x[t.tri_v0[q]], &b = x[t.tri_v1[q]], &c = x[t.tri_v2[q]];
      T e1[3], e2[3], ra[3];
      for (int d = 0; d < 3; ++d) {
        e1[d] = b.c[d] - a.c[d];
        e2[d] = c.c[d] - a.c[d];
        ra[d] = a.c[d] - origin.c[d];
      }
      const TriangleGeometry<T> tri(e1, e2, ra);
      const LocalAreaParams& local = t.local_area[q];
      const double closed = t.closed_weight[q];
      if (local.kal_weight != 0.0)
        bad |= not_positive(tri.area);
      if (closed != 0.0)
        bad |= not_positive(tri.area) & closed_terms;
      area_sum += closed * tri.area;
      volume_sum += closed * tri.volume_term;
      ws.g[q] = closed * tri.area * tri.inv_moment;
      ws.coef[q] = local_area_coefficient(local, tri.area, tri.inv_moment, local_area_energy);
      if (node_sums) {
        const double w = t.separate_sums ? t.normal_weight[q] : closed;
        for (int d = 0; d < 3; ++d) {
          const T nd = w * tri.n[d];
          nsum[t.tri_v0[q]].c[d] += nd;
          nsum[t.tri_v1[q]].c[d] += nd;
          nsum[t.tri_v2[q]].c[d] += nd;
          if (t.separate_sums) {
            const T vd = closed * tri.n[d];
            vsum[t.tri_v0[q]].c[d] += vd;
            vsum[t.tri_v1[q]].c[d] += vd;
            vsum[t.tri_v2[q]].c[d] += vd;
          }
        }
      }
    }
  }
  // the cells' global area and volume factors
  const T cell_volume = volume_sum / 6.0;
  const T sign = orientation_sign(cell_volume);
  T global_area_energy{}, volume_energy{};
  // a volume that collapsed or exploded (where the volume term gives V0);
  // a volume or surface that drifted beyond the tolerance: noted once per
  // cell (the System warns after the run)
  if (shape_checks && volume_forces) {
    const T ratio = abs_of(cell_volume) / select<T>(vol.kv != T{}, vol.volume0, splat<T>(1.0));
    bad |= (vol.kv != T{}) & ((ratio < volume_collapsed) | (ratio > volume_exploded));
  }
  if (shape_checks && drift_tolerance > 0.0 && t.closed)
    for (int j = 0; j < group.n_cells; ++j) {
      const Cell& cell = m_cells[group.cell[j]];
      auto note = [&](const char* quantity, double value, double relaxed, std::uint8_t bit) {
        const double ratio = std::abs(value) / relaxed;
        std::uint8_t& warned = m_drift_warned[cell.mol_id];
        if (!(warned & bit) && std::abs(ratio - 1.0) > drift_tolerance) {
          warned |= bit;
          drift_notes.push_back({cell.mol_id, quantity, ratio, time, step});
        }
      };
      if (cell.volume.kv != 0.0)
        note("volume", lane(cell_volume, j), cell.volume.volume0, 1);
      if (cell.global_area.kag != 0.0)
        note("surface", lane(area_sum, j), cell.global_area.area0, 2);
    }
  const T area_factor =
      global_area_factor(global, area_sum, with_reports ? &global_area_energy : nullptr);
  const T vol_factor =
      volume_factor(vol, cell_volume, sign, with_reports ? &volume_energy : nullptr);
  // area forces (local and global) along the centroid offsets
  if (t.has_local_area || any_lane<T>(area_factor != T{}))
    for (int q = 0; q < n_tri; ++q) {
      const T cq = ws.coef[q] + area_factor * ws.g[q];
      const Node &a = x[t.tri_v0[q]], &b = x[t.tri_v1[q]], &c = x[t.tri_v2[q]];
      for (int d = 0; d < 3; ++d) {
        const CentroidOffsets<T> m(b.c[d] - a.c[d], c.c[d] - a.c[d]);
        f[t.tri_v0[q]].c[d] += cq * m.a;
        f[t.tri_v1[q]].c[d] += cq * m.b;
        f[t.tri_v2[q]].c[d] += cq * m.c;
      }
    }
  // the viscosity of each cell: explicit in the edge pass while the
  // dashpots are safely stable so (viscosity.hpp), else implicit below
  T explicit_visc = splat<T>(1.0);
  bool implicit_visc[kLanes] = {};
  bool any_explicit = false;
  if (t.visc)
    for (int j = 0; j < kLanes; ++j) {
      implicit_visc[j] = needs_implicit_viscosity(m_cells[group.cell[j]], p);
      set_lane(explicit_visc, j, implicit_visc[j] ? 0.0 : 1.0);
      any_explicit |= !implicit_visc[j];
    }
  // edge pass: stretching, explicit viscosity, bending
  T stretching_energy_sum{}, bending_energy_sum{};
  if (t.edges)
    bad |= edge_pass_for<T>(t, x, v, explicit_visc, t.visc && any_explicit, f,
                            with_reports ? &stretching_energy_sum : nullptr,
                            with_reports ? &bending_energy_sum : nullptr, shape_checks);
  // per node: the volume force along its sum of N
  if (volume_forces)
    for (int k = 0; k < n; ++k)
      for (int d = 0; d < 3; ++d)
        f[k].c[d] += vol_factor * vsum[k].c[d];
  // viscosity: implicit against the elastic forces above, cell by cell
  // (viscosity.hpp), in double whatever T (a cell's result does not depend
  // on the lanes it shares)
  if (t.visc)
    for (int j = 0; j < group.n_cells; ++j) {
      if (implicit_visc[j] && defer_implicit_viscosity && !viscous_force) {
        m_deferred.push_back(group.cell[j]); // after the step's other forces
        continue;
      }
      if (implicit_visc[j] || viscous_force)
        add_viscous_forces(m_cells[group.cell[j]], j, p, x, v, f, implicit_visc[j]);
    }
  for (int k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d)
      bad |= not_finite(f[k].c[d]);
  for (int j = 0; j < group.n_cells; ++j)
    if (lane_set<T>(bad, j))
      report_failure<T>(group, j, p, time, lane(cell_volume, j));

  // forces and normals to the particles
  for (int j = 0; j < group.n_cells; ++j) {
    const Cell& cell = m_cells[group.cell[j]];
    const int* const index = m_node_index.data() + cell.node_begin;
    if (force)
      for (int k = 0; k < n; ++k)
        force[index[k]] += Vec3(lane(f[k].c[0], j), lane(f[k].c[1], j), lane(f[k].c[2], j));
    if constexpr (with_reports) {
      CellReport& r = (*reports)[group.cell[j]];
      r.area = lane(area_sum, j);
      r.volume = lane(cell_volume, j);
      r.energy[stretching] = lane(stretching_energy_sum, j);
      r.energy[bending] = lane(bending_energy_sum, j);
      r.energy[local_area] = lane(local_area_energy_sum, j);
      r.energy[global_area] = lane(global_area_energy, j);
      r.energy[volume] = lane(volume_energy, j);
    }
  }
  if (normal && t.normals)
    for (int k = 0; k < n; ++k) {
      if (!t.has_normal[k])
        continue;
      const Node& s = nsum[k];
      if (m_shared_nodes) { // summed over the cells of the node, normalised at the end
        for (int j = 0; j < group.n_cells; ++j)
          normal[m_node_index[m_cells[group.cell[j]].node_begin + k]] +=
              lane(sign, j) * Vec3(lane(s.c[0], j), lane(s.c[1], j), lane(s.c[2], j));
      } else {
        const OutwardNormal<T> nk(s.c[0], s.c[1], s.c[2], sign);
        for (int j = 0; j < group.n_cells; ++j)
          normal[m_node_index[m_cells[group.cell[j]].node_begin + k]] =
              Vec3(lane(nk.x, j), lane(nk.y, j), lane(nk.z, j));
      }
    }
}

bool Model::needs_implicit_viscosity(const Cell& cell, const ParticleStore& p) const {
  if (!(time_step > 0.0))
    return false;
  const Topology& t = m_topologies[cell.topology];
  const int* const index = m_node_index.data() + cell.node_begin;
  double lightest = p.mass[index[0]];
  for (int k = 1; k < t.n_nodes; ++k)
    lightest = std::min(lightest, p.mass[index[k]]);
  return time_step * t.kvisc_node_max / lightest > explicit_viscosity_limit;
}

template <class Node>
void Model::add_viscous_forces(const Cell& cell, int j, const ParticleStore& p, const Node* x,
                               const Node* v, Node* f, bool implicit) {
  const Topology& t = m_topologies[cell.topology];
  const int n = t.n_nodes;
  const int* const index = m_node_index.data() + cell.node_begin;
  ViscousScratch& s = m_viscous_scratch;
  for (auto* a : {&s.x, &s.v, &s.f})
    a->assign(3 * n, 0.0);
  s.mass.resize(n);
  s.load.resize(3 * n);
  for (int k = 0; k < n; ++k) {
    const int i = index[k];
    for (int d = 0; d < 3; ++d) {
      s.x[3 * k + d] = lane(x[k].c[d], j);
      s.v[3 * k + d] = lane(v[k].c[d], j);
      // the forces the dashpots work against in this step: the membrane's
      // elastic ones (so far in f) and the external ones
      s.load[3 * k + d] = lane(f[k].c[d], j) + p.ext_force[i][d];
    }
    s.mass[k] = p.mass[i];
  }
  // explicit (the edge pass added it to f already): only reported
  m_viscous.add_forces(n, static_cast<int>(t.edge_b.size()), t.edge_b.data(), t.edge_c.data(),
                       t.viscosity.data(), s.x.data(), s.v.data(), s.mass.data(), s.load.data(),
                       implicit ? time_step : 0.0, s.f.data());
  if (viscous_force)
    for (int k = 0; k < n; ++k)
      viscous_force[index[k]] += Vec3(s.f[3 * k], s.f[3 * k + 1], s.f[3 * k + 2]);
  if (!implicit)
    return;
  count_viscous_solve();
  for (int k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d)
      set_lane(f[k].c[d], j, lane(f[k].c[d], j) + s.f[3 * k + d]);
}

void Model::add_deferred_viscosity(const ParticleStore& p, const BoxGeometry& box, Vec3* force) {
  // each deferred cell alone, in double, in the order the pass met them
  // (the same on every rank count: a cell is one rank's, its forces the
  // serial sums); positions unfolded as the pass gathers them
  using Node = Workspace<double>::Node;
  std::vector<Node>& x = m_plain.x;
  ViscousScratch& s = m_viscous_scratch;
  for (const int c : m_deferred) {
    const Cell& cell = m_cells[c];
    const Topology& t = m_topologies[cell.topology];
    const int n = t.n_nodes;
    const int* const index = m_node_index.data() + cell.node_begin;
    if (x.size() < static_cast<std::size_t>(n))
      x.resize(n);
    gather<Node>(cell, 0, p, box, x.data(), nullptr);
    s.x.resize(3 * n);
    s.v.resize(3 * n);
    s.load.resize(3 * n);
    s.mass.resize(n);
    s.f.assign(3 * n, 0.0);
    for (int k = 0; k < n; ++k) {
      const int i = index[k];
      for (int d = 0; d < 3; ++d) {
        s.x[3 * k + d] = x[k].c[d];
        s.v[3 * k + d] = p.vel[i][d];
        s.load[3 * k + d] = force[i][d]; // every force of the step so far
      }
      s.mass[k] = p.mass[i];
    }
    m_viscous.add_forces(n, static_cast<int>(t.edge_b.size()), t.edge_b.data(), t.edge_c.data(),
                         t.viscosity.data(), s.x.data(), s.v.data(), s.mass.data(), s.load.data(),
                         time_step, s.f.data());
    count_viscous_solve();
    for (int k = 0; k < n; ++k)
      force[index[k]] += Vec3(s.f[3 * k], s.f[3 * k + 1], s.f[3 * k + 2]);
  }
  m_deferred.clear();
}

template <class Node>
void Model::gather(const Cell& cell, int j, const ParticleStore& p, const BoxGeometry& box, Node* x,
                   Node* v) const {
  const int n = m_topologies[cell.topology].n_nodes;
  const int* const index = m_node_index.data() + cell.node_begin;
  const Vec3 pos_r = p.pos[index[0]];
  const Vec3i image_r = p.image[index[0]];
  const Vec3& box_l = box.length();
  // each node unfolded relative to the cell's first node, the image
  // difference first (integers, exact: no rounding that grows with the
  // number of boxes a cell has travelled)
  Vec3 low = Vec3::Zero(), high = Vec3::Zero();
  for (int k = 0; k < n; ++k) {
    const int i = index[k];
    const Vec3 xk = (p.pos[i] - pos_r) + (p.image[i] - image_r).cast<double>().cwiseProduct(box_l);
    low = low.cwiseMin(xk);
    high = high.cwiseMax(xk);
    for (int d = 0; d < 3; ++d)
      set_lane(x[k].c[d], j, xk[d]);
  }
  auto wider_than_half = [&](const Vec3& lo, const Vec3& hi) {
    for (int d = 0; d < 3; ++d)
      if (box.periodic()[d] && hi[d] - lo[d] > 0.5 * box_l[d])
        return true;
    return false;
  };
  if (wider_than_half(low, high)) {
    // unfolded, the cell spans more than half the box: either it is that
    // large, or a node's unfolded position jumped (a script set it to its
    // folded value). Relative by the minimum image, a cell smaller than half
    // the box comes out whole: take that where it does.
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
    for (int k = 0; k < n; ++k) {
      const Vec3 xk = box.minimum_image(p.pos[index[k]], pos_r);
      lo = lo.cwiseMin(xk);
      hi = hi.cwiseMax(xk);
    }
    if (!wider_than_half(lo, hi))
      for (int k = 0; k < n; ++k) {
        const Vec3 xk = box.minimum_image(p.pos[index[k]], pos_r);
        for (int d = 0; d < 3; ++d)
          set_lane(x[k].c[d], j, xk[d]);
      }
  }
  if (v)
    for (int k = 0; k < n; ++k)
      for (int d = 0; d < 3; ++d)
        set_lane(v[k].c[d], j, p.vel[index[k]][d]);
}

template <class T>
void Model::report_failure(const Group& group, int j, const ParticleStore& p, double time,
                           double volume) const {
  using Node = typename Workspace<T>::Node;
  const Cell& cell = m_cells[group.cell[j]];
  const Topology& t = m_topologies[cell.topology];
  const Workspace<T>& ws = const_cast<Model*>(this)->workspace<T>();
  const int* const index = m_node_index.data() + cell.node_begin;
  auto pid = [&](int k) { return p.id[index[k]]; };
  auto at = [&](const Node& node, double(&out)[3]) {
    for (int d = 0; d < 3; ++d)
      out[d] = lane(node.c[d], j);
  };
  auto difference = [&](int from, int to, double(&out)[3]) {
    double a[3], b[3];
    at(ws.x[from], a);
    at(ws.x[to], b);
    for (int d = 0; d < 3; ++d)
      out[d] = b[d] - a[d];
  };
  auto where = [&](int bond_id) {
    return " (bonded interaction " + std::to_string(bond_id) + ", the cell with mol_id " +
           std::to_string(cell.mol_id) + ")";
  };
  std::ostringstream msg;
  // the checks of the pass, on the cell's gathered positions
  for (std::size_t k = 0; k < t.edge_b.size(); ++k) {
    double e[3], u[3], w[3];
    difference(t.edge_b[k], t.edge_c[k], e);
    difference(t.edge_b[k], t.edge_a[k], u);
    difference(t.edge_b[k], t.edge_d[k], w);
    const bool zero_edge = not_positive(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    const Wings<double> wings(e, u, w);
    const bool flat_wing = t.bend && (not_positive(wings.n1_2) || not_positive(wings.n2_2));
    if (zero_edge || flat_wing) {
      msg << "OifLocalForces bond between particles " << pid(t.edge_b[k]) << ' ' << pid(t.edge_a[k])
          << ' ' << pid(t.edge_c[k]) << ' ' << pid(t.edge_d[k]) << where(cell.local_bond_id)
          << " broke at time " << time << ": "
          << (zero_edge ? "its edge has zero length" : "one of its triangles has zero area");
      throw SimulationInstability("triangle_collapsed", msg.str())
          .at_particle(pid(t.edge_b[k]))
          .in_cell(cell.mol_id)
          .at_time(time)
          .with_value(0.0);
    }
    if (t.bend) {
      const double l = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
      const Deviation<double> dev(t.bending[k], wings.y(l, w), wings.x());
      if (dev.cosine < 0.0 && dev.cosine * dev.cosine > inverted_cos2 * wings.n1_2 * wings.n2_2) {
        const double turned = std::abs(std::atan2(dev.sine, dev.cosine)) * 180.0 / M_PI;
        msg << "an inverted triangle in the cell with mol_id " << cell.mol_id
            << ": the triangles of particles " << pid(t.edge_b[k]) << ' ' << pid(t.edge_c[k])
            << " and " << pid(t.edge_a[k]) << ", " << pid(t.edge_d[k]) << " turned by " << turned
            << " degrees from their relaxed angle at time " << time
            << " (the membrane folded through itself: reduce the time step or the forces on "
               "the cell, or raise kb)";
        throw SimulationInstability("triangle_inverted", msg.str())
            .at_particle(pid(t.edge_a[k]))
            .in_cell(cell.mol_id)
            .at_time(time)
            .with_value(turned);
      }
    }
  }
  const bool closed_terms = cell.global_area.kag != 0.0 || cell.volume.kv != 0.0;
  for (std::size_t q = 0; q < t.tri_v0.size(); ++q) {
    double e1[3], e2[3];
    const double zero[3] = {0.0, 0.0, 0.0};
    difference(t.tri_v0[q], t.tri_v1[q], e1);
    difference(t.tri_v0[q], t.tri_v2[q], e2);
    const bool flat = not_positive(TriangleGeometry<double>(e1, e2, zero).area);
    const bool local = t.local_area[q].kal_weight != 0.0;
    if (flat && (local || (closed_terms && t.closed_weight[q] != 0.0))) {
      msg << (local ? "OifLocalForces" : "OifGlobalForces") << " triangle of particles "
          << pid(t.tri_v0[q]) << ' ' << pid(t.tri_v1[q]) << ' ' << pid(t.tri_v2[q])
          << where(local ? cell.local_bond_id : cell.global_bond_id) << " has zero area at time "
          << time << " (a collapsed triangle: reduce the time step or the forces on the cell)";
      throw SimulationInstability("triangle_collapsed", msg.str())
          .at_particle(pid(t.tri_v0[q]))
          .in_cell(cell.mol_id)
          .at_time(time)
          .with_value(0.0);
    }
  }
  if (t.closed && cell.volume.kv != 0.0) {
    const double ratio = std::abs(volume) / cell.volume.volume0;
    if (ratio < volume_collapsed || ratio > volume_exploded) {
      const bool collapsed = ratio < volume_collapsed;
      msg << "the volume of the cell with mol_id " << cell.mol_id << " "
          << (collapsed ? "collapsed" : "exploded") << " to " << ratio
          << " times its relaxed volume " << cell.volume.volume0 << " at time " << time
          << (collapsed ? " (crushed: reduce the flow or the forces on it, or raise kv)"
                        : " (blown up: reduce the time step or the moduli)");
      throw SimulationInstability(collapsed ? "volume_collapsed" : "volume_exploded", msg.str())
          .in_cell(cell.mol_id)
          .at_particle(pid(0))
          .at_time(time)
          .with_value(ratio);
    }
  }
  int worst = 0;
  for (int k = 0; k < t.n_nodes; ++k) {
    double fk[3];
    at(ws.f[k], fk);
    if (not_finite(fk[0]) || not_finite(fk[1]) || not_finite(fk[2])) {
      worst = k;
      break;
    }
  }
  msg << "the membrane forces of the cell with mol_id " << cell.mol_id
      << " (bonded interactions: local " << cell.local_bond_id << ", global " << cell.global_bond_id
      << ") are not finite at particle " << pid(worst) << " at time " << time
      << ": the cell has blown up (or its triangles collapsed); reduce the time step or the moduli";
  throw SimulationInstability("cell_blown_up", msg.str())
      .at_particle(pid(worst))
      .in_cell(cell.mol_id)
      .at_time(time);
}

void Model::evaluate(const ParticleStore& p, const BoxGeometry& box, double time, Vec3* force,
                     Vec3* normal, std::vector<CellReport>* reports, PassCounts& counts) {
  m_deferred.clear();
  if (reports) {
    reports->assign(m_cells.size(), CellReport{});
    for (std::size_t c = 0; c < m_cells.size(); ++c)
      (*reports)[c].mol_id = m_cells[c].mol_id;
  }
  if (normal && m_shared_nodes)
    for (const int i : m_normal_nodes)
      normal[i].setZero();
  for (const Group& g : m_groups) {
    if (g.lanes > 1) {
      ++counts.lane_batches;
      counts.padded_lanes += g.lanes - g.n_cells;
      if (reports)
        evaluate_group<Lanes, true>(g, p, box, time, force, normal, reports);
      else
        evaluate_group<Lanes, false>(g, p, box, time, force, normal, reports);
    } else {
      ++counts.plain_cells;
      if (reports)
        evaluate_group<double, true>(g, p, box, time, force, normal, reports);
      else
        evaluate_group<double, false>(g, p, box, time, force, normal, reports);
    }
  }
  if (normal && m_shared_nodes)
    for (const int i : m_normal_nodes) {
      const OutwardNormal<double> n(normal[i][0], normal[i][1], normal[i][2], 1.0);
      normal[i] = Vec3(n.x, n.y, n.z);
    }
}

} // namespace pyoif::membrane
