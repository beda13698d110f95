#include "furuta/daemon/session_recorder.hpp"

#include <algorithm>
#include <exception>
#include <limits>

#include "furuta/daemon/daemon.hpp"
#include "furuta/rig_fault_t.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::daemon {

namespace {

template <std::size_t N>
std::string text_of(const std::array<char, N>& chars) {
  return std::string(chars.data());
}

// What the fault record and the status say: the status name, and for the failures an operator
// acts on, what happened and where the data is.
std::string describe_log_failure(session_log::LogWriteStatus status,
                                 const session_log::LcmLogWriter& log) {
  std::string why = "session log: " + std::string(session_log::to_string(status));
  if (status == session_log::LogWriteStatus::file_removed) {
    why += " (deleted under the session, its directory with it?); ";
    why += log.removal_save_error().empty()
               ? "what was written is saved again as " + log.partial_path().string() +
                     (log.is_open() ? " and the session's log goes on there" : "")
               : "what was written is LOST: " + log.removal_save_error();
  } else if (status == session_log::LogWriteStatus::disk_full) {
    why += " (what was synced before stays in " + log.partial_path().string() + ")";
  }
  return why;
}

}  // namespace

furuta::rig_sample_t to_lcm_sample(const RigSample& s, const std::string& session) {
  furuta::rig_sample_t m{};
  m.seq = s.seq;
  m.monotonic_ns = s.monotonic_ns;
  m.wall_time_ns = s.wall_time_ns;
  m.session = session;
  m.arm_counts = s.arm_counts;
  // The message's field is 32 bits: a count beyond it (hundreds of thousands of turns) saturates.
  m.pendulum_counts = static_cast<std::int32_t>(
      std::clamp<std::int64_t>(s.pendulum_counts, std::numeric_limits<std::int32_t>::min(),
                               std::numeric_limits<std::int32_t>::max()));
  m.arm_angle_rad = s.arm_angle_rad;
  m.pendulum_angle_rad = s.pendulum_angle_rad;
  m.commanded_duty = s.commanded_duty;
  m.applied_duty = s.applied_duty;
  m.motor_current_a = s.motor_current_a;
  m.supply_voltage_v = s.supply_voltage_v;
  m.motor_status_flags = s.motor_status_flags;
  m.encoder_flags = s.encoder_flags;
  // The raw bytes of every report are in RIG_USB; the sample lists the ones that decoded.
  for (std::size_t i = 0; i < s.motor.count; ++i) {
    const bridge::MotorReading& r = s.motor.readings[i];
    m.motor_report_host_ns.push_back(r.host_ns);
    m.motor_packet_counter.push_back(static_cast<std::int16_t>(r.report_counter));
    m.motor_encoder_time.push_back(static_cast<std::int32_t>(r.board_time));
  }
  m.n_motor_reports = static_cast<std::int16_t>(m.motor_report_host_ns.size());
  for (std::size_t i = 0; i < s.encoder.count; ++i) {
    const bridge::EncoderReading& r = s.encoder.readings[i];
    m.encoder_report_host_ns.push_back(r.host_ns);
    m.encoder_packet_ticks.push_back(static_cast<std::int32_t>(r.board_ticks));
    m.encoder_delta_counts.push_back(r.delta_counts);
  }
  m.n_encoder_reports = static_cast<std::int16_t>(m.encoder_report_host_ns.size());
  m.motor_lost_reports = s.motor_lost_reports;
  m.encoder_lost_reports = s.encoder_lost_reports;
  m.overruns = s.overruns;
  m.flags = s.flags;
  return m;
}

SessionRecorder::SessionRecorder(RecorderSettings settings, lcm::LCM* lcm,
                                 std::function<void(const std::string&)> on_log_failure)
    : settings_(std::move(settings)), lcm_(lcm), on_log_failure_(std::move(on_log_failure)) {}

SessionRecorder::~SessionRecorder() = default;

template <typename Message>
void SessionRecorder::publish_and_log(const char* channel, const Message& message,
                                      std::int64_t monotonic_ns) {
  const int size = message.getEncodedSize();
  buffer_.resize(static_cast<std::size_t>(size));
  message.encode(buffer_.data(), 0, size);
  if (lcm_) lcm_->publish(channel, buffer_.data(), static_cast<unsigned>(size));
  log_bytes(channel, buffer_, monotonic_ns);
}

void SessionRecorder::log_bytes(const char* channel, const std::vector<std::uint8_t>& bytes,
                                std::int64_t monotonic_ns) {
  if (!log_ || log_failed_) return;
  // Log times are the loop's monotonic clock in microseconds: replay and virtual time stay exact;
  // wall time is inside the messages.
  on_log_status(log_->write(channel, monotonic_ns / 1000, bytes));
}

void SessionRecorder::on_log_status(session_log::LogWriteStatus status) {
  if (status == session_log::LogWriteStatus::ok) return;
  // A log written again after its directory was removed goes on: the session is still stopped
  // (someone removed the logs), but what comes until it has stopped is kept.
  fail_log(describe_log_failure(status, *log_), /*still_logging=*/log_->is_open());
}

void SessionRecorder::fail_log(const std::string& why, bool still_logging) {
  log_failed_ = !still_logging;
  log_failure_ = why;
  note_fault(why);
  if (on_log_failure_) on_log_failure_(last_fault_);
}

void SessionRecorder::note_fault(std::string what) {
  last_fault_ = std::move(what);
  // This thread's wall clock, a moment after the loop's event: a status needs the time to the
  // second, not the cycle.
  history_.last_fault_wall_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                    std::chrono::system_clock::now().time_since_epoch())
                                    .count();
  history_.last_fault_session = session_;
  history_.sessions_since_fault = 0;
  if (!session_.empty()) session_faulted_ = true;
}

void SessionRecorder::note_signed_start(std::int64_t request_id,
                                        std::vector<std::uint8_t> encoded) {
  std::lock_guard lock(signed_starts_mutex_);
  signed_starts_.emplace_back(request_id, std::move(encoded));
  while (signed_starts_.size() > 8) signed_starts_.pop_front();
}

void SessionRecorder::note_controller(std::int64_t request_id, ControllerRecord controller) {
  std::lock_guard lock(signed_starts_mutex_);
  controllers_.emplace_back(request_id, std::move(controller));
  while (controllers_.size() > 8) controllers_.pop_front();
}

void SessionRecorder::start_session(const SessionStartEvent& start) {
  session_ = text_of(start.session);
  session_faulted_ = false;
  history_.last_session_request_id = start.request_id;
  history_.last_session_end.clear();
  wake_latency_.reset();
  log_failed_ = false;
  log_failure_.clear();
  log_.reset();
  samples_logged_ = 0;
  if (!settings_.logs_dir.empty()) {
    // The name was picked when the start was accepted; another process's session into the same
    // directory may have taken it since (names have whole seconds). The next free one is taken
    // then, so that each session keeps its own log.
    const std::string picked = session_;
    for (int attempt = 0; !log_; ++attempt) {
      try {
        log_ = std::make_unique<session_log::LcmLogWriter>(
            session_log::LogWriterOptions{settings_.logs_dir, settings_.flush_interval}, session_);
      } catch (const session_log::LogNameInUse& e) {
        if (attempt == 8) {
          fail_log(std::string("session log: ") + e.what());
          break;
        }
        session_ = unique_session_name(picked, settings_.logs_dir);
      } catch (const std::exception& e) {
        fail_log(std::string("session log: ") + e.what());
        break;
      }
    }
  }
  history_.last_session = session_;
  furuta::rig_session_t m{};
  m.event = furuta::rig_session_t::EVENT_START;
  m.session = session_;
  m.label = text_of(start.label);
  m.profile =
      start.balance ? std::string("balance") : std::string(to_string(start.excitation.kind));
  m.amplitude_duty = start.excitation.amplitude_duty;
  m.duration_s = start.excitation.duration_s;
  m.seed = static_cast<std::int64_t>(start.excitation.seed);
  m.period_ns = start.period_ns;
  m.monotonic_ns = start.monotonic_ns;
  m.wall_time_ns = start.wall_time_ns;
  m.rig_config_toml = settings_.rig_config_toml;
  m.software_version = settings_.software_version;
  m.motor_device = settings_.motor_device;
  m.encoder_device = settings_.encoder_device;
  m.arm_zero_counts = start.arm_zero_counts;
  m.pendulum_zero_counts = start.pendulum_zero_counts;
  publish_and_log(session_log::kChannelSession, m, start.monotonic_ns);
  if (start.request_id != 0) {
    std::vector<std::uint8_t> signed_start;
    {
      std::lock_guard lock(signed_starts_mutex_);
      for (auto& [id, bytes] : signed_starts_) {
        if (id == start.request_id) signed_start = std::move(bytes);
      }
    }
    // Logged only: the command was on the bus already.
    if (!signed_start.empty()) {
      log_bytes(session_log::kChannelSignedCommand, signed_start, start.monotonic_ns);
    }
  }
  if (start.balance) {
    std::optional<ControllerRecord> controller;
    {
      std::lock_guard lock(signed_starts_mutex_);
      for (auto& [id, record] : controllers_) {
        if (id == start.request_id) controller = std::move(record);
      }
    }
    if (controller) {
      furuta::rig_controller_t c;
      c.session = session_;
      c.path = controller->path;
      c.sha256 = controller->sha256;
      c.controller_toml = controller->text;
      const int size = c.getEncodedSize();
      buffer_.resize(static_cast<std::size_t>(size));
      c.encode(buffer_.data(), 0, size);
      log_bytes(session_log::kChannelController, buffer_, start.monotonic_ns);
    }
  }
  if (log_ && !log_failed_) {
    on_log_status(log_->sync_if_due(std::chrono::steady_clock::now(), /*force=*/true));
  }
}

void SessionRecorder::record_sample(const RigSample& s) {
  wake_latency_.record(s.wake_latency_ns);
  // Subscribers first: a controller or a plot waits for the sample, the log does not.
  sample_msg_ = to_lcm_sample(s, session_);
  const int size = sample_msg_.getEncodedSize();
  sample_buffer_.resize(static_cast<std::size_t>(size));
  sample_msg_.encode(sample_buffer_.data(), 0, size);
  if (publish_observer_) publish_observer_(s);
  if (lcm_) {
    lcm_->publish(session_log::kChannelSample, sample_buffer_.data(), static_cast<unsigned>(size));
  }
  // In the log, the raw reports come before their sample, in the order they crossed the wire:
  // inputs, then this cycle's command.
  auto log_raw = [&](const RawReport& raw, std::int8_t board, std::int8_t kind) {
    log_raw_report(raw, board, kind);
  };
  for (std::size_t i = 0; i < s.motor_in.count; ++i) {
    log_raw(s.motor_in.reports[i], furuta::rig_usb_report_t::BOARD_MOTOR,
            furuta::rig_usb_report_t::KIND_INPUT);
  }
  for (std::size_t i = 0; i < s.encoder_in.count; ++i) {
    log_raw(s.encoder_in.reports[i], furuta::rig_usb_report_t::BOARD_ENCODER,
            furuta::rig_usb_report_t::KIND_INPUT);
  }
  if (s.motor_out.length > 0) {
    log_raw(s.motor_out, furuta::rig_usb_report_t::BOARD_MOTOR,
            s.motor_out.status == bridge::TransportStatus::ok
                ? +furuta::rig_usb_report_t::KIND_OUTPUT
                : +furuta::rig_usb_report_t::KIND_ERROR);
  }
  log_bytes(session_log::kChannelSample, sample_buffer_, s.monotonic_ns);
  if (log_ && !log_failed_) ++samples_logged_;
  if (s.control.present) {
    static_assert(furuta::rig_control_t::MODE_FALLEN == 3, "modes in control::BalanceMode's order");
    control_msg_.seq = s.seq;
    control_msg_.monotonic_ns = s.monotonic_ns;
    control_msg_.session = session_;
    control_msg_.mode = static_cast<std::int8_t>(s.control.mode);
    control_msg_.upright_error_rad = s.control.upright_error_rad;
    control_msg_.arm_rate_rad_s = s.control.arm_rate_rad_s;
    control_msg_.pendulum_rate_rad_s = s.control.pendulum_rate_rad_s;
    control_msg_.energy_ratio = s.control.energy_ratio;
    control_msg_.law_duty = s.control.law_duty;
    control_msg_.law_time_ns = s.control.law_time_ns;
    publish_and_log(session_log::kChannelControl, control_msg_, s.monotonic_ns);
  }
  ++samples_published_;
}

void SessionRecorder::log_raw_report(const RawReport& raw, std::int8_t board, std::int8_t kind) {
  usb_msg_.time_ns = raw.time_ns;
  usb_msg_.board = board;
  usb_msg_.kind = kind;
  usb_msg_.status = raw.status == bridge::TransportStatus::ok
                        ? std::string()
                        : std::string(bridge::to_string(raw.status));
  usb_msg_.length = raw.length;
  usb_msg_.bytes.assign(raw.bytes.begin(), raw.bytes.begin() + raw.length);
  const int size = usb_msg_.getEncodedSize();
  buffer_.resize(static_cast<std::size_t>(size));
  usb_msg_.encode(buffer_.data(), 0, size);
  log_bytes(session_log::kChannelUsb, buffer_, raw.time_ns);
}

void SessionRecorder::record_fault(const FaultEvent& f) {
  furuta::rig_fault_t m{};
  m.monotonic_ns = f.monotonic_ns;
  m.session = session_;
  m.seq = f.seq;
  m.reason = text_of(f.what);
  m.detail = text_of(f.detail);
  m.fatal = f.fatal;
  // The loop stops a session for a log failure without knowing what failed; this thread does, and
  // the fault must say it (disk full, the directory, ...) rather than a bare log_error.
  if (f.reason == StopReason::log_error && m.detail.empty()) m.detail = log_failure_;
  // A board lost while idle ends no session: no fatal fault says it, so the status must.
  if (f.fatal || m.reason == "disconnected") {
    note_fault(m.reason + (m.detail.empty() ? "" : ": " + m.detail));
  }
  // A start the loop refuses (the pendulum still swings) or a stop cancels was already answered
  // "accepted": this is the verdict `furuta start` waits for, under its request's id.
  if (m.reason == "start_refused" || m.reason == "start_cancelled") {
    history_.refused_request_id = f.request_id;
    history_.refused_reason = m.reason == "start_cancelled"
                                  ? "cancelled by " + m.detail + " before it could start"
                                  : m.detail;
  }
  publish_and_log(session_log::kChannelFault, m, f.monotonic_ns);
}

void SessionRecorder::end_session(const SessionEndEvent& e) {
  if (e.final_command.length > 0) {
    log_raw_report(e.final_command, furuta::rig_usb_report_t::BOARD_MOTOR,
                   e.final_command.status == bridge::TransportStatus::ok
                       ? +furuta::rig_usb_report_t::KIND_OUTPUT
                       : +furuta::rig_usb_report_t::KIND_ERROR);
  }
  furuta::rig_session_t m{};
  m.event = furuta::rig_session_t::EVENT_END;
  // The log's name, which may differ from the one the loop was given.
  m.session = session_.empty() ? text_of(e.session) : session_;
  m.monotonic_ns = e.monotonic_ns;
  m.wall_time_ns = e.wall_time_ns;
  m.samples = e.samples;
  m.end_reason = std::string(to_string(e.reason));
  const std::string detail = text_of(e.detail);
  if (!detail.empty()) m.end_reason += ": " + detail;
  publish_and_log(session_log::kChannelSession, m, e.monotonic_ns);
  if (log_ && !log_failed_) {
    on_log_status(
        session_log::write_seal(*log_, m.session, samples_logged_, settings_.seal_source));
  }
  if (log_ && !log_failed_) {
    std::filesystem::path final_path;
    if (log_->finish(&final_path) == session_log::LogWriteStatus::ok) {
      last_log_ = final_path;
      if (on_logged_) on_logged_(final_path);
    } else {
      fail_log("session log: cannot finish " + log_->partial_path().string());
    }
  }
  history_.last_session_end = m.end_reason;
  if (!is_fault(e.reason) && !session_faulted_ && !log_failed_) ++history_.sessions_since_fault;
  // A failed log stays as .part: recovery at the next start keeps its readable prefix.
  log_.reset();
  session_.clear();
}

void SessionRecorder::handle(const LoopEvent& event) {
  switch (event.kind) {
    case LoopEvent::Kind::session_start:
      start_session(event.start);
      break;
    case LoopEvent::Kind::sample:
      record_sample(event.sample);
      break;
    case LoopEvent::Kind::fault:
      record_fault(event.fault);
      break;
    case LoopEvent::Kind::session_end:
      end_session(event.end);
      break;
  }
}

void SessionRecorder::sync_if_due(std::chrono::steady_clock::time_point now) {
  if (!log_ || log_failed_) return;
  on_log_status(log_->sync_if_due(now));
}

}  // namespace furuta::daemon
