// Memory that ranks on the same machine read from each other directly: the
// lattice's halo goes through it instead of MPI messages (LBFluid,
// lb_halo.cpp), which saves the transfer's copies and its handshake.
//
// A segment is an anonymous memory file (memfd_create) mapped by its owner;
// another process maps it read-only through /proc/<pid>/fd/<fd>, which the
// owner keeps open until the others have tried. Nothing about it is
// collective: a process unmaps what it mapped whenever it likes, and the
// memory lives until the last mapping is gone (so an LBFluid may be
// destroyed on one rank before another, as Python's garbage collection
// does). Whether two ranks share one machine is not assumed from MPI: the
// owner writes a random cookie at the start, told to the others by MPI,
// and a mapping whose cookie differs (another machine, another process of
// that pid) is dropped, and the messages are used.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <utility>

namespace pyoif {

/** Unmaps a mapping of `size` bytes (the deleter of SharedMapping). */
struct Unmap {
  std::size_t size = 0;
  void operator()(unsigned char* p) const noexcept;
};
/** A mapping of a segment, unmapped when the last owner lets go of it
 *  (move-only; null when none). */
using SharedMapping = std::unique_ptr<unsigned char, Unmap>;

/** This process's segment: `bytes` of zeroed memory after a header that
 *  holds the cookie. Empty (data() null) when it could not be made. */
class SharedSegment {
public:
  static constexpr std::size_t header = 64;
  SharedSegment() = default;
  explicit SharedSegment(std::size_t bytes);
  ~SharedSegment() { close_fd(); }
  // (the descriptor changes hands with the mapping)
  SharedSegment(SharedSegment&& other) noexcept
      : m_data(std::move(other.m_data)), m_fd(std::exchange(other.m_fd, -1)),
        m_cookie(other.m_cookie) {}
  SharedSegment& operator=(SharedSegment&& other) noexcept {
    if (this != &other) {
      close_fd();
      m_data = std::move(other.m_data);
      m_fd = std::exchange(other.m_fd, -1);
      m_cookie = other.m_cookie;
    }
    return *this;
  }

  unsigned char* data() const { return m_data.get(); }
  std::size_t size() const { return m_data ? m_data.get_deleter().size : 0; }
  int fd() const { return m_fd; }
  std::uint64_t cookie() const { return m_cookie; }
  /** Closes the descriptor others open it through (the mapping stays). */
  void close_fd();

private:
  SharedMapping m_data;
  int m_fd = -1;
  std::uint64_t m_cookie = 0;
};

/** Another process's segment, mapped read-only; empty when it could not be
 *  mapped or its cookie differs. */
class PeerSegment {
public:
  PeerSegment() = default;
  PeerSegment(long pid, int fd, std::size_t bytes, std::uint64_t cookie);

  const unsigned char* data() const { return m_data.get(); }
  explicit operator bool() const { return m_data != nullptr; }

private:
  SharedMapping m_data; ///< mapped read-only
};

} // namespace pyoif
