#include "furuta/daemon/control_loop.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <numbers>
#include <system_error>
#include <thread>

namespace furuta::daemon {

using bridge::TransportStatus;

EventQueue::EventQueue(std::size_t capacity)
    : boost::lockfree::spsc_queue<LoopEvent>(capacity), fd_(::eventfd(0, EFD_CLOEXEC)) {
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "eventfd");
}

EventQueue::~EventQueue() {
  ::close(fd_);
}

void EventQueue::notify() noexcept {
  const std::uint64_t one = 1;
  // Only a counter at its maximum refuses; the consumer is then already due to wake.
  [[maybe_unused]] const ssize_t written = ::write(fd_, &one, sizeof one);
}

void EventQueue::wait_for(std::chrono::nanoseconds timeout) noexcept {
  pollfd p{fd_, POLLIN, 0};
  const auto ns = std::max<std::int64_t>(0, timeout.count());
  const timespec ts{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  if (::ppoll(&p, 1, &ts, nullptr) > 0) {
    std::uint64_t count = 0;
    [[maybe_unused]] const ssize_t read = ::read(fd_, &count, sizeof count);
  }
}

namespace {

// Capacity kept free for the events that end a session, so a full queue can never swallow them.
constexpr std::size_t kReservedEvents = 4;

std::int64_t thread_cpu_time_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

std::int64_t wall_time_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

ControlLoop::ControlLoop(const LoopSettings& settings, BoardLink& motor, BoardLink& encoder,
                         bridge::Clock& clock, EventQueue& events)
    : settings_(settings),
      motor_(motor),
      encoder_(encoder),
      clock_(clock),
      events_(events),
      motor_board_(
          bridge::make_motor_board(settings.motor_board, motor.device_info(),
                                   {settings.safety.max_duty, settings.acceleration_pct_per_s})),
      encoder_board_(bridge::make_encoder_board(settings.encoder_board, encoder.device_info(),
                                                settings.pendulum_channel)) {
  counters_.clock_ns.store(clock_.now_ns());
  if (settings_.period_ns <= 0) throw std::invalid_argument("period_ns must be > 0");
}

bool ControlLoop::request_session(const SessionRequest& request) noexcept {
  return requests_.push(request);
}

void ControlLoop::request_stop(StopReason reason) noexcept {
  // An e-stop overrides whatever stop is pending (a log error, a signal): each ends a session the
  // same way, but only an e-stop also brakes an idle motor, and it must never be swallowed.
  if (reason == StopReason::estop_command) {
    stop_request_.store(reason);
    return;
  }
  // Any other stop or fault must not be downgraded by a later plain stop.
  StopReason current = stop_request_.load();
  while (current == StopReason::none || current == StopReason::stop_command) {
    if (stop_request_.compare_exchange_weak(current, reason)) return;
  }
}

void ControlLoop::request_exit() noexcept {
  exit_.store(true);
}

bool ControlLoop::queue_has_room(std::size_t events) noexcept {
  while (events_.write_available() < events + kReservedEvents) {
    if (!settings_.wait_when_queue_full) return false;
    std::this_thread::yield();
  }
  return true;
}

void ControlLoop::emit(LoopEvent::Kind kind) noexcept {
  event_.kind = kind;
  // The reserve guarantees room for session and fault events; samples checked it before.
  while (!events_.push(event_)) {
    if (!settings_.wait_when_queue_full) return;
    std::this_thread::yield();
  }
  events_.notify();
}

void ControlLoop::emit_fault(const char* what, const char* detail, StopReason reason, bool fatal,
                             std::int64_t now_ns, std::int64_t request_id) noexcept {
  FaultEvent& f = event_.fault;
  f.request_id = request_id;
  f.reason = reason;
  copy_text(f.what, what);
  copy_text(f.detail, detail);
  f.seq = seq_;
  f.monotonic_ns = now_ns;
  f.fatal = fatal;
  emit(LoopEvent::Kind::fault);
}

bool ControlLoop::write_command(double duty, double braking_fraction, RawReport* record) {
  std::array<std::uint8_t, bridge::kMaxReportBytes> bytes{};
  const std::size_t length = motor_.device_info().output_report_bytes;
  if (length > bytes.size()) return false;
  if (!motor_board_->write({duty, braking_fraction}, {bytes.data(), length})) return false;
  const TransportStatus status = motor_.write({bytes.data(), length});
  if (record) {
    record->time_ns = clock_.now_ns();
    record->status = status;
    record->length = static_cast<std::uint8_t>(length);
    record->bytes = bytes;
  }
  if (status != TransportStatus::ok) mark_down(motor_, status);
  return status == TransportStatus::ok;
}

void ControlLoop::mark_down(BoardLink& board, TransportStatus status) noexcept {
  if (usb_failure_ == TransportStatus::ok) usb_failure_ = status;
  bool& down = &board == &motor_ ? motor_down_ : encoder_down_;
  if (down) return;
  down = true;
  counters_.disconnects.fetch_add(1, std::memory_order_relaxed);
  // The first attempt waits an interval: a board that has just gone is rarely back at once.
  if (!(motor_down_ && encoder_down_)) {
    down_since_ns_ = clock_.now_ns();
    next_reconnect_ns_ = down_since_ns_ + settings_.reconnect_interval_ns;
  }
}

void ControlLoop::report_lost_boards(std::int64_t now_ns) noexcept {
  char detail[kDetailChars];
  if (motor_down_ && !motor_down_reported_) {
    motor_down_reported_ = true;
    std::snprintf(detail, sizeof detail, "%s motor board lost; reconnecting",
                  settings_.motor_board.c_str());
    emit_fault("disconnected", detail, StopReason::none, false, now_ns);
  }
  if (encoder_down_ && !encoder_down_reported_) {
    encoder_down_reported_ = true;
    std::snprintf(detail, sizeof detail, "%s encoder board lost; reconnecting",
                  settings_.encoder_board.c_str());
    emit_fault("disconnected", detail, StopReason::none, false, now_ns);
  }
}

bool ControlLoop::initialise_boards() {
  std::array<std::uint8_t, bridge::kMaxReportBytes> enable{};
  const std::size_t length = encoder_board_->enable(enable);
  const TransportStatus encoder_status =
      length == 0 ? TransportStatus::ok : encoder_.write({enable.data(), length});
  if (encoder_status != TransportStatus::ok) mark_down(encoder_, encoder_status);
  const bool motor_ok = write_command(0.0, settings_.stop_braking_fraction, nullptr);
  return encoder_status == TransportStatus::ok && motor_ok;
}

void ControlLoop::try_reconnect(std::int64_t now_ns) {
  if (now_ns < next_reconnect_ns_) return;
  next_reconnect_ns_ = now_ns + settings_.reconnect_interval_ns;
  if (motor_down_ && motor_.reconnect() == TransportStatus::ok) {
    motor_down_ = false;
    motor_down_reported_ = false;  // lost again before the other is back: reported again
    // The motor board back without a power-up (a USB error, not an unplug) may still drive: zero
    // it now.
    write_command(0.0, settings_.stop_braking_fraction, nullptr);
  }
  if (encoder_down_ && encoder_.reconnect() == TransportStatus::ok) {
    encoder_down_ = false;
    encoder_down_reported_ = false;
  }
  if (motor_down_ || encoder_down_) return;
  if (!initialise_boards()) return;  // marked down again: the next attempt after the interval

  // Both boards are new as far as the loop knows: the counters restart, the supply and flags are
  // unknown until their first report, and the pendulum must be seen at rest afresh before a start.
  motor_board_->restart();
  encoder_board_->restart();
  have_supply_ = false;
  motor_flags_ = 0;
  motor_over_temperature_ = false;
  motor_under_voltage_ = false;
  encoder_flags_ = 0;
  cycles_without_motor_ = 0;
  cycles_without_encoder_ = 0;
  rest_anchor_counts_ = pendulum_counts_;
  rest_anchor_ns_ = now_ns;
  usb_failure_ = TransportStatus::ok;
  motor_down_reported_ = false;
  encoder_down_reported_ = false;
  counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
  counters_.state.store(LoopState::idle);
  char detail[kDetailChars];
  std::snprintf(detail, sizeof detail, "both boards open and initialised again after %lld ms",
                static_cast<long long>((now_ns - down_since_ns_) / 1'000'000));
  emit_fault("reconnected", detail, StopReason::none, false, now_ns);
}

void ControlLoop::drain_boards(RigSample& sample, std::int64_t& newest_arm_counts) {
  sample.motor_in.count = 0;
  sample.encoder_in.count = 0;
  // A board that is down is left alone until it is reconnected.
  if (!motor_down_) {
    const TransportStatus status = motor_.drain(sample.motor_in);
    if (status != TransportStatus::ok) mark_down(motor_, status);
  }
  if (!encoder_down_) {
    const TransportStatus status = encoder_.drain(sample.encoder_in);
    if (status != TransportStatus::ok) mark_down(encoder_, status);
  }

  // Each report is read once, here; a report that does not decode stays raw in the sample and the
  // log and is not trusted for state.
  sample.motor.count = 0;
  int motor_lost = 0;
  for (std::size_t i = 0; i < sample.motor_in.count; ++i) {
    const RawReport& raw = sample.motor_in.reports[i];
    if (raw.status != TransportStatus::ok) continue;
    const std::optional<bridge::MotorReading> r =
        motor_board_->read({raw.bytes.data(), raw.length}, raw.time_ns);
    if (!r) continue;
    sample.motor.readings[sample.motor.count++] = *r;
    motor_lost += r->lost_before;
    newest_arm_counts = r->position_counts;
    applied_duty_ = r->applied_duty;
    motor_current_a_ = r->current_a;
    supply_voltage_v_ = r->supply_v;
    have_supply_ = true;
    motor_flags_ = r->status_flags;
    motor_over_temperature_ = r->over_temperature;
    motor_under_voltage_ = r->under_voltage;
  }
  sample.encoder.count = 0;
  int encoder_lost = 0;
  for (std::size_t i = 0; i < sample.encoder_in.count; ++i) {
    const RawReport& raw = sample.encoder_in.reports[i];
    if (raw.status != TransportStatus::ok) continue;
    const std::optional<bridge::EncoderReading> r =
        encoder_board_->read({raw.bytes.data(), raw.length}, raw.time_ns);
    if (!r) continue;
    sample.encoder.readings[sample.encoder.count++] = *r;
    encoder_lost += r->lost_before;
    pendulum_counts_ += r->delta_counts;
    encoder_flags_ = r->flags;
  }
  // When each angle was read: a board that sent nothing this cycle leaves its angle as old as
  // its last report.
  if (sample.motor.count > 0) arm_read_ns_ = sample.motor.readings[sample.motor.count - 1].host_ns;
  if (sample.encoder.count > 0) {
    pendulum_read_ns_ = sample.encoder.readings[sample.encoder.count - 1].host_ns;
  }
  const int motor_fresh = sample.motor.count;
  const int encoder_fresh = sample.encoder.count;
  if (motor_fresh > 0) counters_.motor_reports_seen.store(true, std::memory_order_relaxed);
  if (encoder_fresh > 0) counters_.encoder_reports_seen.store(true, std::memory_order_relaxed);
  cycles_without_motor_ = motor_fresh > 0 ? 0 : cycles_without_motor_ + 1;
  cycles_without_encoder_ = encoder_fresh > 0 ? 0 : cycles_without_encoder_ + 1;
  counters_.motor_lost_reports.fetch_add(motor_lost, std::memory_order_relaxed);
  counters_.encoder_lost_reports.fetch_add(encoder_lost, std::memory_order_relaxed);

  sample.flags = 0;
  if (motor_fresh == 0) sample.flags |= kSampleMotorStale;
  if (encoder_fresh == 0) sample.flags |= kSampleEncoderStale;
  if (motor_lost > 0) sample.flags |= kSampleMotorLost;
  if (encoder_lost > 0) sample.flags |= kSampleEncoderLost;
  // Accounted to the session (and reported) in cycle(), once it is known whether this cycle's
  // sample belongs to one: a start in this very cycle makes it the session's first.
  cycle_motor_lost_ = motor_lost;
  cycle_encoder_lost_ = encoder_lost;
}

void ControlLoop::watch_encoders(const RigSample& sample) noexcept {
  // Only a fresh report says where an encoder is; a board that is late is the stale rules' case.
  if (!(sample.flags & kSampleMotorStale)) {
    const std::int64_t moved = arm_counts_ - watched_arm_counts_;
    watched_arm_counts_ = arm_counts_;
    const bool driven = std::fabs(applied_duty_) >= settings_.safety.stuck_arm_min_duty;
    arm_still_driven_cycles_ = moved == 0 && driven ? arm_still_driven_cycles_ + 1 : 0;
    arm_travel_pendulum_still_rad_ +=
        std::fabs(bridge::counts_to_rad(settings_.arm_encoder, moved));
  }
  if (!(sample.flags & kSampleEncoderStale) && pendulum_counts_ != watched_pendulum_counts_) {
    watched_pendulum_counts_ = pendulum_counts_;
    arm_travel_pendulum_still_rad_ = 0.0;
  }
}

void ControlLoop::begin_session(const SessionRequest& request, std::int64_t now_ns) {
  if (running_) {
    emit_fault("start_refused", "a session is already running", StopReason::none, false, now_ns,
               request.request_id);
    return;
  }
  if (usb_failure_ != TransportStatus::ok) {
    emit_fault("start_refused", "the boards are not reachable", StopReason::none, false, now_ns,
               request.request_id);
    return;
  }
  excitation_ = request.excitation;
  balance_ = request.balance;
  if (balance_) {
    balance_law_ = request.balance_law;
    balance_law_.reset();
  }
  session_ = request.session;
  running_ = true;
  session_start_ns_ = now_ns;
  seq_ = 0;
  session_overruns_ = 0;
  session_motor_lost_ = 0;
  session_encoder_lost_ = 0;
  arm_zero_counts_ = request.has_arm_zero ? request.arm_zero_counts : arm_counts_;
  pendulum_zero_counts_ = pendulum_counts_;
  watched_arm_counts_ = arm_counts_;
  watched_pendulum_counts_ = pendulum_counts_;
  arm_still_driven_cycles_ = 0;
  arm_travel_pendulum_still_rad_ = 0.0;
  counters_.state.store(LoopState::running);

  SessionStartEvent& s = event_.start;
  s.session = request.session;
  s.label = request.label;
  s.request_id = request.request_id;
  s.excitation = excitation_.spec();
  s.balance = balance_;
  s.period_ns = settings_.period_ns;
  s.monotonic_ns = now_ns;
  s.wall_time_ns = wall_time_ns();
  s.arm_zero_counts = arm_zero_counts_;
  s.pendulum_zero_counts = pendulum_zero_counts_;
  emit(LoopEvent::Kind::session_start);
}

void ControlLoop::consider_pending_request(std::int64_t now_ns) {
  if (!have_pending_) {
    if (!requests_.pop(pending_)) return;
    have_pending_ = true;
    pending_since_ns_ = now_ns;
  }
  const auto rest_ns = static_cast<std::int64_t>(settings_.rest_check_s * 1e9);
  if (!running_ && now_ns - rest_anchor_ns_ < rest_ns) {
    const auto wait_ns = static_cast<std::int64_t>(settings_.rest_wait_s * 1e9);
    if (now_ns - pending_since_ns_ < wait_ns) return;  // keep waiting
    have_pending_ = false;
    emit_fault("start_refused", "the pendulum is not at rest: wait until it hangs still",
               StopReason::none, false, now_ns, pending_.request_id);
    return;
  }
  have_pending_ = false;
  begin_session(pending_, now_ns);
}

void ControlLoop::end_session(StopReason reason, const char* detail, std::int64_t now_ns) {
  if (!running_) return;
  running_ = false;
  if (is_fault(reason)) emit_fault(to_string(reason).data(), detail, reason, true, now_ns);
  SessionEndEvent& e = event_.end;
  e.session = session_;
  e.reason = reason;
  copy_text(e.detail, detail);
  e.samples = seq_;
  e.monotonic_ns = now_ns;
  e.wall_time_ns = wall_time_ns();
  emit(LoopEvent::Kind::session_end);
  counters_.last_stop.store(reason);
  counters_.sessions_completed.fetch_add(1);
  counters_.state.store(is_fault(reason) ? LoopState::fault : LoopState::idle);
}

void ControlLoop::cycle(std::int64_t deadline_ns, std::int64_t wake_ns, std::int64_t missed) {
  if (running_) {
    // Requested ends and the duration end before this cycle's reports are taken: the session's
    // samples are exactly its cycles, and the zero command goes out at once.
    const double t_s = static_cast<double>(deadline_ns - session_start_ns_) * 1e-9;
    // Taken, not read: a stop applies to the session it ended, never to a start queued after it.
    StopReason reason = stop_request_.exchange(StopReason::none);
    if (reason == StopReason::none && excitation_.finished(t_s)) {
      reason = StopReason::duration_reached;
    }
    if (reason != StopReason::none) {
      write_command(0.0, settings_.stop_braking_fraction, &event_.end.final_command);
      end_session(reason, "", deadline_ns);
    }
  }

  RigSample& sample = event_.sample;
  sample.monotonic_ns = deadline_ns;
  sample.wake_latency_ns = wake_ns - deadline_ns;
  drain_boards(sample, arm_counts_);
  report_lost_boards(deadline_ns);

  if (std::llabs(pendulum_counts_ - rest_anchor_counts_) > settings_.rest_tolerance_counts) {
    rest_anchor_counts_ = pendulum_counts_;
    rest_anchor_ns_ = deadline_ns;
  }

  if (!running_) {
    // A stop while no session runs cancels every start asked for before it, including one still
    // waiting for the pendulum to rest: no session asked for before an e-stop may start after it.
    const StopReason idle_stop = stop_request_.exchange(StopReason::none);
    if (idle_stop != StopReason::none) {
      // One event per start cancelled, each naming its request: every start gets its verdict.
      const char* why = to_string(idle_stop).data();
      if (have_pending_) {
        emit_fault("start_cancelled", why, StopReason::none, false, deadline_ns,
                   pending_.request_id);
      }
      have_pending_ = false;
      auto cancel = [&](const SessionRequest& r) {
        emit_fault("start_cancelled", why, StopReason::none, false, deadline_ns, r.request_id);
      };
      requests_.consume_all(cancel);
      // An e-stop while idle still brakes the motor (something else may have moved it).
      if (idle_stop == StopReason::estop_command) {
        write_command(0.0, settings_.stop_braking_fraction, nullptr);
      }
    }
  }
  consider_pending_request(deadline_ns);
  if (!running_) {
    if (usb_failure_ != TransportStatus::ok) {
      counters_.state.store(LoopState::fault);
      report_lost_boards(deadline_ns);  // a failed idle e-stop write
      try_reconnect(deadline_ns);
    }
    return;
  }

  session_motor_lost_ += cycle_motor_lost_;
  session_encoder_lost_ += cycle_encoder_lost_;
  char lost[kDetailChars];
  if (cycle_motor_lost_ > 0) {
    std::snprintf(lost, sizeof lost, "%s motor board: %d report(s) lost",
                  settings_.motor_board.c_str(), cycle_motor_lost_);
    emit_fault("lost_reports", lost, StopReason::none, false, deadline_ns);
  }
  if (cycle_encoder_lost_ > 0) {
    std::snprintf(lost, sizeof lost, "%s encoder board: %d report(s) lost, their counts too",
                  settings_.encoder_board.c_str(), cycle_encoder_lost_);
    emit_fault("lost_reports", lost, StopReason::none, false, deadline_ns);
  }
  session_overruns_ += missed;
  if (missed > 0) {
    sample.flags |= kSampleOverrun;
    emit_fault("overrun", "missed cycles skipped", StopReason::none, false, deadline_ns);
  }
  sample.seq = seq_;
  sample.wall_time_ns = wall_time_ns();
  sample.arm_counts = static_cast<std::int32_t>(arm_counts_ - arm_zero_counts_);
  sample.pendulum_counts = pendulum_counts_ - pendulum_zero_counts_;
  sample.arm_angle_rad = bridge::counts_to_rad(settings_.arm_encoder, sample.arm_counts);
  sample.pendulum_angle_rad =
      bridge::counts_to_rad(settings_.pendulum_encoder, sample.pendulum_counts);
  sample.applied_duty = applied_duty_;
  sample.motor_current_a = motor_current_a_;
  sample.supply_voltage_v = supply_voltage_v_;
  sample.motor_status_flags = motor_flags_;
  sample.encoder_flags = encoder_flags_;
  sample.motor_lost_reports = static_cast<std::int32_t>(session_motor_lost_);
  sample.encoder_lost_reports = static_cast<std::int32_t>(session_encoder_lost_);
  sample.overruns = static_cast<std::int32_t>(session_overruns_);

  const double t_s = static_cast<double>(deadline_ns - session_start_ns_) * 1e-9;
  StopReason reason = StopReason::none;
  if (usb_failure_ != TransportStatus::ok) reason = StopReason::usb_error;
  double duty = 0;
  sample.control.present = balance_;
  if (balance_) {
    // Real time, whatever the loop's clock: the law's cost is the figure, also in virtual time.
    const auto law_start = std::chrono::steady_clock::now();
    // How old each angle is (its board's newest report against this cycle's deadline), and
    // whether the board reported this cycle: an angle is used by the filter once.
    control::ReadingTimes times;
    times.arm_age_s = static_cast<double>(deadline_ns - arm_read_ns_) * 1e-9;
    times.pendulum_age_s = static_cast<double>(deadline_ns - pendulum_read_ns_) * 1e-9;
    times.arm_fresh = sample.motor.count > 0;
    times.pendulum_fresh = sample.encoder.count > 0;
    const control::BalanceStep step =
        balance_law_.step(sample.arm_angle_rad, sample.pendulum_angle_rad, times);
    ControlFigures& c = sample.control;
    c.mode = static_cast<std::uint8_t>(step.mode);
    c.upright_error_rad = step.upright_error_rad;
    c.arm_rate_rad_s = step.arm_rate_rad_s;
    c.pendulum_rate_rad_s = step.pendulum_rate_rad_s;
    c.energy_ratio = step.energy_ratio;
    c.law_duty = step.duty;
    c.law_time_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                        std::chrono::steady_clock::now() - law_start)
                        .count();
    duty = step.duty;
    if (step.mode == control::BalanceMode::fallen && reason == StopReason::none) {
      reason = StopReason::pendulum_fell;
    }
  } else {
    duty = excitation_.duty(t_s, sample.arm_angle_rad);
  }
  if (reason == StopReason::none) {
    SafetyInput in;
    in.arm_angle_rad = sample.arm_angle_rad;
    in.commanded_duty = duty;
    in.cycles_without_motor_report = cycles_without_motor_;
    in.cycles_without_encoder_report = cycles_without_encoder_;
    in.motor_over_temperature = motor_over_temperature_;
    in.motor_under_voltage = motor_under_voltage_;
    in.supply_voltage_v = supply_voltage_v_;
    in.have_supply_reading = have_supply_;
    watch_encoders(sample);
    in.arm_still_driven_cycles = arm_still_driven_cycles_;
    in.arm_travel_pendulum_still_rad = arm_travel_pendulum_still_rad_;
    reason = check_safety(settings_.safety, in);
  }
  if (reason == StopReason::none && !queue_has_room(1)) reason = StopReason::log_error;

  if (reason != StopReason::none) {
    // This cycle's reports are logged with the zero command as its command.
    sample.commanded_duty = 0.0;
    write_command(0.0, settings_.stop_braking_fraction, &sample.motor_out);
    if (reason != StopReason::log_error) {
      sample.queued_ns = clock_.now_ns();
      emit(LoopEvent::Kind::sample);
      ++seq_;
    }
    const char* detail =
        reason == StopReason::usb_error ? bridge::to_string(usb_failure_).data() : "";
    char fell[kDetailChars];
    if (reason == StopReason::pendulum_fell) {
      std::snprintf(fell, sizeof fell, "%.1f deg from upright, beyond the fall limit of %.1f deg",
                    std::fabs(sample.control.upright_error_rad) * 180 / std::numbers::pi,
                    balance_law_.spec().region.fall_rad * 180 / std::numbers::pi);
      detail = fell;
    }
    event_.end.final_command.length = 0;  // the sample above carries it
    end_session(reason, detail, deadline_ns);
    return;
  }
  sample.commanded_duty = duty;
  write_command(duty, 0.0, &sample.motor_out);
  sample.queued_ns = clock_.now_ns();
  emit(LoopEvent::Kind::sample);
  ++seq_;
}

void ControlLoop::run() {
  // Start-up (may allocate): enable the pendulum channel, make sure the motor is at zero. A board
  // that fails here is reconnected like one lost later.
  initialise_boards();
  counters_.state.store(usb_failure_ == TransportStatus::ok ? LoopState::idle : LoopState::fault);

  std::int64_t deadline = clock_.now_ns() + settings_.period_ns;
  rest_anchor_ns_ = clock_.now_ns();
  const std::int64_t cpu_start_ns = thread_cpu_time_ns();
  struct CpuTimeOnExit {
    std::atomic<std::int64_t>& out;
    std::int64_t start;
    ~CpuTimeOnExit() { out.store(thread_cpu_time_ns() - start); }
  } cpu_on_exit{counters_.loop_cpu_time_ns, cpu_start_ns};
  try {
    for (;;) {
      if (exit_.load()) {
        if (!running_) {
          write_command(0.0, settings_.stop_braking_fraction, nullptr);
          break;
        }
        // A running session ends in a cycle of its own, so its zero command is logged with it.
        request_stop(StopReason::signal);
      }
      if (exit_when_idle_.load() && !running_ && !have_pending_ &&
          requests_.read_available() == 0) {
        write_command(0.0, settings_.stop_braking_fraction, nullptr);
        break;
      }
      clock_.sleep_until_ns(deadline);
      const std::int64_t wake = clock_.now_ns();
      counters_.clock_ns.store(wake, std::memory_order_relaxed);
      // The whole lateness, before any skipping: an overrun shows in the latency figures too.
      wake_latency_.record(wake - deadline);
      // Late by a period or more: those cycles are gone; skip to the newest deadline passed.
      std::int64_t missed = 0;
      if (wake - deadline >= settings_.period_ns) {
        missed = (wake - deadline) / settings_.period_ns;
        deadline += missed * settings_.period_ns;
        counters_.overruns.fetch_add(missed, std::memory_order_relaxed);
      }
      cycle(deadline, wake, missed);
      counters_.cycles.fetch_add(1, std::memory_order_relaxed);
      deadline += settings_.period_ns;
    }
  } catch (...) {
    // The zero command first: nothing below may delay it.
    try {
      write_command(0.0, settings_.stop_braking_fraction, &event_.end.final_command);
    } catch (...) {
      // The board layer threw again: the zero could not be written. The session still ends and
      // the first exception, the cause, is the one rethrown.
      event_.end.final_command.length = 0;
    }
    end_session(StopReason::exception, "exception in the control loop", clock_.now_ns());
    throw;
  }
}

}  // namespace furuta::daemon
