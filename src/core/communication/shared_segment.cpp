#include "communication/shared_segment.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <random>
#include <string>
#include <utility>

namespace pyoif {

SharedSegment::SharedSegment(std::size_t bytes) {
  const std::size_t total = header + bytes;
  const int fd = static_cast<int>(memfd_create("pyoif-halo", MFD_CLOEXEC));
  if (fd < 0)
    return;
  if (ftruncate(fd, static_cast<off_t>(total)) != 0) {
    close(fd);
    return;
  }
  void* p = mmap(nullptr, total, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  if (p == MAP_FAILED) {
    close(fd);
    return;
  }
  m_data = SharedMapping(static_cast<unsigned char*>(p), Unmap{total});
  m_fd = fd;
  std::random_device entropy;
  m_cookie = (static_cast<std::uint64_t>(entropy()) << 32) ^ entropy() ^
             static_cast<std::uint64_t>(getpid());
  // the pages are reserved now: a machine short of memory fails here, where
  // it is caught, not with a signal at the first halo
  std::memset(data(), 0, total);
  std::memcpy(data(), &m_cookie, sizeof m_cookie);
}

void Unmap::operator()(unsigned char* p) const noexcept {
  munmap(p, size);
}

void SharedSegment::close_fd() {
  if (m_fd >= 0)
    close(m_fd);
  m_fd = -1;
}

PeerSegment::PeerSegment(long pid, int fd, std::size_t bytes, std::uint64_t cookie) {
  const std::string path = "/proc/" + std::to_string(pid) + "/fd/" + std::to_string(fd);
  const int mine = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (mine < 0)
    return;
  const std::size_t total = SharedSegment::header + bytes;
  // a file of another size is not the segment offered
  const off_t length = lseek(mine, 0, SEEK_END);
  void* p = length == static_cast<off_t>(total)
                ? mmap(nullptr, total, PROT_READ, MAP_SHARED, mine, 0)
                : MAP_FAILED;
  close(mine);
  if (p == MAP_FAILED)
    return;
  std::uint64_t found = 0;
  std::memcpy(&found, p, sizeof found);
  if (found != cookie) {
    munmap(p, total);
    return;
  }
  m_data = SharedMapping(static_cast<unsigned char*>(p), Unmap{total});
}

} // namespace pyoif
