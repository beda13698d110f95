#include "furuta/firmware_bridge/clock.hpp"

#include <cerrno>
#include <ctime>

namespace furuta::bridge {

namespace {
constexpr std::int64_t kNsPerS = 1'000'000'000;
}

std::int64_t MonotonicClock::now_ns() const {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

void MonotonicClock::sleep_until_ns(std::int64_t deadline_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(deadline_ns / kNsPerS);
  ts.tv_nsec = static_cast<long>(deadline_ns % kNsPerS);
  // clock_nanosleep returns the error number instead of setting errno; with an absolute deadline a
  // retry after a signal cannot oversleep.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace furuta::bridge
