#pragma once
// The publisher/logger side of the loop, on its own thread: each loop event becomes LCM messages,
// published (RIG_SAMPLE, RIG_SESSION, RIG_FAULT) and written to the session's log (plus every raw
// USB report on RIG_USB), synced at the flush interval, renamed into the logs directory at the end.

#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "furuta/daemon/loop_events.hpp"
#include "furuta/daemon/realtime.hpp"
#include "furuta/firmware_bridge/encoder_geometry.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/rig_usb_report_t.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::daemon {

struct RecorderSettings {
  std::filesystem::path logs_dir;
  std::chrono::milliseconds flush_interval{1000};
  std::string rig_config_toml;  // verbatim into the start record
  std::string software_version;
  std::string motor_device;  // usb trace device lines, for replay
  std::string encoder_device;
  // A start is refused while the logs file system has less than this available: about 8 s of a
  // session (some 30 KiB/s at 16 ms), so a full disk refuses instead of starting the motor for a
  // log that fails at once.
  std::uint64_t min_free_bytes_to_start = 256 * 1024;
  // What each log's seal says its data came from: empty on the rig, the replayed log in a replay.
  session_log::SealSource seal_source;
};

class SessionRecorder {
 public:
  // `lcm` may be null (no publishing). `on_log_failure` is called once per session when the log
  // cannot be written (the daemon stops the session with log_error).
  SessionRecorder(RecorderSettings settings, lcm::LCM* lcm,
                  std::function<void(const std::string&)> on_log_failure = {});
  ~SessionRecorder();  // a session still open keeps its .part for recovery

  void handle(const LoopEvent& event);
  // The signed command (encoded rig_signed_command_t) behind start request `request_id`: written
  // into that session's log right after its start record, so the log shows who started it. From
  // any thread; only the latest few are kept.
  void note_signed_start(std::int64_t request_id, std::vector<std::uint8_t> encoded);
  // The controller file behind balance start request `request_id`: written into that session's
  // log (RIG_CONTROLLER) after its start record. From any thread; only the latest few are kept.
  struct ControllerRecord {
    std::string path;
    std::string sha256;
    std::string text;
  };
  void note_controller(std::int64_t request_id, ControllerRecord controller);
  void sync_if_due(std::chrono::steady_clock::time_point now);

  // Called with the final path of each log when its session ends.
  void on_session_logged(std::function<void(const std::filesystem::path&)> callback) {
    on_logged_ = std::move(callback);
  }

  const std::optional<std::filesystem::path>& last_log() const { return last_log_; }
  std::string current_session() const { return session_; }
  std::int64_t samples_published() const { return samples_published_; }
  // Called on this thread with each sample just before it is published (a benchmark's probe of
  // the hand-off: RigSample::queued_ns). Set before the daemon starts.
  void on_publish(std::function<void(const RigSample&)> observer) {
    publish_observer_ = std::move(observer);
  }
  const LatencyHistogram& session_wake_latency() const { return wake_latency_; }
  const std::string& last_fault() const { return last_fault_; }

  // What the status says about the past, beyond the last fault itself: when it happened and in
  // which session, how many sessions ended well since, the latest session and the start request
  // it came from, and the latest start the loop refused after the command was answered.
  struct History {
    std::int64_t last_fault_wall_ns = 0;
    std::string last_fault_session;
    std::int64_t sessions_since_fault = 0;
    std::string last_session;
    std::int64_t last_session_request_id = 0;
    std::string last_session_end;
    std::int64_t refused_request_id = 0;
    std::string refused_reason;
  };
  const History& history() const { return history_; }

 private:
  void start_session(const SessionStartEvent& start);
  void end_session(const SessionEndEvent& end);
  void record_sample(const RigSample& sample);
  void record_fault(const FaultEvent& fault);
  void log_raw_report(const RawReport& raw, std::int8_t board, std::int8_t kind);
  template <typename Message>
  void publish_and_log(const char* channel, const Message& message, std::int64_t monotonic_ns);
  void log_bytes(const char* channel, const std::vector<std::uint8_t>& bytes,
                 std::int64_t monotonic_ns);
  // A write or sync that did not succeed: stops the session (log_error) with what happened.
  void on_log_status(session_log::LogWriteStatus status);
  // The daemon stops the session (log_error); unless still_logging, nothing more is written.
  void fail_log(const std::string& why, bool still_logging = false);
  // The status's last fault, stamped now (UTC) with the session it happened in.
  void note_fault(std::string what);

  RecorderSettings settings_;
  lcm::LCM* lcm_;
  std::function<void(const std::string&)> on_log_failure_;
  std::function<void(const std::filesystem::path&)> on_logged_;
  std::unique_ptr<session_log::LcmLogWriter> log_;
  bool log_failed_ = false;
  std::string log_failure_;  // why, for the log_error fault the loop sends back
  std::string session_;
  std::optional<std::filesystem::path> last_log_;
  std::int64_t samples_published_ = 0;
  std::int64_t samples_logged_ = 0;  // in the running session's log, for its seal
  std::function<void(const RigSample&)> publish_observer_;
  LatencyHistogram wake_latency_;
  std::string last_fault_;
  History history_;
  bool session_faulted_ = false;  // a fault was noted during the running session
  std::vector<std::uint8_t> buffer_;
  std::mutex signed_starts_mutex_;
  std::deque<std::pair<std::int64_t, std::vector<std::uint8_t>>> signed_starts_;
  std::deque<std::pair<std::int64_t, ControllerRecord>> controllers_;  // under signed_starts_mutex_
  furuta::rig_control_t control_msg_;
  furuta::rig_sample_t sample_msg_;
  std::vector<std::uint8_t> sample_buffer_;  // the encoded sample, published then logged
  furuta::rig_usb_report_t usb_msg_;
};

// The LCM sample message for a loop sample: its fields, and the per-report arrays from the
// readings the loop made of each report (nothing is decoded again here).
furuta::rig_sample_t to_lcm_sample(const RigSample& sample, const std::string& session);

}  // namespace furuta::daemon
