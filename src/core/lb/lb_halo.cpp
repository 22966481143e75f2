// The lattice's halo: the plan (per neighbouring rank, the places of the
// populations that cross each face, sent from the faces after an even update
// and from the ghost layer after an odd one, lb_fluid.hpp), its transports
// (periodic copies on this rank, MPI messages through NeighbourExchange, or a
// shared-memory segment between ranks of one machine), and the two other
// exchanges of the ghost layer: the fluid velocities it holds and the
// coupling's ghost velocities.
#include "communication/neighbour_exchange.hpp"
#include "lb/lb_fluid.hpp"

#include "utils/errors.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <utility>

#include "lb/lattice_codegen.hpp" // last: it applies to this file's functions

namespace pyoif::lb {

using namespace d3q19;

template <class Visit>
void LBFluid::visit_region(const Vec3i& lower, const Vec3i& extent, const Vec3i& o, bool with_q,
                           Visit&& visit) const {
  // Region o of the ghost layer of the subdomain (lower, extent), in its
  // padded coordinates: the single ghost plane where o_d != 0, the domain's
  // range where o_d = 0. With q: the populations whose velocity points into
  // the region (c_d = o_d wherever o_d != 0), at the ghosts g that a domain
  // node g - c_q reaches (along an axis the region spans, only ghosts whose
  // node g - c_q lies in the domain take part; the others belong to a
  // neighbouring edge or corner region). Listed z, y, x outermost to
  // innermost, q innermost: both ranks of a pair walk it alike.
  int lo[3], hi[3];
  for (int d = 0; d < 3; ++d) {
    if (o[d] == 0) {
      lo[d] = 1;
      hi[d] = extent[d];
    } else {
      lo[d] = hi[d] = o[d] < 0 ? 0 : extent[d] + 1;
    }
  }
  for (int q = with_q ? 1 : 0; q < (with_q ? Q : 1); ++q) {
    if (with_q) {
      bool moves_in = true;
      for (int d = 0; d < 3; ++d)
        if (o[d] != 0 && c[q][d] != o[d])
          moves_in = false;
      if (!moves_in)
        continue;
    }
    int qlo[3], qhi[3];
    for (int d = 0; d < 3; ++d) {
      const int cq = with_q ? c[q][d] : 0;
      qlo[d] = o[d] == 0 ? std::max(lo[d], 1 + cq) : lo[d];
      qhi[d] = o[d] == 0 ? std::min(hi[d], extent[d] + cq) : hi[d];
    }
    for (int z = qlo[2]; z <= qhi[2]; ++z)
      for (int y = qlo[1]; y <= qhi[1]; ++y)
        for (int x = qlo[0]; x <= qhi[0]; ++x)
          visit(Vec3i(lower[0] + x - 1, lower[1] + y - 1, lower[2] + z - 1), q);
  }
}

void LBFluid::build_halo_pairs() {
  // After an odd update the region o of the ghost layer holds what the
  // domain pushed out, to be folded into the neighbour's face; after an even
  // update the odd update will read it there, so it is filled from the
  // neighbour's face. Only pairs where the ghost g and the node g - c_q
  // are fluid are kept: a solid node pushes nothing and reads nothing, and
  // a solid ghost is served by the bounce-back links. So channel walls cost
  // no halo traffic at all. Where the neighbour is this rank (an axis not
  // split), the pairs are copies within the array (merged into runs); with
  // another rank, lists of places packed into one message per neighbour:
  // this rank's ghosts of region o (neighbour at o), and this rank's face
  // that is region o of the neighbour at -o, both listed by visit_region
  // over the ghost owner's subdomain.
  std::vector<PlaceRun> pairs;
  m_halo.peers.clear();
  m_halo.ghost_slot.clear();
  m_halo.ghost_node.clear();
  m_halo.ghost_velocity.clear();
  m_halo.ghost_velocity_version = ~std::uint64_t{0};
  auto peer = [&](int rank) -> HaloPeer& {
    for (HaloPeer& p : m_halo.peers)
      if (p.rank == rank)
        return p;
    m_halo.peers.emplace_back();
    m_halo.peers.back().rank = rank;
    return m_halo.peers.back();
  };
  const Vec3i me = m_grid.coords();
  for (int oz = -1; oz <= 1; ++oz)
    for (int oy = -1; oy <= 1; ++oy)
      for (int ox = -1; ox <= 1; ++ox) {
        const Vec3i o(ox, oy, oz);
        if (o == Vec3i::Zero())
          continue;
        const int ahead = m_grid.neighbour(o), behind = m_grid.neighbour(-o);
        if (ahead == m_grid.rank()) {
          // this rank's own periodic image (behind is this rank too)
          visit_region(m_origin, m_n, o, true, [&](const Vec3i& g, int q) {
            const std::size_t ghost =
                index(g[0] - m_origin[0] + 1, g[1] - m_origin[1] + 1, g[2] - m_origin[2] + 1);
            if (m_flag[ghost] != 0 || m_flag[ghost - m_offset[q]] != 0)
              return;
            const std::size_t slot = static_cast<std::size_t>(q) * m_pop.stride();
            pairs.push_back({slot + ghost, slot + domain_index(g), 1, 0.0});
          });
          continue;
        }
        HaloPeer& in = peer(ahead);
        visit_region(m_origin, m_n, o, true, [&](const Vec3i& g, int q) {
          const std::size_t ghost =
              index(g[0] - m_origin[0] + 1, g[1] - m_origin[1] + 1, g[2] - m_origin[2] + 1);
          if (m_flag[ghost] != 0 || m_flag[ghost - m_offset[q]] != 0)
            return;
          in.ghost.push_back(static_cast<std::size_t>(q) * m_pop.stride() + ghost);
        });
        const Vec3i c_behind = me - o;
        HaloPeer& out = peer(behind);
        visit_region(m_grid.lower(c_behind), m_grid.extent(c_behind), o, true,
                     [&](const Vec3i& g, int q) {
                       const std::size_t face = domain_index(g);
                       if (m_flag[face] != 0 || m_flag[face - m_offset[q]] != 0)
                         return;
                       out.face.push_back(static_cast<std::size_t>(q) * m_pop.stride() + face);
                     });
        // the coupling's stencils reach ghosts only across split axes (an
        // unsplit axis wraps onto this rank's own nodes): their velocities
        bool split_only = true;
        for (int d = 0; d < 3; ++d)
          split_only &= o[d] == 0 || m_grid.dims()[d] > 1;
        if (!split_only)
          continue;
        visit_region(m_origin, m_n, o, false, [&](const Vec3i& g, int) {
          const std::size_t ghost =
              index(g[0] - m_origin[0] + 1, g[1] - m_origin[1] + 1, g[2] - m_origin[2] + 1);
          if (m_halo.ghost_slot.empty())
            m_halo.ghost_slot.assign(m_pop.stride(), HaloPlan::no_ghost_slot);
          if (m_halo.ghost_slot[ghost] == HaloPlan::no_ghost_slot) {
            m_halo.ghost_slot[ghost] = static_cast<std::uint32_t>(m_halo.ghost_velocity.size());
            m_halo.ghost_velocity.emplace_back(Vec3::Zero());
            m_halo.ghost_node.push_back(ghost);
          }
          in.velocity_slot.push_back(m_halo.ghost_slot[ghost]);
        });
        visit_region(m_grid.lower(c_behind), m_grid.extent(c_behind), o, false,
                     [&](const Vec3i& g, int) { out.velocity_face.push_back(domain_index(g)); });
      }
  m_halo.local = merge_place_runs(std::move(pairs));
  connect_shared_halo();
}

int LBFluid::shared_halo_peers() const {
  require_flagged("the shared-memory halo peers");
  int n = 0;
  for (const HaloPeer& p : m_halo.peers)
    n += p.shared ? 1 : 0;
  return n;
}

void LBFluid::connect_shared_halo() {
  m_halo.segment = SharedSegment();
  if (m_halo.peers.empty())
    return;
  // this rank's segment: per neighbour two buffers (update parity) of as
  // many values as the larger of its two lists (a fill sends the faces, a
  // fold the ghosts), whole cache lines each, in double (a float fits)
  std::size_t bytes = 0;
  auto reserve = [&](HaloPeer::Buffers& b, std::size_t values) {
    b.capacity = (values + 7) / 8 * 8;
    b.offset = SharedSegment::header + bytes;
    bytes += 2 * b.capacity * sizeof(double);
  };
  for (HaloPeer& p : m_halo.peers) {
    reserve(p.own_halo, std::max(p.face.size(), p.ghost.size()));
    reserve(p.own_velocity, 1 + 4 * p.velocity_face.size());
  }
  m_halo.coupling_rounds = 0;
  const char* setting = std::getenv("PYOIF_HALO_SHARED");
  const bool wanted = !(setting && std::string(setting) == "0");
  if (wanted)
    m_halo.segment = SharedSegment(bytes);
  // the offer to each neighbour: pid, descriptor, size, cookie, the offsets
  // of its buffers (all zero: no segment); then whether each mapped the other's
  const bool offered = m_halo.segment.data() != nullptr;
  constexpr int fields = 8;
  auto exchange = [&](auto make_send, int tag) {
    std::vector<std::uint64_t> send(fields * m_halo.peers.size()),
        recv(fields * m_halo.peers.size());
    NeighbourExchange round(m_grid.comm(), tag);
    for (std::size_t k = 0; k < m_halo.peers.size(); ++k)
      round.receive(m_halo.peers[k].rank, recv.data() + fields * k, fields);
    for (std::size_t k = 0; k < m_halo.peers.size(); ++k) {
      make_send(m_halo.peers[k], send.data() + fields * k);
      round.send(m_halo.peers[k].rank, send.data() + fields * k, fields);
    }
    round.wait();
    return recv;
  };
  const std::vector<std::uint64_t> offers = exchange(
      [&](const HaloPeer& p, std::uint64_t* out) {
        out[0] = offered ? static_cast<std::uint64_t>(getpid()) : 0;
        out[1] = offered ? static_cast<std::uint64_t>(m_halo.segment.fd()) : 0;
        out[2] = offered ? m_halo.segment.size() - SharedSegment::header : 0;
        out[3] = offered ? m_halo.segment.cookie() : 0;
        out[4] = p.own_halo.offset;
        out[5] = p.own_halo.capacity;
        out[6] = p.own_velocity.offset;
        out[7] = p.own_velocity.capacity;
      },
      74);
  for (std::size_t k = 0; k < m_halo.peers.size(); ++k) {
    HaloPeer& p = m_halo.peers[k];
    const std::uint64_t* o = offers.data() + fields * k;
    // (the neighbour's lists for this rank are as long as this rank's for it)
    if (offered && o[0] != 0 && o[5] == p.own_halo.capacity)
      p.shared = PeerSegment(static_cast<long>(o[0]), static_cast<int>(o[1]),
                             static_cast<std::size_t>(o[2]), o[3]);
    p.peer_halo = {static_cast<std::size_t>(o[4]), static_cast<std::size_t>(o[5])};
    p.peer_velocity = {static_cast<std::size_t>(o[6]), static_cast<std::size_t>(o[7])};
  }
  const std::vector<std::uint64_t> mapped = exchange(
      [&](const HaloPeer& p, std::uint64_t* out) {
        std::fill(out, out + fields, std::uint64_t{0});
        out[0] = p.shared ? 1 : 0;
      },
      75);
  bool any = false;
  for (std::size_t k = 0; k < m_halo.peers.size(); ++k) {
    HaloPeer& p = m_halo.peers[k];
    if (!(p.shared && mapped[fields * k] == 1))
      p.shared = PeerSegment(); // one way only: both use messages
    any |= static_cast<bool>(p.shared);
  }
  m_halo.segment.close_fd(); // every neighbour has tried to open it
  if (!any)
    m_halo.segment = SharedSegment();
}

template <typename Real> void LBFluid::pack_shared_halo(const Real* f, bool fill_ghosts) const {
  const std::size_t parity = m_updates & 1u;
  for (const HaloPeer& p : m_halo.peers) {
    if (!p.shared)
      continue;
    const std::vector<std::size_t>& out = fill_ghosts ? p.face : p.ghost;
    Real* to = p.own_halo.at<Real>(m_halo.segment.data(), parity);
    for (std::size_t i = 0; i < out.size(); ++i)
      to[i] = f[out[i]];
  }
  // the values before the agreement that tells the neighbours they are there
  std::atomic_thread_fence(std::memory_order_release);
}

std::size_t LBFluid::halo_bytes() const {
  require_flagged("the halo size");
  std::size_t n = 0;
  for (const HaloPeer& p : m_halo.peers)
    n += p.face.size(); // sent by a fill, as many as the ghosts folded back
  return n * m_pop.value_bytes();
}

namespace {
/** The halo buffer of the stored type: populations travel as they are
 *  stored (MPI_FLOAT in single precision, half the bytes). */
template <typename Real>
std::vector<Real>& halo_buffer(std::vector<double>& as_double, std::vector<float>& as_float) {
  if constexpr (std::is_same_v<Real, float>)
    return as_float;
  else
    return as_double;
}
/** Stores received halo values at their places: a face plane's
 *  populations, across the split axis a lattice row apart, each on its own
 *  cache line and a page every few places, which the hardware prefetchers
 *  do not follow. The line `ahead` places on is requested while one is
 *  stored (64: about the latency of the last-level cache at a nanosecond or
 *  two per place). Measured at 2 ranks in the bifurcation scene (46 kB per
 *  update): 0.0145 -> 0.0106 ms per update. The same requests in the
 *  packing of the sends changed nothing (0.021 ms either way). */
template <typename Real>
void scatter_places(const Real* in, const std::vector<std::size_t>& places, Real* f) {
  constexpr std::size_t ahead = 64;
  const std::size_t n = places.size();
  const std::size_t* at = places.data();
  for (std::size_t i = 0; i < n; ++i) {
    if (i + ahead < n)
      __builtin_prefetch(f + at[i + ahead], 1, 3);
    f[at[i]] = in[i];
  }
}
} // namespace

template <typename Real> void LBFluid::exchange_remote(Real* f, bool fill_ghosts) const {
  if (m_halo.peers.empty())
    return;
  // fill: faces out, ghosts in; fold: ghosts out, faces in (a copy, as in
  // the periodic case: the face slot receives the population the
  // neighbour's node pushed across, its only value in this update)
  NeighbourExchange round(m_grid.comm(), 71);
  for (const HaloPeer& p : m_halo.peers) {
    if (p.shared)
      continue;
    const std::vector<std::size_t>& in = fill_ghosts ? p.ghost : p.face;
    std::vector<Real>& recv = halo_buffer<Real>(p.recv, p.recv_single);
    recv.resize(in.size());
    round.receive(p.rank, recv.data(), recv.size());
  }
  for (const HaloPeer& p : m_halo.peers) {
    if (p.shared)
      continue;
    const std::vector<std::size_t>& out = fill_ghosts ? p.face : p.ghost;
    std::vector<Real>& send = halo_buffer<Real>(p.send, p.send_single);
    send.resize(out.size());
    for (std::size_t i = 0; i < out.size(); ++i)
      send[i] = f[out[i]];
    round.send(p.rank, send.data(), send.size());
  }
  // (the bounce-back, which touches other places, was tried here, between
  // the sends and the wait, 27 Nov 2026: the wait did not shorten, as the
  // transfer moves only inside MPI calls, and the stores after it slowed)
  // the neighbours on this machine packed theirs before the agreement
  // (pack_shared_halo), which every rank has passed: read in place, while
  // the messages travel. A neighbour packs into this buffer again two
  // updates on, after the next agreement, which this rank joins only when
  // done here: no other wait is needed.
  std::atomic_thread_fence(std::memory_order_acquire);
  const std::size_t parity = m_updates & 1u;
  for (const HaloPeer& p : m_halo.peers)
    if (p.shared)
      scatter_places(p.peer_halo.at<const Real>(p.shared.data(), parity),
                     fill_ghosts ? p.ghost : p.face, f);
  round.wait();
  for (const HaloPeer& p : m_halo.peers)
    if (!p.shared)
      scatter_places(halo_buffer<Real>(p.recv, p.recv_single).data(),
                     fill_ghosts ? p.ghost : p.face, f);
}

void LBFluid::refresh_ghost_velocities() {
  require_flagged("the fluid velocity at a point");
  if (m_halo.peers.empty() || m_halo.ghost_velocity_version == m_state_version)
    return;
  const auto start = std::chrono::steady_clock::now();
  // (the peers' halo buffers: this exchange never overlaps a halo step)
  NeighbourExchange round(m_grid.comm(), 72);
  for (const HaloPeer& peer : m_halo.peers) {
    peer.recv.resize(3 * peer.velocity_slot.size());
    round.receive(peer.rank, peer.recv.data(), peer.recv.size());
  }
  for (const HaloPeer& peer : m_halo.peers) {
    peer.send.clear();
    for (const std::size_t n : peer.velocity_face) {
      const Vec3 u = velocity_at_index(n);
      peer.send.insert(peer.send.end(), {u[0], u[1], u[2]});
    }
    round.send(peer.rank, peer.send.data(), peer.send.size());
  }
  round.wait();
  for (const HaloPeer& peer : m_halo.peers)
    for (std::size_t i = 0; i < peer.velocity_slot.size(); ++i)
      m_halo.ghost_velocity[peer.velocity_slot[i]] =
          Vec3(peer.recv[3 * i], peer.recv[3 * i + 1], peer.recv[3 * i + 2]);
  m_halo.ghost_velocity_version = m_state_version;
  m_coupling_exchange_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void LBFluid::exchange_coupling_ghosts(CouplingNodes& list, bool with_values) {
  list.ghosts_pending = false;
  if (m_halo.peers.empty())
    return;
  const auto start = std::chrono::steady_clock::now();
  const std::uint64_t* needed = list.needed.data();
  const std::uint32_t* entry = list.compact.data();
  auto* state = list.node_coupling.data();
  auto listed = [needed](std::size_t n) { return ((needed[n >> 6] >> (n & 63)) & 1) != 0; };
  // per node sent: its place in the peer's velocity list, then the velocity
  // (4 doubles; the place is exact in a double). A neighbour on this machine
  // reads them from this rank's segment (a count first), told by an empty
  // message that they are there; this rank writes that buffer again two
  // rounds on, after the neighbour's empty message of the next round, which
  // it sends only after reading.
  constexpr std::size_t per = 4;
  const std::size_t parity = m_halo.coupling_rounds++ & 1u;
  auto pack = [&](const HaloPeer& peer, double* out) {
    std::size_t k = 0;
    if (with_values)
      for (std::size_t i = 0; i < peer.velocity_face.size(); ++i) {
        const std::size_t n = peer.velocity_face[i];
        if (!listed(n))
          continue;
        const Vec3& u = state[entry[n]].velocity;
        out[k] = static_cast<double>(i);
        out[k + 1] = u[0];
        out[k + 2] = u[1];
        out[k + 3] = u[2];
        k += per;
      }
    return k;
  };
  NeighbourExchange round(m_grid.comm(), 73);
  for (const HaloPeer& peer : m_halo.peers) {
    peer.recv.resize(peer.shared ? 0 : per * peer.velocity_slot.size());
    round.receive(peer.rank, peer.recv.data(), peer.recv.size()); // k-th receive: m_halo.peers[k]
  }
  for (const HaloPeer& peer : m_halo.peers) {
    if (peer.shared) {
      double* out = peer.own_velocity.at<double>(m_halo.segment.data(), parity);
      out[0] = static_cast<double>(pack(peer, out + 1));
      std::atomic_thread_fence(std::memory_order_release);
      peer.send.clear(); // the empty message
    } else {
      peer.send.resize(per * peer.velocity_face.size());
      peer.send.resize(pack(peer, peer.send.data()));
    }
    round.send(peer.rank, peer.send.data(), peer.send.size());
  }
  round.wait();
  std::atomic_thread_fence(std::memory_order_acquire);
  if (with_values)
    for (std::size_t k = 0; k < m_halo.peers.size(); ++k) {
      const HaloPeer& peer = m_halo.peers[k];
      const double* in = peer.recv.data();
      int received = 0;
      if (peer.shared) {
        in = peer.peer_velocity.at<const double>(peer.shared.data(), parity);
        received = static_cast<int>(in[0]);
        ++in;
      } else {
        received = static_cast<int>(round.received(k));
      }
      for (std::size_t j = 0; j + per <= static_cast<std::size_t>(received); j += per) {
        const std::size_t n =
            m_halo.ghost_node[peer.velocity_slot[static_cast<std::size_t>(in[j])]];
        if (is_fluid_ghost(n) && listed(n))
          state[entry[n]].velocity = Vec3(in[j + 1], in[j + 2], in[j + 3]);
      }
    }
  m_coupling_exchange_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template <typename Real> void LBFluid::halo_exchange(Real* f, bool fill_ghosts) const {
  apply_place_runs(f, m_halo.local, fill_ghosts);
  if (m_halo.peers.empty())
    return;
  const auto start = std::chrono::steady_clock::now();
  exchange_remote(f, fill_ghosts);
  m_halo_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

template void LBFluid::pack_shared_halo<float>(const float*, bool) const;
template void LBFluid::pack_shared_halo<double>(const double*, bool) const;
template void LBFluid::halo_exchange<float>(float*, bool) const;
template void LBFluid::halo_exchange<double>(double*, bool) const;

} // namespace pyoif::lb
