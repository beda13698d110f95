// Missed cycles are skipped and counted, never replayed in a burst: the loop's clock returns five
// periods late once, mid-session, and the loop must carry on from the newest deadline passed, on
// the same grid, with the late cycle flagged in its sample and in a fault record.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <vector>

#include "daemon_test_support.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"

namespace furuta::daemon {
namespace {

namespace fs = std::filesystem;

// A virtual clock that once oversleeps: the first sleep for a deadline at or after `at_ns` returns
// `late_ns` after it, as a loop thread kept off the CPU would. Records every sleep. Used by the
// loop thread only.
class OversleepingClock final : public bridge::Clock {
 public:
  OversleepingClock(bridge::VirtualClock& inner, std::int64_t at_ns, std::int64_t late_ns)
      : inner_(inner), at_ns_(at_ns), late_ns_(late_ns) {
    sleeps_.reserve(1 << 12);
  }
  std::int64_t now_ns() const override { return inner_.now_ns(); }
  void sleep_until_ns(std::int64_t deadline_ns) override {
    Sleep s{deadline_ns, inner_.now_ns(), 0};
    inner_.sleep_until_ns(deadline_ns);
    if (!overslept_ && deadline_ns >= at_ns_) {
      inner_.advance_ns(late_ns_);
      overslept_ = true;
    }
    s.woke_ns = inner_.now_ns();
    sleeps_.push_back(s);
  }

  struct Sleep {
    std::int64_t deadline_ns;
    std::int64_t called_ns;  // when the loop asked to sleep
    std::int64_t woke_ns;
  };
  const std::vector<Sleep>& sleeps() const { return sleeps_; }

 private:
  bridge::VirtualClock& inner_;
  std::int64_t at_ns_;
  std::int64_t late_ns_;
  bool overslept_ = false;
  std::vector<Sleep> sleeps_;
};

TEST(MissedCycles, AreSkippedAndCountedNeverReplayedInABurst) {
  testing::TempDir dir("furuta-missed");
  const config::RigConfig config = testing::quiet_rig();
  RigConnection io = connect_rig(config, {BackendChoice::simulated, {}, /*virtual_time=*/true});
  DaemonSettings settings = daemon_settings_from_config(config);
  settings.recorder.logs_dir = dir.path();
  settings.recorder.motor_device = bridge::format_trace_device_line(io.motor->device_info());
  settings.recorder.encoder_device = bridge::format_trace_device_line(io.encoder->device_info());
  settings.loop.wait_when_queue_full = true;
  settings.loop.rest_wait_s = 5.0;
  const std::int64_t period = settings.loop.period_ns;
  constexpr std::int64_t kMissed = 5;
  constexpr std::int64_t kExtraLateNs = 3'000'000;  // and then some: the wake-up is 3 ms late
  // The session starts after the one-second rest check; two seconds in, it is well under way.
  OversleepingClock clock(static_cast<bridge::VirtualClock&>(*io.clock), 2'000'000'000,
                          kMissed * period + kExtraLateNs);

  lcm::LCM lcm("memq://");
  std::optional<fs::path> log_path;
  std::int64_t overruns = 0;
  std::int64_t cycles = 0;
  double max_latency_us = 0;
  {
    Daemon daemon(settings, *io.motor_link, *io.encoder_link, clock, lcm);
    const auto reply = daemon.handle_command(testing::start_command("bang_bang", 0.3, 4.0));
    ASSERT_TRUE(reply.request_accepted) << reply.request_reason;
    daemon.loop().exit_when_idle();
    daemon.start();
    daemon.wait();
    EXPECT_EQ(daemon.loop().counters().last_stop.load(), StopReason::duration_reached);
    overruns = daemon.loop().counters().overruns.load();
    cycles = daemon.loop().counters().cycles.load();
    max_latency_us = daemon.loop().wake_latency().max_us();
    log_path = daemon.recorder().last_log();
  }

  // Counted: five cycles missed; the latency figures show the whole lateness, 5 periods + 3 ms.
  EXPECT_EQ(overruns, kMissed);
  EXPECT_EQ(max_latency_us, static_cast<double>(kMissed * period + kExtraLateNs) / 1000.0);

  // Never replayed: every sleep was for a deadline still ahead (a burst would ask for deadlines
  // already past), each deadline one period after the one before except once, where the five
  // missed ones were skipped, and all of them on the grid of the first.
  const auto& sleeps = clock.sleeps();
  ASSERT_GT(sleeps.size(), 100u);
  EXPECT_EQ(static_cast<std::int64_t>(sleeps.size()), cycles);
  int skips = 0;
  for (std::size_t i = 0; i < sleeps.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_GT(sleeps[i].deadline_ns, sleeps[i].called_ns);
    EXPECT_EQ((sleeps[i].deadline_ns - sleeps[0].deadline_ns) % period, 0);
    if (i == 0) continue;
    const std::int64_t step = sleeps[i].deadline_ns - sleeps[i - 1].deadline_ns;
    if (step == (kMissed + 1) * period) {
      ++skips;
      // The late wake-up was the sleep before this one.
      EXPECT_EQ(sleeps[i - 1].woke_ns - sleeps[i - 1].deadline_ns, kMissed * period + kExtraLateNs);
    } else {
      EXPECT_EQ(step, period);
    }
  }
  EXPECT_EQ(skips, 1);

  // In the log: consecutive samples, one flagged late, its deadline six periods after the one
  // before, the overrun count carried on from there; one fault record for it; the reports of the
  // missed cycles arrive in the late cycle, none lost.
  ASSERT_TRUE(log_path.has_value());
  const session_log::SessionLog log = session_log::load_session_log(*log_path);
  ASSERT_TRUE(log.complete());
  EXPECT_TRUE(log.missing_sequence_numbers().empty());
  const std::size_t expected_samples = static_cast<std::size_t>(4'000'000'000 / period) - kMissed;
  ASSERT_EQ(log.samples.size(), expected_samples);
  std::optional<std::size_t> late;
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    const auto& s = log.samples[i];
    SCOPED_TRACE(i);
    EXPECT_EQ(s.seq, static_cast<std::int64_t>(i));
    EXPECT_EQ(s.motor_lost_reports, 0);
    EXPECT_EQ(s.encoder_lost_reports, 0);
    if (s.flags & kSampleOverrun) {
      EXPECT_FALSE(late.has_value()) << "more than one late sample";
      late = i;
    }
    EXPECT_EQ(s.overruns, late ? kMissed : 0);
    if (i > 0) {
      const std::int64_t step = s.monotonic_ns - log.samples[i - 1].monotonic_ns;
      EXPECT_EQ(step, late == i ? (kMissed + 1) * period : period);
    }
  }
  ASSERT_TRUE(late.has_value());
  const auto& late_sample = log.samples[*late];
  // Two 1065 reports a period: those of the five missed cycles and of the late one, in one drain.
  EXPECT_GE(late_sample.n_motor_reports, 2 * (kMissed + 1) - 1);
  EXPECT_GE(late_sample.n_encoder_reports, 2 * (kMissed + 1) - 1);
  EXPECT_EQ(late_sample.flags &
                (kSampleMotorStale | kSampleEncoderStale | kSampleMotorLost | kSampleEncoderLost),
            0);
  int overrun_faults = 0;
  for (const auto& f : log.faults) {
    if (f.reason != "overrun") continue;
    ++overrun_faults;
    EXPECT_FALSE(f.fatal);
    EXPECT_EQ(f.seq, late_sample.seq);
    EXPECT_EQ(f.monotonic_ns, late_sample.monotonic_ns);
  }
  EXPECT_EQ(overrun_faults, 1);
  EXPECT_EQ(log.end->end_reason, "duration_reached");
}

}  // namespace
}  // namespace furuta::daemon
