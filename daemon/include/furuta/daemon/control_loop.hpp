#pragma once
// The real-time loop: one cycle every period on absolute deadlines; each cycle drains both boards,
// builds a sample, runs the safety rules, computes the next command from the excitation and writes
// it, and hands the sample to the publisher/logger through a lock-free queue. After start-up the
// loop thread neither allocates nor locks; its only system calls are USB I/O, the sleep, and the
// queue's wake-up of the publisher.
//
// Every way out of a session (its end, a stop or e-stop, a fault, a signal, an exception) writes a
// zero, braking command as the last thing sent to the motor.

#include <array>
#include <atomic>
#include <boost/lockfree/spsc_queue.hpp>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "furuta/control/balance_law.hpp"
#include "furuta/daemon/board_link.hpp"
#include "furuta/daemon/excitation.hpp"
#include "furuta/daemon/loop_events.hpp"
#include "furuta/daemon/realtime.hpp"
#include "furuta/daemon/safety.hpp"
#include "furuta/firmware_bridge/board_roles.hpp"
#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/encoder_geometry.hpp"

namespace furuta::daemon {

// The loop's events to the publisher/logger: a lock-free single-producer queue with a wake-up, so
// the consumer sleeps until there is something to take instead of polling. notify() writes an
// eventfd (no lock, no allocation); a wake-up is never lost, since the consumer clears it before it
// drains the queue.
class EventQueue : public boost::lockfree::spsc_queue<LoopEvent> {
 public:
  explicit EventQueue(std::size_t capacity);
  ~EventQueue();
  EventQueue(const EventQueue&) = delete;
  EventQueue& operator=(const EventQueue&) = delete;

  // Producer, or whoever asks the consumer to look (a stop): wakes a wait_for.
  void notify() noexcept;
  // Consumer: returns once notified since the last return, or after `timeout`.
  void wait_for(std::chrono::nanoseconds timeout) noexcept;

 private:
  int fd_ = -1;
};

struct LoopSettings {
  std::int64_t period_ns = 16'000'000;
  SafetyLimits safety;
  bridge::EncoderGeometry arm_encoder;  // counts_per_rev of the motor shaft, gear ratio Nm*Ng
  bridge::EncoderGeometry pendulum_encoder;
  // The boards' adapters by their configuration names (bridge::make_motor_board, ...).
  std::string motor_board{bridge::kShippedMotorBoard};
  std::string encoder_board{bridge::kShippedEncoderBoard};
  int pendulum_channel = 0;
  double stop_braking_fraction = 1.0;  // braking applied with the zero command on every stop
  // The motor board's duty ramp (% of full duty per s; 0: its fastest). A gentler ramp keeps the
  // duty's edges slower than the sampling, which the identification needs (docs: identification).
  double acceleration_pct_per_s = 0.0;
  double rest_check_s = 1.0;  // the pendulum must not have moved for this long to start
  // How long a start request waits for the pendulum to come to rest before it is refused
  // (0: refused at once, as the daemon does; a one-shot run waits).
  double rest_wait_s = 0.0;
  std::int64_t rest_tolerance_counts = 2;
  // Virtual-time runs outpace the logger thread: wait for room in the queue instead of treating a
  // full queue as a stuck logger (which, in real time, stops the session with log_error).
  bool wait_when_queue_full = false;
  // After a board is lost (unplugged, USB error), how often the loop tries to reopen it. A board
  // that comes back is open again within this (plus a period) and initialised as at start-up.
  std::int64_t reconnect_interval_ns = 200'000'000;
};

// Built off the loop thread (constructing the Excitation validates and precomputes), copied in.
struct SessionRequest {
  std::array<char, kNameChars> session{};  // the log's name
  std::array<char, kNameChars> label{};
  std::int64_t request_id = 0;  // the command's, so the status can give its verdict
  // The duration (and, outside balance sessions, the duty) of the session.
  Excitation excitation;
  // A balance session: the law decides each cycle's duty from the angles; a fall ends the session
  // (StopReason::pendulum_fell).
  bool balance = false;
  control::BalanceLaw balance_law;
  // Replay: the arm's zero as the original session recorded it (the replayed traffic starts at the
  // session, after the board's absolute position was already known).
  bool has_arm_zero = false;
  std::int64_t arm_zero_counts = 0;
};

enum class LoopState : std::uint8_t { starting, idle, running, fault };

// Figures other threads may read at any time.
struct LoopCounters {
  std::atomic<std::int64_t> cycles{0};
  std::atomic<std::int64_t> overruns{0};
  std::atomic<std::int64_t> motor_lost_reports{0};
  std::atomic<std::int64_t> encoder_lost_reports{0};
  std::atomic<LoopState> state{LoopState::starting};
  std::atomic<StopReason> last_stop{StopReason::none};
  std::atomic<std::int64_t> sessions_completed{0};
  // Boards lost (each board counted once per loss) and reconnections (both boards open again and
  // initialised).
  std::atomic<std::int64_t> disconnects{0};
  std::atomic<std::int64_t> reconnects{0};
  // Set once the first decodable report of each board has come in (systemd's READY waits for it).
  std::atomic<bool> motor_reports_seen{false};
  std::atomic<bool> encoder_reports_seen{false};
  // The loop's clock at its latest wake-up (at construction before the first). Other threads read
  // time here: a VirtualClock is the loop thread's alone, so they must not call it.
  std::atomic<std::int64_t> clock_ns{0};
  // The loop thread's CPU time over run(), read once as it returns (a syscall the cycles avoid).
  std::atomic<std::int64_t> loop_cpu_time_ns{0};
};

class ControlLoop {
 public:
  ControlLoop(const LoopSettings& settings, BoardLink& motor, BoardLink& encoder,
              bridge::Clock& clock, EventQueue& events);

  // --- from other threads, lock-free ---
  // Queues a session; false when one is already waiting. The loop may still refuse it (pendulum
  // not at rest, a session running): the refusal comes back as a fault event.
  bool request_session(const SessionRequest& request) noexcept;
  void request_stop(StopReason reason) noexcept;  // stop_command, estop_command or signal
  void request_exit() noexcept;                   // ends any session, then run() returns
  // After the current session (or at once when idle), run() returns: one-shot runs and tests.
  void exit_when_idle() noexcept { exit_when_idle_.store(true); }

  // Runs until exit is requested. Throws only what start-up throws; an exception inside a cycle
  // ends the session (reason exception) and is then rethrown, after the zero command.
  void run();

  const LoopCounters& counters() const noexcept { return counters_; }
  LatencyHistogram& wake_latency() noexcept { return wake_latency_; }

 private:
  struct BoardState;
  void cycle(std::int64_t deadline_ns, std::int64_t wake_ns, std::int64_t missed);
  void drain_boards(RigSample& sample, std::int64_t& newest_arm_counts);
  void begin_session(const SessionRequest& request, std::int64_t now_ns);
  void consider_pending_request(std::int64_t now_ns);
  void end_session(StopReason reason, const char* detail, std::int64_t now_ns);
  // May throw what the motor link throws (run() catches it).
  bool write_command(double duty, double braking_fraction, RawReport* record);
  void emit(LoopEvent::Kind kind) noexcept;
  void emit_fault(const char* what, const char* detail, StopReason reason, bool fatal,
                  std::int64_t now_ns, std::int64_t request_id = 0) noexcept;
  bool queue_has_room(std::size_t events) noexcept;
  // Follows the counts of fresh reports for the stuck-encoder rules (SafetyLimits::stuck_*).
  void watch_encoders(const RigSample& sample) noexcept;
  // A board's link failed: it is down until reconnected. Records the first failure's status.
  void mark_down(BoardLink& board, bridge::TransportStatus status) noexcept;
  // Reports each board newly down (a "disconnected" fault event, in the running session's log).
  void report_lost_boards(std::int64_t now_ns) noexcept;
  // While idle with a board down: every reconnect interval, try to reopen and re-initialise.
  void try_reconnect(std::int64_t now_ns);
  // Enables the pendulum's channel and writes the zero command: at start-up and after a
  // reconnect (the motor board resets on power-up, the encoder board's channels come up
  // disabled). False if a write failed (the board is marked down again).
  bool initialise_boards();

  LoopSettings settings_;
  BoardLink& motor_;
  BoardLink& encoder_;
  bridge::Clock& clock_;
  EventQueue& events_;

  boost::lockfree::spsc_queue<SessionRequest, boost::lockfree::capacity<2>> requests_;
  std::atomic<StopReason> stop_request_{StopReason::none};
  std::atomic<bool> exit_{false};
  std::atomic<bool> exit_when_idle_{false};
  LoopCounters counters_;
  LatencyHistogram wake_latency_;

  // Loop-thread state (no other thread touches it).
  LoopEvent event_;  // built in place, then copied into the queue
  // The boards' adapters: each report is decoded once, by them, with their loss detection.
  std::unique_ptr<bridge::MotorBoard> motor_board_;
  std::unique_ptr<bridge::EncoderBoard> encoder_board_;
  bool running_ = false;
  SessionRequest pending_;  // a start request waiting for the pendulum to rest
  bool have_pending_ = false;
  std::int64_t pending_since_ns_ = 0;
  Excitation excitation_;
  bool balance_ = false;
  control::BalanceLaw balance_law_;
  // When the newest angle of each board was read (its report's arrival, on the loop's clock),
  // kept by drain_boards every cycle.
  std::int64_t arm_read_ns_ = 0;
  std::int64_t pendulum_read_ns_ = 0;
  std::array<char, kNameChars> session_{};
  std::int64_t session_start_ns_ = 0;
  std::int64_t seq_ = 0;
  std::int64_t arm_zero_counts_ = 0;
  std::int64_t pendulum_zero_counts_ = 0;
  std::int64_t session_overruns_ = 0;
  std::int64_t session_motor_lost_ = 0;
  std::int64_t session_encoder_lost_ = 0;
  int cycle_motor_lost_ = 0;  // found by this cycle's drain
  int cycle_encoder_lost_ = 0;
  // Board state carried across cycles.
  std::int64_t arm_counts_ = 0;
  // Running sum of the encoder board's deltas since the pendulum channel was enabled.
  std::int64_t pendulum_counts_ = 0;
  double applied_duty_ = 0;
  double motor_current_a_ = 0;
  double supply_voltage_v_ = 0;
  bool have_supply_ = false;
  std::uint8_t motor_flags_ = 0;
  bool motor_over_temperature_ = false;
  bool motor_under_voltage_ = false;
  std::uint8_t encoder_flags_ = 0;
  int cycles_without_motor_ = 0;
  int cycles_without_encoder_ = 0;
  // The first USB failure since the boards were last all up (ok: both are up).
  bridge::TransportStatus usb_failure_ = bridge::TransportStatus::ok;
  bool motor_down_ = false;
  bool encoder_down_ = false;
  bool motor_down_reported_ = false;
  bool encoder_down_reported_ = false;
  std::int64_t down_since_ns_ = 0;
  std::int64_t next_reconnect_ns_ = 0;
  // Stuck-encoder watch, per session: the counts last seen in a fresh report of each board.
  std::int64_t watched_arm_counts_ = 0;
  std::int64_t watched_pendulum_counts_ = 0;
  int arm_still_driven_cycles_ = 0;
  double arm_travel_pendulum_still_rad_ = 0.0;
  // Rest detection: the pendulum count and when it last moved beyond the tolerance.
  std::int64_t rest_anchor_counts_ = 0;
  std::int64_t rest_anchor_ns_ = 0;
};

}  // namespace furuta::daemon
