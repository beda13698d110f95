#pragma once
// The daemon: the control loop on its own (real-time) thread, the recorder on an I/O thread that
// drains the loop's queue, and an LCM thread that takes commands and answers with status.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "furuta/command_auth/command_auth.hpp"
#include "furuta/command_auth/status_signature.hpp"
#include "furuta/daemon/command_intake.hpp"
#include "furuta/daemon/control_loop.hpp"
#include "furuta/daemon/session_recorder.hpp"
#include "furuta/rig_command_t.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/rig_signed_command_t.hpp"
#include "furuta/rig_status_t.hpp"

namespace furuta::daemon {

struct DaemonSettings {
  std::string rig_name;  // [rig] name: a balance controller must have been designed for it
  LoopSettings loop;
  RecorderSettings recorder;
  CommandLimits command_limits;
  ExcitationSpec default_excitation;  // fields a command leaves out
  RealtimeOptions realtime;
  std::size_t queue_capacity = 4096;  // loop events: about a minute at 16 ms
  std::chrono::milliseconds status_interval{1000};
  // Who may move the motor over LCM (docs/security.md): starts come signed with this key on
  // RIG_COMMAND_SIGNED, within `command_auth.window` of `wall_clock_ns` and once. Without a key
  // every start over LCM is refused with `command_key_problem`; stop, e-stop and status never
  // need one.
  std::optional<command_auth::CommandKey> command_key;
  std::string command_key_problem = "no command key was given to the daemon";
  command_auth::VerifierSettings command_auth;
  // Signs every status published on RIG_STATUS (the daemon key's seed). Without it statuses go
  // out unsigned, and tools that hold the public key say so.
  std::optional<command_auth::CommandKey> daemon_key;
  std::function<std::int64_t()> wall_clock_ns;       // empty: the system's UTC clock
  std::function<std::int64_t()> monotonic_clock_ns;  // empty: CLOCK_MONOTONIC (the replay floor)
  // Where commands arrive: a udpm:// URL is read by the daemon's own batched reader
  // (command_intake.hpp); anything else (memq:// in tests, or empty) through the `lcm` given.
  std::string command_url;
  int command_socket_buffer_bytes = 4 << 20;
};

// Refusals since start-up by reason, as rig_status_t counts them.
struct RefusalCounts {
  std::atomic<std::int64_t> unsigned_motor_commands{0};
  std::atomic<std::int64_t> bad_signature{0};
  std::atomic<std::int64_t> malformed{0};
  std::atomic<std::int64_t> out_of_time{0};
  std::atomic<std::int64_t> replayed{0};
  std::atomic<std::int64_t> start_budget{0};
  std::atomic<std::int64_t> stop_budget{0};
  std::atomic<std::int64_t> status_budget{0};
  std::atomic<std::int64_t> invalid{0};
  std::atomic<std::int64_t> replies_withheld{0};
};

class Daemon {
 public:
  // `lcm` must outlive the daemon; statuses and samples go out on it. Commands are read on the
  // daemon's own thread, from `settings.command_url`'s group or, for other URLs, through `lcm`.
  // Throws std::system_error when the command socket cannot be opened. `clock` is the loop thread's
  // alone (it may be a single-threaded VirtualClock): the other threads take time from the loop's
  // counters.
  Daemon(DaemonSettings settings, BoardLink& motor, BoardLink& encoder, bridge::Clock& clock,
         lcm::LCM& lcm);
  ~Daemon();  // stops everything (the motor at zero first)

  // Starts the threads. Returns the real-time set-up outcome (refusals are warnings here; furutad
  // decides whether they are fatal).
  RealtimeResult start();
  // Blocks until the loop has exited (after stop(), or after the current session when
  // exit_when_idle), then stops the other threads. Rethrows an exception from the loop.
  void wait();
  // From any thread, e.g. a signal handler thread: ends any session with `reason`, then exits.
  void stop(StopReason reason);

  // A command from inside this process (furuta run, tests): trusted, then validated,
  // rate-limited and answered like one from LCM.
  furuta::rig_status_t handle_command(const furuta::rig_command_t& command);
  // What RIG_COMMAND takes: anyone's command, but none that moves the motor.
  furuta::rig_status_t handle_unsigned_command(const furuta::rig_command_t& command);
  // What RIG_COMMAND_SIGNED takes: a command whose tag, time and freshness check out.
  furuta::rig_status_t handle_signed_command(const furuta::rig_signed_command_t& message);
  // Replay: start a session as a log's start record describes it (the same excitation and zeros).
  // A balance session's law comes from `controller`, the log's RIG_CONTROLLER record (false
  // without one, or when it does not read).
  bool start_replayed_session(const furuta::rig_session_t& start,
                              const furuta::rig_controller_t* controller = nullptr);

  ControlLoop& loop() { return *loop_; }
  SessionRecorder& recorder() { return *recorder_; }
  // Sessions finished so far (by the I/O thread).
  std::int64_t sessions_logged() const { return sessions_logged_.load(); }
  void on_session_logged(std::function<void(const std::filesystem::path&)> callback);
  // True once the loop runs and the first report of each board is in (furutad's READY=1).
  bool ready() const { return ready_.load(); }
  // Why a session could not be logged now ("": it can), as of the last status (once a second).
  std::string logs_problem() const;
  // What the replay state file said at start ("" when all was well).
  const std::string& command_state_problem() const { return verifier_.state_problem(); }
  // Advances while the loop cycles (furutad pings the watchdog only while it moves).
  std::int64_t heartbeat() const { return loop_->counters().cycles.load(); }

 private:
  // What the I/O thread knows that status replies from the LCM thread need.
  struct StatusSnapshot {
    std::string session;
    std::string last_fault;
    std::int64_t latency_samples = 0;
    double jitter_mean_us = 0, jitter_p99_us = 0, jitter_max_us = 0;
    SessionRecorder::History history;
    std::string logs_problem;  // checked at each periodic status
  };
  furuta::rig_status_t status_message();
  void refresh_snapshot();
  // Can a session be logged now? On the I/O thread, once a status interval (a probe file and a
  // statvfs), so `furuta status` says so before a start is refused for it.
  void check_logs_dir();
  void io_thread_main();
  // Sleeps until the loop queues an event or a status is due; from shortly before the next sample
  // is due (a period after the last) until shortly after, watches the queue instead.
  void wait_for_event(std::optional<std::chrono::steady_clock::time_point> next_sample);
  void lcm_thread_main();
  // Raw handlers: oversized and undecodable messages are counted as malformed, never decoded or
  // printed (LCM's typed handlers print every decoding error).
  void on_command(const lcm::ReceiveBuffer* buffer, const std::string&);
  void on_signed_command(const lcm::ReceiveBuffer* buffer, const std::string&);
  void take_command(std::span<const std::uint8_t> bytes);
  void take_signed_command(std::span<const std::uint8_t> bytes);
  // One batch from the command socket, in arrival order; other channels are not looked at.
  void take_datagrams(std::size_t count);
  // Publishes a status: bounded and signed.
  void publish(furuta::rig_status_t status);
  // Whether a command's reply may go out: a refusal or an e-stop only within its reply budget
  // (counted as withheld otherwise), so a refusal's status is built only when it is sent.
  bool reply_allowed(bool accepted, bool estop);
  // A command refused for its signature: counted by reason, the reason kept for the status.
  void note_unauthenticated(command_auth::Refusal refusal, const std::string& reason);
  furuta::rig_status_t refusal_reply(std::int64_t request_id, const std::string& reason);
  furuta::rig_status_t reply_for(std::int64_t request_id, const CommandDecision& decision);
  static std::int64_t unverified_request_id(const furuta::rig_signed_command_t& message);
  command_auth::Verdict verify(const furuta::rig_signed_command_t& message);
  // A command whose signature checked out: a start's signed bytes kept for its log, then decided.
  CommandDecision take_signed(const furuta::rig_signed_command_t& message,
                              const furuta::rig_command_t& command);
  // Validated, rate-limited and carried out (under command_mutex_), the refusal counted.
  CommandDecision decide(const furuta::rig_command_t& command);
  void count(CommandRefusal refusal);
  std::int64_t wall_now_ns() const;
  std::int64_t monotonic_now_ns() const;
  // An accepted command's action, under command_mutex_; a start may still be refused.
  CommandDecision carry_out(const furuta::rig_command_t& command);
  // A balance start: reads and checks its controller file into `request` (the law) and `spec`
  // (the amplitude); the refusal's reason, or empty.
  std::string prepare_balance(const furuta::rig_command_t& command, ExcitationSpec& spec,
                              SessionRequest& request);

  DaemonSettings settings_;
  lcm::LCM& lcm_;
  EventQueue events_;
  std::unique_ptr<ControlLoop> loop_;
  std::unique_ptr<SessionRecorder> recorder_;
  CommandValidator validator_;
  command_auth::CommandVerifier verifier_;  // under command_mutex_
  std::optional<command_auth::StatusSigner> signer_;
  RefusalCounts refusals_;
  // Reply budgets, on the LCM thread only.
  TokenBucket refusal_replies_;
  TokenBucket estop_replies_;
  std::string unauthenticated_reason_;  // under snapshot_mutex_
  // Validator state and the loop's single-producer request queue: commands come from LCM and
  // from handle_command, replays from start_replayed_session.
  std::mutex command_mutex_;
  mutable std::mutex snapshot_mutex_;
  StatusSnapshot snapshot_;
  std::function<void(const std::filesystem::path&)> on_logged_;

  std::atomic<bool> io_stop_{false};
  std::atomic<bool> lcm_stop_{false};
  std::atomic<bool> ready_{false};
  std::atomic<std::int64_t> sessions_logged_{0};
  std::exception_ptr loop_error_;
  std::thread loop_thread_;
  std::thread io_thread_;
  std::thread lcm_thread_;
  std::unique_ptr<MulticastReceiver> intake_;  // null: commands come through lcm_
  lcm::Subscription* subscription_ = nullptr;
  lcm::Subscription* signed_subscription_ = nullptr;
};

// "2026-11-21T10-04-05Z_label": sortable, safe as a file name (label reduced to [A-Za-z0-9_.-]).
std::string session_name(std::int64_t wall_time_ns, const std::string& label);
// `name`, or name-2, name-3, ... : the first that no log in `logs_dir` (or its done/, failed/ and
// .partial/, where running sessions write) already starts with, so two sessions started within
// one second both get their log.
std::string unique_session_name(const std::string& name, const std::filesystem::path& logs_dir);

}  // namespace furuta::daemon
