#include "interactions/bonded/oif_fast_path.hpp"

#include "interactions/bonded/oif_edge_terms.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

// The per-cell arrays of the triangle passes are disjoint slices of one
// buffer: tell the compiler their iterations are independent (vectorise).
#if defined(__clang__)
#define PYOIF_INDEPENDENT_ITERATIONS _Pragma("clang loop vectorize(assume_safety)")
#elif defined(__GNUC__)
#define PYOIF_INDEPENDENT_ITERATIONS _Pragma("GCC ivdep")
#else
#define PYOIF_INDEPENDENT_ITERATIONS
#endif

namespace pyoif::oif {

namespace {

constexpr int kind_local = 0, kind_global = 1, kind_out_direction = 2;

/** Local-area force (eq. 5) of the triangle (p0, p1, p2), allocated through
 *  its centroid T as in oif_area.hpp: vertex i gets scale (T - p_i), scale =
 *  kal (weight A - A0) / sum_i |T - p_i|^2; weight 0 for a triangle another
 *  bond owns. Vertices relative to the bond's owner (one of them is zero). */
__attribute__((always_inline)) inline void
centroid_area_force(const double (&p0)[3], const double (&p1)[3], const double (&p2)[3],
                    double area, double weight, double area0, double kal, double* const (&f0)[3],
                    double* const (&f1)[3], double* const (&f2)[3]) {
  double m0[3], m1[3], m2[3], norm2 = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double t = (p0[d] + p1[d] + p2[d]) / 3.0;
    m0[d] = t - p0[d];
    m1[d] = t - p1[d];
    m2[d] = t - p2[d];
  }
  for (int d = 0; d < 3; ++d)
    norm2 += m0[d] * m0[d] + m1[d] * m1[d] + m2[d] * m2[d];
  const double scale = kal * (weight * area - area0) / norm2;
  for (int d = 0; d < 3; ++d) {
    *f0[d] += scale * m0[d];
    *f1[d] += scale * m1[d];
    *f2[d] += scale * m2[d];
  }
}

/** atan(t) for |t| <= 1/4 (dihedral deviations below 14 degrees, most of a
 *  membrane's): t P(t^2), P the Chebyshev economisation on [0, 1/16] of the
 *  Taylor series of atan(sqrt s)/sqrt s, derived in exact rational arithmetic
 *  (dropped terms < 5e-18; largest relative error against libm's atan on 2e5
 *  random points 2.2e-16). Branch-free, so a block of bonds vectorises. */
inline double atan_small(double t) {
  const double s = t * t;
  double pz = 0.04599761088928747;
  pz = pz * s - 0.06523656687585018;
  pz = pz * s + 0.07683492919828101;
  pz = pz * s - 0.09090589248444612;
  pz = pz * s + 0.11111104259672454;
  pz = pz * s - 0.1428571420303533;
  pz = pz * s + 0.19999999999499324;
  pz = pz * s - 0.33333333333332166;
  pz = pz * s + 1.0;
  return t * pz;
}

/** The minimum image of box_geometry.hpp on n separations along one periodic
 *  axis of length L, as a loop over an array that vectorises (no branch per
 *  vector component in the gather): where |d| > L/2, d - L n with n the
 *  nearest integer to d/L (as BoxGeometry::minimum_image; only a separation
 *  of exactly a half-integer number of boxes, ambiguous anyway, can round the
 *  other way). */
inline void minimum_image_axis(double* d, int n, double L) {
  const double half = 0.5 * L, inv_L = 1.0 / L;
  for (int k = 0; k < n; ++k) {
    const double x = d[k];
    d[k] = std::abs(x) > half ? x - L * std::nearbyint(x * inv_L) : x;
  }
}

/** Whether any of n separations along one periodic axis of length L is
 *  longer than L/2 (then minimum_image_axis is needed). */
inline bool beyond_half(const double* d, int n, double L) {
  const double half = 0.5 * L;
  int beyond = 0;
  for (int k = 0; k < n; ++k)
    beyond |= std::abs(d[k]) > half;
  return beyond;
}

constexpr int kBlock = 64; ///< bonds or triangles per block (arrays stay in L1)

/** Per-block arrays of the edge pass (structure of arrays). */
struct EdgeBlock {
  double e[3][kBlock], u[3][kBlock], w[3][kBlock], dv[3][kBlock];
  double l[kBlock], inv_l2[kBlock], coefficient[kBlock];
  double n1[3][kBlock], n2[3][kBlock], n1_2[kBlock], n2_2[kBlock];
  double sine[kBlock], cosine[kBlock], dphi[kBlock];
  double fa[3][kBlock], fb[3][kBlock], fc[3][kBlock], fd[3][kBlock];
};

} // namespace

FastBondPlan::Key FastBondPlan::key_of(const BondGroup& group, const ParticleStore& p,
                                       int kind) const {
  Key k;
  k.particles_version = p.layout_version;
  k.ids = group.ids.data();
  k.per_bond = group.per_bond.data();
  k.n_ids = group.ids.size();
  k.n_per_bond = group.per_bond.size();
  k.kind = kind;
  return k;
}

bool FastBondPlan::build_slots(const BondGroup& group, const ParticleStore& p,
                               std::vector<int>& bond_slots) {
  std::vector<int> slot_of(p.n_local(), -1);
  m_index.clear();
  bond_slots.resize(group.ids.size());
  for (std::size_t k = 0; k < group.ids.size(); ++k) {
    const int i = p.index(group.ids[k]);
    if (i < 0)
      return false; // the generic loop names the missing particle
    if (slot_of[i] < 0) {
      slot_of[i] = static_cast<int>(m_index.size());
      m_index.push_back(i);
    }
    bond_slots[k] = slot_of[i];
  }
  const std::size_t n = m_index.size();
  // frames: the connected sets of the bonds (union-find over slots), each
  // referred to its first slot
  std::vector<int> parent(n);
  for (std::size_t s = 0; s < n; ++s)
    parent[s] = static_cast<int>(s);
  auto root = [&](int s) {
    while (parent[s] != s)
      s = parent[s] = parent[parent[s]];
    return s;
  };
  const std::size_t stride = group.n_particles > 0 ? group.n_particles : 1;
  for (std::size_t k = 0; k + stride <= bond_slots.size(); k += stride)
    for (std::size_t j = 1; j < stride; ++j) {
      const int r0 = root(bond_slots[k]), r1 = root(bond_slots[k + j]);
      if (r0 != r1)
        parent[std::max(r0, r1)] = std::min(r0, r1); // the root stays the first slot
    }
  // slots renumbered frame by frame (a frame's nodes contiguous, its
  // reference node first; the order within a frame kept): one pass per frame
  std::vector<int> frame_of(n), order(n), new_slot(n);
  for (std::size_t s = 0; s < n; ++s) {
    frame_of[s] = root(static_cast<int>(s));
    order[s] = static_cast<int>(s);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return frame_of[x] < frame_of[y]; });
  std::vector<int> index(n);
  m_frame_begin.clear();
  for (std::size_t k = 0; k < n; ++k) {
    if (k == 0 || frame_of[order[k]] != frame_of[order[k - 1]])
      m_frame_begin.push_back(static_cast<int>(k));
    new_slot[order[k]] = static_cast<int>(k);
    index[k] = m_index[order[k]];
  }
  m_frame_begin.push_back(static_cast<int>(n));
  m_index.swap(index);
  for (int& s : bond_slots)
    s = new_slot[s];
  m_x.resize(n);
  m_v.resize(n);
  m_f.resize(n);
  return true;
}

bool FastBondPlan::build_local(const BondGroup& group, const ParticleStore& p) {
  std::vector<int> slots;
  if (group.n_particles != 4 || group.per_bond_stride != 4 || !build_slots(group, p, slots))
    return false;
  const std::size_t n = group.size();
  m_bonds.resize(n);
  m_ref.resize(n);
  // Unique triangles, keyed by their sorted slots (21 bits each). Each is
  // evaluated once, by one of the bonds that have it (its "owner", in the
  // owner's edge pass, from the vectors gathered there anyway) with weight =
  // (bonds using it) / 3 and area0 = the sum of those bonds' reference areas
  // / 3: the sum of the bonds' kal (S - S0_bond) / 3 of oif_local_forces.hpp
  // is then kal (weight S - area0), applied once. Owners are chosen so that a
  // bond owns at most one triangle (a closed mesh has 2/3 triangle per edge):
  // each bond then evaluates one centroid allocation, not two.
  if (m_index.size() >= (std::size_t(1) << 21))
    return false;
  struct Use {
    std::size_t bond;
    int bcd; // 0: triangle ABC, 1: BCD
  };
  std::unordered_map<std::uint64_t, int> triangle_of;
  triangle_of.reserve(n);
  std::vector<std::vector<Use>> uses;
  std::vector<double> area0_sum;
  auto add_triangle = [&](int s0, int s1, int s2, double area0, std::size_t bond, int bcd) {
    int lo = std::min({s0, s1, s2}), hi = std::max({s0, s1, s2});
    const int mid = s0 + s1 + s2 - lo - hi;
    const std::uint64_t key = static_cast<std::uint64_t>(lo) |
                              (static_cast<std::uint64_t>(mid) << 21) |
                              (static_cast<std::uint64_t>(hi) << 42);
    auto [it, inserted] = triangle_of.try_emplace(key, static_cast<int>(uses.size()));
    if (inserted) {
      uses.emplace_back();
      area0_sum.push_back(0.0);
    }
    area0_sum[it->second] += area0;
    uses[it->second].push_back({bond, bcd});
  };
  for (std::size_t b = 0; b < n; ++b) {
    const int* s = slots.data() + 4 * b; // (B, A, C, D)
    const double* ref = group.reference(b);
    // the generic loop rejects these as degenerate (and throws): leave it to it
    if (!(ref[0] > 0.0) || !(ref[2] > 0.0) || !(ref[3] > 0.0) || !std::isfinite(ref[1]))
      return false;
    m_bonds[b] = {s[0], s[1], s[2], s[3]};
    m_ref.r0[b] = ref[0];
    m_ref.inv_r0[b] = 1.0 / ref[0];
    // psi0 = pi - phi0: cos psi0 = -cos phi0, sin psi0 = sin phi0
    m_ref.cos_psi0[b] = -std::cos(ref[1]);
    m_ref.sin_psi0[b] = std::sin(ref[1]);
    add_triangle(s[1], s[0], s[2], ref[2], b, 0); // A B C
    add_triangle(s[0], s[2], s[3], ref[3], b, 1); // B C D
  }
  // owners: greedily the first free bond; else move the owner of one of the
  // triangle's bonds to another free bond of its own (one augmenting step);
  // else the triangle is an extra of its first bond
  const std::size_t n_triangles = uses.size();
  std::vector<int> owned(n, -1); // bond -> triangle it evaluates
  std::vector<Use> owner(n_triangles, Use{0, -1});
  std::vector<int> unplaced;
  auto place = [&](int t, const Use& u) {
    owned[u.bond] = t;
    owner[t] = u;
  };
  for (std::size_t t = 0; t < n_triangles; ++t) {
    bool done = false;
    for (const Use& u : uses[t])
      if (!done && owned[u.bond] < 0) {
        place(static_cast<int>(t), u);
        done = true;
      }
    if (!done)
      unplaced.push_back(static_cast<int>(t));
  }
  m_extra.clear();
  for (const int t : unplaced) {
    bool done = false;
    for (const Use& u : uses[t]) {
      const int other = owned[u.bond];
      for (const Use& v : uses[other])
        if (!done && owned[v.bond] < 0) {
          place(other, v);
          place(t, u);
          done = true;
        }
      if (done)
        break;
    }
    if (!done) {
      const Use& u = uses[t].front();
      m_extra.push_back({u.bond, u.bcd, uses[t].size() / 3.0, area0_sum[t] / 3.0});
    }
  }
  std::sort(m_extra.begin(), m_extra.end(),
            [](const ExtraTriangle& x, const ExtraTriangle& y) { return x.bond < y.bond; });
  for (std::size_t t = 0; t < n_triangles; ++t) {
    if (owner[t].bcd < 0)
      continue; // an extra
    const std::size_t b = owner[t].bond;
    m_ref.bcd[b] = owner[t].bcd;
    m_ref.weight[b] = uses[t].size() / 3.0;
    m_ref.area0[b] = area0_sum[t] / 3.0;
  }
  return true;
}

bool FastBondPlan::build_triangles(const BondGroup& group, const ParticleStore& p) {
  std::vector<int> slots;
  if (group.n_particles != 3 || !build_slots(group, p, slots))
    return false;
  const std::size_t n = group.size();
  m_triangles.resize(n);
  m_slot_mol.resize(m_index.size());
  for (std::size_t k = 0; k < m_index.size(); ++k)
    m_slot_mol[k] = p.mol_id[m_index[k]];
  m_cell_mol.clear();
  m_cell_reference.clear();
  // cells as the generic cell sums define them: the mol_id of a triangle's
  // first node; reference point the first node of the cell's first triangle
  std::unordered_map<int, int> cell_of_mol;
  for (std::size_t t = 0; t < n; ++t) {
    const int* s = slots.data() + 3 * t;
    const int mol = p.mol_id[m_index[s[0]]];
    auto [it, inserted] = cell_of_mol.try_emplace(mol, static_cast<int>(m_cell_mol.size()));
    if (inserted) {
      m_cell_mol.push_back(mol);
      m_cell_reference.push_back(s[0]);
    }
    m_triangles[t] = {s[0], s[1], s[2], it->second};
  }
  // each node in the triangles of one cell only (as an OifCell's): its
  // forces are then its cell's factors times its sums (run); else decline
  m_slot_cell.assign(m_index.size(), -1);
  m_nodes_in_one_cell = true;
  for (const Triangle& tr : m_triangles)
    for (const int v : {tr.v0, tr.v1, tr.v2}) {
      m_nodes_in_one_cell &= m_slot_cell[v] < 0 || m_slot_cell[v] == tr.cell;
      m_slot_cell[v] = tr.cell;
    }
  const std::size_t n_cells = m_cell_mol.size();
  // triangles grouped by cell (a cell's are contiguous when created in bulk;
  // the stable sort keeps their order): per-cell passes over a range
  std::stable_sort(m_triangles.begin(), m_triangles.end(),
                   [](const Triangle& a, const Triangle& b) { return a.cell < b.cell; });
  m_cell_begin.assign(n_cells + 1, 0);
  for (std::size_t t = 0; t < n; ++t)
    ++m_cell_begin[m_triangles[t].cell + 1];
  std::size_t largest = 0;
  for (std::size_t c = 0; c < n_cells; ++c) {
    largest = std::max<std::size_t>(largest, m_cell_begin[c + 1]);
    m_cell_begin[c + 1] += m_cell_begin[c];
  }
  m_scratch.resize(kCellArrays * largest);
  m_cell_origin.resize(n_cells);
  return true;
}

bool FastBondPlan::gather_relative_same_cells(const ParticleStore& p, const BoxGeometry& box) {
  int same = 1;
  for (std::size_t s = 0; s < m_index.size(); ++s)
    same &= p.mol_id[m_index[s]] == m_slot_mol[s];
  gather_relative(p, box);
  return same;
}

void FastBondPlan::gather_relative(const ParticleStore& p, const BoxGeometry& box) {
  const Vec3& L = box.length();
  const Vec3 half = 0.5 * L;
  int within = 1;
  for (std::size_t f = 0; f + 1 < m_frame_begin.size(); ++f) {
    const int begin = m_frame_begin[f], end = m_frame_begin[f + 1];
    const int r = m_index[begin];
    const Vec3 pos_r = p.pos[r];
    const Vec3i image_r = p.image[r];
    Vec3 low = Vec3::Zero(), high = Vec3::Zero();
    for (int s = begin; s < end; ++s) {
      const int i = m_index[s];
      // the image difference first (integers, exact): no growth of rounding
      // with the number of boxes a cell has travelled
      const Vec3 x = (p.pos[i] - pos_r) + (p.image[i] - image_r).cast<double>().cwiseProduct(L);
      m_x[s] = x;
      low = low.cwiseMin(x);
      high = high.cwiseMax(x);
    }
    // within half the box on every periodic axis, all the frame's
    // separations are their own minimum images (no check per bond)
    for (int d = 0; d < 3; ++d)
      within &= !box.periodic()[d] || high[d] - low[d] <= half[d];
  }
  m_within_half = within;
}

void FastBondPlan::gather_positions(const ParticleStore& p) {
  for (std::size_t s = 0; s < m_index.size(); ++s)
    m_x[s] = p.pos[m_index[s]];
}

bool FastBondPlan::commit_forces(ParticleStore& p) const {
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "m_f is read as an array of doubles");
  // NaN or inf anywhere: decline, the generic loop names the bond
  const double* f = m_f.empty() ? nullptr : m_f[0].data();
  const std::size_t n = 3 * m_f.size();
  const double largest = std::numeric_limits<double>::max();
  int finite = 1;
  for (std::size_t k = 0; k < n; ++k)
    finite &= std::abs(f[k]) <= largest;
  if (!finite)
    return false;
  for (std::size_t s = 0; s < m_index.size(); ++s)
    p.force[m_index[s]] += m_f[s];
  return true;
}

// ---------------------------------------------------------------------------
// OifLocalForces
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifLocalForces& ia, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const Key key = key_of(group, p, kind_local);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_local(group, p);
    ++m_n_builds;
  }
  if (!m_usable)
    return false;
  gather_relative(p, box);
  if (ia.kvisc != 0.0)
    for (std::size_t s = 0; s < m_index.size(); ++s)
      m_v[s] = p.vel[m_index[s]];
  for (Vec3& f : m_f)
    f.setZero();

  // One pass over the bonds in blocks: gather the minimum-image edge vectors
  // (indexed loads), then the arithmetic over plain arrays (short independent
  // loops the compiler vectorises; one bond at a time, its long chain of square
  // roots, divisions and the arctangent leaves the core waiting), then scatter
  // the forces on the four nodes.
  const double ks = ia.ks, kslin = ia.kslin, kvisc = ia.kvisc, kb = ia.kb, kal = ia.kal;
  const bool wings = kb != 0.0 || kal != 0.0; // terms that need a and d
  EdgeBlock blk;
  const ExtraTriangle *extra = m_extra.data(), *const extra_end = extra + m_extra.size();
  for (std::size_t first = 0; first < m_bonds.size(); first += kBlock) {
    const int nb = static_cast<int>(std::min<std::size_t>(kBlock, m_bonds.size() - first));
    const EdgeBond* bond = m_bonds.data() + first;
    const double *r0 = m_ref.r0.data() + first, *inv_r0 = m_ref.inv_r0.data() + first;
    const double *cos_psi0 = m_ref.cos_psi0.data() + first,
                 *sin_psi0 = m_ref.sin_psi0.data() + first;
    const double *bcd = m_ref.bcd.data() + first, *weight = m_ref.weight.data() + first,
                 *area0 = m_ref.area0.data() + first;
    for (int k = 0; k < nb; ++k) {
      const EdgeBond& bd = bond[k];
      const Vec3& xb = m_x[bd.b];
      const Vec3 e = m_x[bd.c] - xb; // c - b, the shared edge (minimum image below)
      for (int d = 0; d < 3; ++d)
        blk.e[d][k] = e[d];
      if (wings) {
        const Vec3 u = m_x[bd.a] - xb; // a - b
        const Vec3 w = m_x[bd.d] - xb; // d - b
        for (int d = 0; d < 3; ++d) {
          blk.u[d][k] = u[d];
          blk.w[d][k] = w[d];
        }
      }
      if (kvisc != 0.0) {
        const Vec3 dv = m_v[bd.c] - m_v[bd.b];
        for (int d = 0; d < 3; ++d)
          blk.dv[d][k] = dv[d];
      }
    }
    // separations of the frame; a cell wider than half the box (unusual)
    // needs the minimum image of the generic loop
    for (int d = 0; d < 3; ++d)
      if (!m_within_half && box.periodic()[d]) {
        const double L = box.length()[d];
        if (beyond_half(blk.e[d], nb, L))
          minimum_image_axis(blk.e[d], nb, L);
        if (wings) {
          if (beyond_half(blk.u[d], nb, L))
            minimum_image_axis(blk.u[d], nb, L);
          if (beyond_half(blk.w[d], nb, L))
            minimum_image_axis(blk.w[d], nb, L);
        }
      }
    int bad = 0;
    for (int k = 0; k < nb; ++k) {
      const double l2 =
          blk.e[0][k] * blk.e[0][k] + blk.e[1][k] * blk.e[1][k] + blk.e[2][k] * blk.e[2][k];
      bad |= !(l2 > 0.0);
      blk.l[k] = std::sqrt(l2);
      blk.inv_l2[k] = 1.0 / l2;
    }
    if (bad)
      return false;

    // stretching (eq. 3) and viscosity: force on b along e, c gets the opposite
    for (int k = 0; k < nb; ++k)
      blk.coefficient[k] = 0.0;
    if (ks != 0.0)
      for (int k = 0; k < nb; ++k) {
        const double l = blk.l[k];
        blk.coefficient[k] +=
            ks * neo_hookean_kappa(l * inv_r0[k]) * (l - r0[k]) * l * blk.inv_l2[k]; // (l - l0) / l
      }
    if (kslin != 0.0)
      for (int k = 0; k < nb; ++k)
        blk.coefficient[k] += kslin * (blk.l[k] - r0[k]) * blk.l[k] * blk.inv_l2[k];
    if (kvisc != 0.0)
      for (int k = 0; k < nb; ++k)
        blk.coefficient[k] +=
            kvisc *
            (blk.dv[0][k] * blk.e[0][k] + blk.dv[1][k] * blk.e[1][k] + blk.dv[2][k] * blk.e[2][k]) *
            blk.inv_l2[k];
    for (int k = 0; k < nb; ++k)
      for (int d = 0; d < 3; ++d) {
        const double fe = blk.coefficient[k] * blk.e[d][k];
        blk.fa[d][k] = 0.0;
        blk.fb[d][k] = fe;
        blk.fc[d][k] = -fe;
        blk.fd[d][k] = 0.0;
      }

    if (wings) {
      // the triangles' normals n1 = (a - b) x e (triangle ABC) and
      // n2 = e x (d - b) (BCD), |n| = twice the area
      for (int k = 0; k < nb; ++k) {
        const double ex = blk.e[0][k], ey = blk.e[1][k], ez = blk.e[2][k];
        const double ux = blk.u[0][k], uy = blk.u[1][k], uz = blk.u[2][k];
        const double wx = blk.w[0][k], wy = blk.w[1][k], wz = blk.w[2][k];
        const double n1x = uy * ez - uz * ey, n1y = uz * ex - ux * ez, n1z = ux * ey - uy * ex;
        const double n2x = ey * wz - ez * wy, n2y = ez * wx - ex * wz, n2z = ex * wy - ey * wx;
        const double n1_2 = n1x * n1x + n1y * n1y + n1z * n1z;
        const double n2_2 = n2x * n2x + n2y * n2y + n2z * n2z;
        bad |= !(n1_2 > 0.0) | !(n2_2 > 0.0); // degenerate triangle
        blk.n1[0][k] = n1x, blk.n1[1][k] = n1y, blk.n1[2][k] = n1z;
        blk.n2[0][k] = n2x, blk.n2[1][k] = n2y, blk.n2[2][k] = n2z;
        blk.n1_2[k] = n1_2;
        blk.n2_2[k] = n2_2;
      }
      if (bad)
        return false;
    }

    if (kb != 0.0) {
      // the dihedral angle of oif_bending.hpp: psi = atan2((n1 x n2).e / l,
      // n1.n2) with (n1 x n2).e / l = l n1.w; phi - phi0 = -(psi - psi0),
      // psi0 = pi - phi0, taken as one angle (sine and cosine rotated by psi0)
      int slow = 0;
      for (int k = 0; k < nb; ++k) {
        const double y = blk.l[k] * (blk.n1[0][k] * blk.w[0][k] + blk.n1[1][k] * blk.w[1][k] +
                                     blk.n1[2][k] * blk.w[2][k]);
        const double x =
            blk.n1[0][k] * blk.n2[0][k] + blk.n1[1][k] * blk.n2[1][k] + blk.n1[2][k] * blk.n2[2][k];
        const double c0 = cos_psi0[k], s0 = sin_psi0[k];
        const double sine = y * c0 - x * s0, cosine = x * c0 + y * s0;
        const bool small = cosine > 0.0 && std::abs(sine) <= 0.25 * cosine;
        slow |= !small;
        blk.dphi[k] = -atan_small(small ? sine / cosine : 0.0);
        blk.sine[k] = sine;
        blk.cosine[k] = cosine;
      }
      if (slow) // deviations beyond atan(1/4): the library's arctangent
        for (int k = 0; k < nb; ++k) {
          const double sine = blk.sine[k], cosine = blk.cosine[k];
          if (cosine > 0.0 && std::abs(sine) <= 0.25 * cosine)
            continue;
          double dphi = -std::atan2(sine, cosine);
          if (dphi <= -M_PI) // into (-pi, pi] as the generic bending
            dphi += 2.0 * M_PI;
          blk.dphi[k] = dphi;
        }
      // F = -kb dphi grad phi: on the wings kb dphi l n / |n|^2, the edge ends
      // split by the wings' foot points ta, td (oif_bending.hpp)
      for (int k = 0; k < nb; ++k) {
        const double c = kb * blk.dphi[k] * blk.l[k] / (blk.n1_2[k] * blk.n2_2[k]);
        const double ca = c * blk.n2_2[k], cd = c * blk.n1_2[k];
        const double ta =
            (blk.u[0][k] * blk.e[0][k] + blk.u[1][k] * blk.e[1][k] + blk.u[2][k] * blk.e[2][k]) *
            blk.inv_l2[k];
        const double td =
            (blk.w[0][k] * blk.e[0][k] + blk.w[1][k] * blk.e[1][k] + blk.w[2][k] * blk.e[2][k]) *
            blk.inv_l2[k];
        for (int d = 0; d < 3; ++d) {
          const double fa = ca * blk.n1[d][k], fd = cd * blk.n2[d][k];
          blk.fa[d][k] += fa;
          blk.fd[d][k] += fd;
          blk.fb[d][k] -= (1.0 - ta) * fa + (1.0 - td) * fd;
          blk.fc[d][k] -= ta * fa + td * fd;
        }
      }
    }

    if (kal != 0.0) {
      // local area (eq. 5) of the triangle this bond owns (weight 0 else),
      // centroid allocation (oif_area.hpp). Both triangles have b, the
      // frame's zero, as a vertex: the triangle is (0, P, Q) with ABC: P = u
      // (a), Q = e (c); BCD: P = e (c), Q = w (d), chosen by factors 0/1
      // (exact), branch-free. Centroid T = (P + Q)/3; vertex i gets
      // scale (T - p_i), scale = kal (weight S - area0) / sum_i |T - p_i|^2.
      constexpr double third = 1.0 / 3.0;
      for (int k = 0; k < nb; ++k) {
        const double s1 = bcd[k], s0 = 1.0 - s1;
        double t[3], mp[3], mq[3];
        for (int d = 0; d < 3; ++d) {
          const double pd = s0 * blk.u[d][k] + s1 * blk.e[d][k];
          const double qd = s0 * blk.e[d][k] + s1 * blk.w[d][k];
          t[d] = (pd + qd) * third;
          mp[d] = t[d] - pd;
          mq[d] = t[d] - qd;
        }
        const double norm2 = (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]) +
                             (mp[0] * mp[0] + mp[1] * mp[1] + mp[2] * mp[2]) +
                             (mq[0] * mq[0] + mq[1] * mq[1] + mq[2] * mq[2]);
        const double area = 0.5 * std::sqrt(s0 * blk.n1_2[k] + s1 * blk.n2_2[k]);
        const double scale = kal * (weight[k] * area - area0[k]) / norm2;
        for (int d = 0; d < 3; ++d) {
          const double fp = scale * mp[d], fq = scale * mq[d];
          blk.fb[d][k] += scale * t[d];
          blk.fa[d][k] += s0 * fp;
          blk.fc[d][k] += s0 * fq + s1 * fp;
          blk.fd[d][k] += s1 * fq;
        }
      }
      // triangles that no bond could own alone (none on closed meshes seen)
      for (; extra != extra_end && extra->bond < first + nb; ++extra) {
        const int k = static_cast<int>(extra->bond - first);
        const double e[3] = {blk.e[0][k], blk.e[1][k], blk.e[2][k]};
        const double u[3] = {blk.u[0][k], blk.u[1][k], blk.u[2][k]};
        const double w[3] = {blk.w[0][k], blk.w[1][k], blk.w[2][k]};
        const double zero[3] = {0.0, 0.0, 0.0};
        double* fa[3] = {&blk.fa[0][k], &blk.fa[1][k], &blk.fa[2][k]};
        double* fb[3] = {&blk.fb[0][k], &blk.fb[1][k], &blk.fb[2][k]};
        double* fc[3] = {&blk.fc[0][k], &blk.fc[1][k], &blk.fc[2][k]};
        double* fd[3] = {&blk.fd[0][k], &blk.fd[1][k], &blk.fd[2][k]};
        if (extra->bcd == 0)
          centroid_area_force(u, zero, e, 0.5 * std::sqrt(blk.n1_2[k]), extra->weight, extra->area0,
                              kal, fa, fb, fc);
        else
          centroid_area_force(zero, e, w, 0.5 * std::sqrt(blk.n2_2[k]), extra->weight, extra->area0,
                              kal, fb, fc, fd);
      }
    }

    for (int k = 0; k < nb; ++k) {
      const EdgeBond& bd = bond[k];
      m_f[bd.b] += Vec3(blk.fb[0][k], blk.fb[1][k], blk.fb[2][k]);
      m_f[bd.c] += Vec3(blk.fc[0][k], blk.fc[1][k], blk.fc[2][k]);
      if (wings) {
        m_f[bd.a] += Vec3(blk.fa[0][k], blk.fa[1][k], blk.fa[2][k]);
        m_f[bd.d] += Vec3(blk.fd[0][k], blk.fd[1][k], blk.fd[2][k]);
      }
    }
  }
  return commit_forces(p);
}

// ---------------------------------------------------------------------------
// OifGlobalForces
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifGlobalForces& ia, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const Key key = key_of(group, p, kind_global);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_triangles(group, p);
    ++m_n_builds;
  }
  m_normals_written = false;
  if (!m_usable)
    return false;
  if (!gather_relative_same_cells(p, box)) { // a mol_id changed: the cells regroup
    m_usable = build_triangles(group, p);
    ++m_n_builds;
    if (!m_usable)
      return false;
    gather_relative(p, box);
  }
  if (!m_nodes_in_one_cell)
    return false;
  // One pass over each cell's triangles: per node, the sums that its forces
  // are the cell's factors times (eqs. 6, 7 need the cell's totals first):
  //   global area (centroid allocation, oif_area.hpp): vertex i of triangle
  //     t gets kag (S - S0)/S0 S_t (T - p_i) / sum_j |T - p_j|^2: sum over t
  //     of g_t (T - p_i), g_t = S_t / sum_j |T - p_j|^2, in m_f;
  //   volume (oif_volume.hpp): each vertex gets -kv (|V| - V0)/V0 s N_t / 6:
  //     sum of N_t = (b - a) x (c - a) over t, in m_normal (whose direction
  //     is also the node's normal of OifOutDirection).
  for (Vec3& f : m_f)
    f.setZero();
  m_normal.assign(m_index.size(), Vec3::Zero());
  m_cell_area_factor.resize(m_cell_mol.size());
  m_cell_volume_factor.resize(m_cell_mol.size());
  m_cell_sign.resize(m_cell_mol.size());
  const double ka_g = ia.ka_g, kv = ia.kv, A0_g = ia.A0_g, V0 = ia.V0;
  constexpr double third = 1.0 / 3.0;
  for (std::size_t cell = 0; cell < m_cell_mol.size(); ++cell) {
    const std::size_t begin = m_cell_begin[cell];
    const int n = static_cast<int>(m_cell_begin[cell + 1] - begin);
    const Triangle* tri = m_triangles.data() + begin;
    double* const sc = m_scratch.data();
    const std::size_t stride = m_scratch.size() / kCellArrays;
    auto arr = [&](int which) { return sc + which * stride; };
    double *e1x = arr(0), *e1y = arr(1), *e1z = arr(2), *e2x = arr(3), *e2y = arr(4), *e2z = arr(5),
           *nx = arr(6), *ny = arr(7), *nz = arr(8), *area = arr(9), *vol = arr(10), *ax = arr(11),
           *ay = arr(12), *az = arr(13);
    double *g0x = arr(14), *g0y = arr(15), *g0z = arr(16), *g1x = arr(17), *g1y = arr(18),
           *g1z = arr(19), *g2x = arr(20), *g2y = arr(21), *g2z = arr(22);
    // m_x: unfolded, relative to the frame's reference node (gather_relative)
    const Vec3 origin = m_x[m_cell_reference[cell]];
    for (int k = 0; k < n; ++k) {
      const Vec3& x0 = m_x[tri[k].v0];
      const Vec3 e1 = m_x[tri[k].v1] - x0; // minimum image below if needed
      const Vec3 e2 = m_x[tri[k].v2] - x0;
      // first vertex relative to the cell's reference point, unfolded
      // (oif_cell_sums.hpp): a . (b x c) = a . N with N = (b - a) x (c - a)
      const Vec3 a = x0 - origin;
      e1x[k] = e1[0], e1y[k] = e1[1], e1z[k] = e1[2];
      e2x[k] = e2[0], e2y[k] = e2[1], e2z[k] = e2[2];
      ax[k] = a[0], ay[k] = a[1], az[k] = a[2];
    }
    for (int d = 0; d < 3; ++d)
      if (!m_within_half && box.periodic()[d]) {
        const double L = box.length()[d];
        for (int which : {d, 3 + d}) // e1, e2
          if (beyond_half(arr(which), n, L))
            minimum_image_axis(arr(which), n, L);
      }
    int bad = 0;
    PYOIF_INDEPENDENT_ITERATIONS
    for (int k = 0; k < n; ++k) {
      const double e1x_ = e1x[k], e1y_ = e1y[k], e1z_ = e1z[k];
      const double e2x_ = e2x[k], e2y_ = e2y[k], e2z_ = e2z[k];
      const double x = e1y_ * e2z_ - e1z_ * e2y_;
      const double y = e1z_ * e2x_ - e1x_ * e2z_;
      const double z = e1x_ * e2y_ - e1y_ * e2x_;
      nx[k] = x, ny[k] = y, nz[k] = z;
      const double s = 0.5 * std::sqrt(x * x + y * y + z * z);
      bad |= !(s > 0.0);
      area[k] = s;
      vol[k] = ax[k] * x + ay[k] * y + az[k] * z;
      // centroid relative to the first vertex: T - p0 = (e1 + e2)/3
      const double m0x = (e1x_ + e2x_) * third, m0y = (e1y_ + e2y_) * third,
                   m0z = (e1z_ + e2z_) * third;
      const double m1x = m0x - e1x_, m1y = m0y - e1y_, m1z = m0z - e1z_;
      const double m2x = m0x - e2x_, m2y = m0y - e2y_, m2z = m0z - e2z_;
      const double g = s / (m0x * m0x + m0y * m0y + m0z * m0z + m1x * m1x + m1y * m1y + m1z * m1z +
                            m2x * m2x + m2y * m2y + m2z * m2z);
      g0x[k] = g * m0x, g0y[k] = g * m0y, g0z[k] = g * m0z;
      g1x[k] = g * m1x, g1y[k] = g * m1y, g1z[k] = g * m1z;
      g2x[k] = g * m2x, g2y[k] = g * m2y, g2z[k] = g * m2z;
    }
    if (bad)
      return false;
    // four partial sums: no loop-carried chain of additions
    double sa[4] = {0.0, 0.0, 0.0, 0.0}, sv[4] = {0.0, 0.0, 0.0, 0.0};
    int k = 0;
    for (; k + 4 <= n; k += 4)
      for (int j = 0; j < 4; ++j) {
        sa[j] += area[k + j];
        sv[j] += vol[k + j];
      }
    for (; k < n; ++k) {
      sa[0] += area[k];
      sv[0] += vol[k];
    }
    const double cell_area = (sa[0] + sa[1]) + (sa[2] + sa[3]);
    const double cell_volume = ((sv[0] + sv[1]) + (sv[2] + sv[3])) / 6.0;
    if (!(cell_area > 0.0))
      return false;
    // volume (eq. 7): F = -kv (|V| - V0)/V0 s N / 6 on each vertex
    const double sign = cell_volume < 0.0 ? -1.0 : 1.0;
    m_cell_volume_factor[cell] =
        kv != 0.0 ? -kv * ((sign * cell_volume - V0) / V0) * sign / 6.0 : 0.0;
    // global area (eq. 6): kag (S - S0) / S0 times the sums of g_t (T - p_i)
    m_cell_area_factor[cell] = ka_g != 0.0 ? ka_g * (cell_area - A0_g) / A0_g : 0.0;
    m_cell_sign[cell] = sign;
    for (int q = 0; q < n; ++q) {
      const Vec3 nq(nx[q], ny[q], nz[q]);
      m_f[tri[q].v0] += Vec3(g0x[q], g0y[q], g0z[q]);
      m_normal[tri[q].v0] += nq;
      m_f[tri[q].v1] += Vec3(g1x[q], g1y[q], g1z[q]);
      m_normal[tri[q].v1] += nq;
      m_f[tri[q].v2] += Vec3(g2x[q], g2y[q], g2z[q]);
      m_normal[tri[q].v2] += nq;
    }
  }
  for (std::size_t s = 0; s < m_index.size(); ++s) {
    const int c = m_slot_cell[s];
    m_f[s] = m_cell_area_factor[c] * m_f[s] + m_cell_volume_factor[c] * m_normal[s];
  }
  if (!commit_forces(p))
    return false;
  if (write_normals) { // OifOutDirection's area-weighted normals, outward by the volume's sign
    for (std::size_t s = 0; s < m_index.size(); ++s) {
      const double len = m_normal[s].norm();
      const Vec3 nq = m_cell_sign[m_slot_cell[s]] * m_normal[s];
      p.normal[m_index[s]] = len > 0.0 ? Vec3(nq / len) : nq;
    }
    m_normals_written = true;
  }
  return true;
}

bool FastBondPlan::same_triangles(const BondGroup& own, const BondGroup& source) {
  const Link now{own.ids.data(), own.ids.size(), source.ids.data(), source.ids.size()};
  if (!(now == m_link)) {
    m_link = now;
    m_link_same = own.n_particles == 3 && source.n_particles == 3 && own.ids == source.ids;
  }
  return m_link_same;
}

// ---------------------------------------------------------------------------
// OifOutDirection
// ---------------------------------------------------------------------------
bool FastBondPlan::run(const OifOutDirection&, const BondGroup& group, ParticleStore& p,
                       const BoxGeometry& box) {
  const Key key = key_of(group, p, kind_out_direction);
  if (!(key == m_key)) {
    m_key = key;
    m_usable = build_triangles(group, p);
    ++m_n_builds;
    if (m_usable) {
      // a cell's orientation is fixed by its mesh: the sign of its oriented
      // volume, determined once per set of bonds (as OifOutDirection does)
      gather_positions(p);
      std::vector<double> volume(m_cell_mol.size(), 0.0);
      for (std::size_t c = 0; c < m_cell_mol.size(); ++c) {
        const int i = m_index[m_cell_reference[c]];
        m_cell_origin[c] = box.unfolded(p.pos[i], p.image[i]);
      }
      for (const Triangle& tr : m_triangles) {
        const Vec3& x0 = m_x[tr.v0];
        const Vec3 n = box.minimum_image(m_x[tr.v1], x0).cross(box.minimum_image(m_x[tr.v2], x0));
        volume[tr.cell] +=
            (box.unfolded(x0, p.image[m_index[tr.v0]]) - m_cell_origin[tr.cell]).dot(n);
      }
      m_outward_sign.resize(m_triangles.size());
      for (std::size_t t = 0; t < m_triangles.size(); ++t)
        m_outward_sign[t] = volume[m_triangles[t].cell] < 0.0 ? -1.0 : 1.0;
    }
  }
  if (!m_usable)
    return false;
  gather_positions(p);
  for (Vec3& f : m_f)
    f.setZero();
  // area-weighted normal of each node: the sum of its triangles' 2 S n
  for (std::size_t t = 0; t < m_triangles.size(); ++t) {
    const Triangle& tr = m_triangles[t];
    const Vec3& x0 = m_x[tr.v0];
    const Vec3 n = m_outward_sign[t] *
                   box.minimum_image(m_x[tr.v1], x0).cross(box.minimum_image(m_x[tr.v2], x0));
    m_f[tr.v0] += n;
    m_f[tr.v1] += n;
    m_f[tr.v2] += n;
  }
  for (std::size_t s = 0; s < m_index.size(); ++s) {
    const double len = m_f[s].norm();
    p.normal[m_index[s]] = len > 0.0 ? Vec3(m_f[s] / len) : m_f[s];
  }
  return true;
}

} // namespace pyoif::oif
