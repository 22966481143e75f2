// The shared-memory halo's segments (communication/shared_segment.hpp):
// another process maps a rank's segment through /proc/<pid>/fd and sees
// what the owner wrote; a wrong cookie, size or descriptor leaves the
// mapping empty (the pair then uses MPI messages), never a wrong mapping.
#include "communication/shared_segment.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>

using namespace pyoif;

namespace {

constexpr std::size_t bytes = 3 * 4096 + 40; // not a whole page: the size is checked exactly

void write_pattern(SharedSegment& s) {
  auto* v = reinterpret_cast<double*>(s.data() + SharedSegment::header);
  for (std::size_t i = 0; i < bytes / sizeof(double); ++i)
    v[i] = 0.5 * static_cast<double>(i) - 7.0;
}

bool pattern_seen(const unsigned char* data) {
  const auto* v = reinterpret_cast<const double*>(data + SharedSegment::header);
  for (std::size_t i = 0; i < bytes / sizeof(double); ++i)
    if (v[i] != 0.5 * static_cast<double>(i) - 7.0)
      return false;
  return true;
}

} // namespace

TEST(SharedSegment, MadeZeroedWithItsCookie) {
  SharedSegment s(bytes);
  ASSERT_NE(s.data(), nullptr);
  EXPECT_EQ(s.size(), SharedSegment::header + bytes);
  EXPECT_GE(s.fd(), 0);
  std::uint64_t cookie = 0;
  std::memcpy(&cookie, s.data(), sizeof cookie);
  EXPECT_EQ(cookie, s.cookie());
  for (std::size_t i = SharedSegment::header; i < s.size(); ++i)
    ASSERT_EQ(s.data()[i], 0u);
  SharedSegment moved(std::move(s));
  EXPECT_EQ(s.data(), nullptr);
  EXPECT_NE(moved.data(), nullptr);
}

TEST(SharedSegment, AnotherProcessReadsWhatTheOwnerWrote) {
  SharedSegment s(bytes);
  ASSERT_NE(s.data(), nullptr);
  write_pattern(s);
  const long owner = static_cast<long>(getpid());
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // a process of its own opens the owner's descriptor through /proc
    PeerSegment peer(owner, s.fd(), bytes, s.cookie());
    _exit(peer && pattern_seen(peer.data()) ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "the other process did not see the segment's values";
}

TEST(SharedSegment, MappingStaysAfterTheOwnerClosesItsDescriptor) {
  SharedSegment s(bytes);
  write_pattern(s);
  PeerSegment peer(static_cast<long>(getpid()), s.fd(), bytes, s.cookie());
  ASSERT_TRUE(peer);
  s.close_fd();
  EXPECT_EQ(s.fd(), -1);
  EXPECT_TRUE(pattern_seen(peer.data()));
  // the owner's later writes are seen in place
  reinterpret_cast<double*>(s.data() + SharedSegment::header)[5] = 42.0;
  EXPECT_EQ(reinterpret_cast<const double*>(peer.data() + SharedSegment::header)[5], 42.0);
}

TEST(SharedSegment, WrongCookieSizeOrDescriptorGivesNoMapping) {
  SharedSegment s(bytes);
  const long me = static_cast<long>(getpid());
  EXPECT_FALSE(PeerSegment(me, s.fd(), bytes, s.cookie() ^ 1u)); // another machine's segment
  EXPECT_FALSE(PeerSegment(me, s.fd(), bytes + 8, s.cookie()));  // not the size offered
  EXPECT_FALSE(PeerSegment(me, 1 << 20, bytes, s.cookie()));     // no such descriptor
  EXPECT_FALSE(PeerSegment(-1, s.fd(), bytes, s.cookie()));      // no such process
  EXPECT_TRUE(PeerSegment(me, s.fd(), bytes, s.cookie()));
}
