// The halo of one rank's subdomain as a plan and its buffers: which places
// of the populations the halo steps copy (the periodic images on this rank,
// `local`) and exchange with each neighbouring rank (`peers`, in an order
// both sides derive from the shared cuts), the shared-memory segment a
// neighbour on the same machine reads, and the coupling's ghost-node
// velocities. Made by LBFluid::build_halo_pairs from the flags; used by the
// halo steps and the coupling's exchanges (lb_halo.cpp), which pack and
// unpack in place by the update's parity.
#pragma once

#include "communication/shared_segment.hpp"
#include "lb/boundary_links.hpp"
#include "utils/vector.hpp"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace pyoif::lb {

/// The halo with one neighbouring rank: population places (q * stride +
/// node) of this rank's ghosts that the neighbour's faces fill (and that
/// are folded back into them), and of this rank's faces that fill the
/// neighbour's ghosts, each in the order both sides list them.
struct HaloPeer {
  int rank = -1;
  std::vector<std::size_t> ghost, face;
  /// the coupling's ghost velocities: this rank's faces the neighbour
  /// needs (nodes), and the ghost_velocity slot of each ghost it fills
  std::vector<std::size_t> velocity_face;
  std::vector<std::uint32_t> velocity_slot;
  mutable std::vector<double> send, recv;
  /// the population halo in single precision (MPI_FLOAT: half the bytes)
  mutable std::vector<float> send_single, recv_single;
  /// Two buffers of `capacity` doubles at `offset` bytes into a segment,
  /// used in turn by round parity.
  struct Buffers {
    std::size_t offset = 0, capacity = 0;
    template <typename T, typename Byte> T* at(Byte* segment, std::size_t parity) const {
      return reinterpret_cast<T*>(segment + offset + parity * capacity * sizeof(double));
    }
  };
  /// On the same machine the population halo goes through shared memory
  /// (connect_shared_halo): this rank packs what it sends into its
  /// segment (own_halo), the neighbour reads it from there, and this rank
  /// reads the neighbour's (peer_halo of `shared`); the coupling's ghost
  /// velocities likewise (a count, then 4 values per node, signalled by
  /// an empty message per round). Empty `shared`: MPI messages.
  PeerSegment shared;
  Buffers own_halo, peer_halo, own_velocity, peer_velocity;
};

struct HaloPlan {
  /// first = ghost-layer place (population included), second = its
  /// periodic image, for the halo exchange; fluid ones only
  std::vector<PlaceRun> local;
  /// rounds of exchange_coupling_ghosts so far (their buffers' parity)
  std::uint64_t coupling_rounds = 0;
  std::vector<HaloPeer> peers;
  /// this rank's halo buffers that neighbours on this machine read
  SharedSegment segment;
  std::vector<Vec3> ghost_velocity;
  /// padded index -> slot in ghost_velocity (no_ghost_slot: none), on a
  /// decomposed lattice: a dense table (4 bytes a node against the
  /// populations' 76 or more) because the coupling looks up every node it
  /// reads, at every step
  std::vector<std::uint32_t> ghost_slot;
  std::vector<std::size_t> ghost_node; ///< slot -> padded index
  static constexpr std::uint32_t no_ghost_slot = ~std::uint32_t{0};
  std::uint64_t ghost_velocity_version = ~std::uint64_t{0};
};

} // namespace pyoif::lb
