// Wall-clock laps for System::run_timings: lap(slot) adds the time since the
// last lap (or since construction) to slot. A disabled clock reads no time.
#pragma once

#include <chrono>

namespace pyoif {

class PhaseClock {
public:
  explicit PhaseClock(bool enabled) : m_enabled(enabled) {
    if (m_enabled)
      m_last = Clock::now();
  }
  void lap(double& slot) {
    if (!m_enabled)
      return;
    const Clock::time_point now = Clock::now();
    slot += std::chrono::duration<double>(now - m_last).count();
    m_last = now;
  }

private:
  using Clock = std::chrono::steady_clock;
  bool m_enabled;
  Clock::time_point m_last{};
};

} // namespace pyoif
