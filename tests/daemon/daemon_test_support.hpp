#pragma once
// What the daemon's virtual-time tests share: a temporary directory, the shipped configuration,
// board-link wrappers that act from the loop thread, and readers of what a session
// log says was written to the motor.
//
// Faults are injected from the loop thread itself (a wrapper's drain runs there), because the
// VirtualClock and the simulated rig's physics are single-threaded: the test thread must not touch
// them while the loop runs.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/board_link.hpp"
#include "furuta/daemon/control_loop.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/rig_command_t.hpp"
#include "furuta/session_log/session_log.hpp"
#include "temp_dir.hpp"

namespace furuta::daemon::testing {

using furuta::testing::TempDir;

namespace fs = std::filesystem;

// The shipped configuration. Its simulated rig has no noise: the pendulum hangs exactly still, so
// the rest check passes after its one second and every session starts on the same cycle.
inline config::RigConfig quiet_rig() {
  return config::load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
}

inline furuta::rig_command_t start_command(const std::string& profile, double amplitude,
                                           double duration_s, const std::string& label = "test") {
  furuta::rig_command_t c{};
  c.request_id = 11;
  c.kind = furuta::rig_command_t::KIND_START_SESSION;
  c.profile = profile;
  c.amplitude_duty = amplitude;
  c.duration_s = duration_s;
  c.label = label;
  c.seed = 3;
  return c;
}

inline furuta::rig_command_t simple_command(std::int8_t kind, std::int64_t request_id = 12) {
  furuta::rig_command_t c{};
  c.request_id = request_id;
  c.kind = kind;
  return c;
}

// Duty magnitude of a 1065 output report as written (raw 0..255; 0 is the zero command), or -1000
// when the bytes are not a 1065 output report.
inline int duty_raw_of(std::span<const std::uint8_t> bytes) {
  bridge::MotorOutput1065 out;
  if (bridge::decode_output_1065(bytes, out) != bridge::CodecStatus::ok) return -1000;
  return out.duty_raw;
}

// The last attempt to write the 1065 that the log recorded, successful (KIND_OUTPUT) or not
// (KIND_ERROR: the write failed, e.g. the board was unplugged).
struct LoggedMotorWrite {
  std::int8_t kind = -1;
  std::string status;
  int duty_raw = -1000;
};
inline std::optional<LoggedMotorWrite> last_logged_motor_write(const session_log::SessionLog& log) {
  std::optional<LoggedMotorWrite> last;
  for (const auto& r : log.usb_reports) {
    if (r.board != furuta::rig_usb_report_t::BOARD_MOTOR) continue;
    if (r.kind != furuta::rig_usb_report_t::KIND_OUTPUT &&
        r.kind != furuta::rig_usb_report_t::KIND_ERROR) {
      continue;
    }
    last = LoggedMotorWrite{r.kind, r.status, duty_raw_of(r.bytes)};
  }
  return last;
}

// Wraps a board link: runs an action on the loop thread before the drain of a chosen cycle, counts
// cycles, and keeps every report written with the loop's state at that moment. For the safety
// tests (it allocates as it records).
class HookedLink final : public BoardLink {
 public:
  explicit HookedLink(BoardLink& inner) : inner_(inner) {}

  // The loop's counters, to tell cycles that run a session from idle ones. Set before the loop
  // thread starts.
  void watch(const LoopCounters& counters) { counters_ = &counters; }
  // Before the n-th drain (from 1) made while a session runs: `action`, on the loop thread.
  void at_running_cycle(int n, std::function<void()> action) {
    running_actions_.push_back({n, std::move(action)});
  }
  // Before the n-th drain (from 1) whatever the state.
  void at_cycle(int n, std::function<void()> action) { actions_.push_back({n, std::move(action)}); }
  // Throws instead of draining at the n-th running cycle (the action, if any, runs first).
  void throw_at_running_cycle(int n) { throw_running_cycle_ = n; }

  bridge::TransportStatus drain(BoardReports& out) override {
    ++cycles_;
    if (running()) ++running_cycles_;
    for (auto& [n, action] : actions_) {
      if (action && n == cycles_) std::exchange(action, nullptr)();
    }
    for (auto& [n, action] : running_actions_) {
      if (action && n == running_cycles_) std::exchange(action, nullptr)();
    }
    if (throw_running_cycle_ > 0 && running_cycles_ == throw_running_cycle_) {
      throw_running_cycle_ = 0;
      events_.push_back({Event::Kind::threw, 0, cycles_, running_cycles_, true});
      throw std::runtime_error("injected failure in drain");
    }
    return inner_.drain(out);
  }
  bridge::TransportStatus write(std::span<const std::uint8_t> report) override {
    events_.push_back(
        {Event::Kind::write, duty_raw_of(report), cycles_, running_cycles_, running()});
    return inner_.write(report);
  }
  bridge::TransportStatus reconnect() override { return inner_.reconnect(); }
  const bridge::DeviceInfo& device_info() const noexcept override { return inner_.device_info(); }

  // Read after the loop thread has been joined.
  struct Event {
    enum class Kind { write, threw };
    Kind kind;
    int duty_raw;
    int cycle;          // cycles drained before it
    int running_cycle;  // of which with a session running
    bool session_running;
  };
  const std::vector<Event>& events() const { return events_; }
  int running_cycles() const { return running_cycles_; }

 private:
  bool running() const { return counters_ && counters_->state.load() == LoopState::running; }

  BoardLink& inner_;
  const LoopCounters* counters_ = nullptr;
  int cycles_ = 0;
  int running_cycles_ = 0;
  std::vector<std::pair<int, std::function<void()>>> actions_;
  std::vector<std::pair<int, std::function<void()>>> running_actions_;
  int throw_running_cycle_ = 0;
  std::vector<Event> events_;
};

// What the motor link's record says about the end of the session: the last write made while the
// session still ran must be the zero command, nothing written after it may be anything else, and
// the session must have driven the motor before (else the test proves nothing).
struct WriteSummary {
  bool drove_motor = false;            // a non-zero duty was written while running
  int last_running_duty_raw = -1;      // the last write while the session ran
  int nonzero_after_last_running = 0;  // writes after it that were not zero
  int last_running_write_cycle = -1;
  std::ptrdiff_t last_running_index = -1;  // position in events()
};
inline WriteSummary summarize_writes(const std::vector<HookedLink::Event>& events) {
  WriteSummary s;
  for (std::size_t i = 0; i < events.size(); ++i) {
    const auto& e = events[i];
    if (e.kind != HookedLink::Event::Kind::write) continue;
    if (e.session_running) {
      if (e.duty_raw != 0) s.drove_motor = true;
      s.last_running_duty_raw = e.duty_raw;
      s.last_running_write_cycle = e.running_cycle;
      s.last_running_index = static_cast<std::ptrdiff_t>(i);
      s.nonzero_after_last_running = 0;
    } else if (s.last_running_index >= 0 && e.duty_raw != 0) {
      ++s.nonzero_after_last_running;
    }
  }
  return s;
}

}  // namespace furuta::daemon::testing
