#include "furuta/session_log/session_log.hpp"

#include <algorithm>
#include <climits>
#include <exception>
#include <stdexcept>
#include <string_view>

#include "furuta/firmware_bridge/board_roles.hpp"
#include "log_digest.hpp"

namespace furuta::session_log {

namespace {

// lcm-gen's decoders check each field against the buffer; the lengths and counts they trusted (a
// negative array count reached std::vector::resize and threw, a string length of 0 or INT32_MIN
// threw or read past the buffer) are decode errors since lcmtypes/harden_generated.cmake. The catch
// stays for what is left (an allocation failing). Trailing bytes are refused too: an intact message
// fills its event exactly.
template <typename Message>
bool decode_exactly(const std::vector<std::uint8_t>& data, Message& message) {
  if (data.size() > static_cast<std::size_t>(INT_MAX)) return false;
  const int size = static_cast<int>(data.size());
  try {
    return message.decode(data.data(), 0, size) == size;
  } catch (const std::exception&) {
    return false;
  }
}

// A gap of more than this is not a run of lost samples but a damaged sequence number; listing it
// would only exhaust memory.
constexpr std::size_t kMaxMissingListed = 1'000'000;

}  // namespace

std::vector<std::int64_t> SessionLog::missing_sequence_numbers() const {
  std::vector<std::int64_t> seen;
  seen.reserve(samples.size());
  for (const furuta::rig_sample_t& s : samples) seen.push_back(s.seq);
  std::sort(seen.begin(), seen.end());
  seen.erase(std::unique(seen.begin(), seen.end()), seen.end());

  std::vector<std::int64_t> missing;
  // A session numbers its samples from 0.
  if (!seen.empty() && seen.front() > 0) seen.insert(seen.begin(), -1);
  for (std::size_t i = 1; i < seen.size(); ++i) {
    for (std::int64_t seq = seen[i - 1] + 1; seq < seen[i]; ++seq) {
      if (missing.size() >= kMaxMissingListed) return missing;
      missing.push_back(seq);
    }
  }
  return missing;
}

SessionLog load_session_log(const std::filesystem::path& path) {
  SessionLog log;
  log.path = path;
  LcmLogReader reader(path);
  LogEvent event;
  std::uint64_t damaged_so_far = 0;
  detail::LogDigest digest;
  std::int64_t utime_before = 0;
  while (reader.next(event)) {
    const std::string_view channel = event.channel;
    if (log.seal) {
      ++log.events_after_seal;
    } else if (channel != kChannelSeal) {
      digest.add(event.event_number, event.utime, channel, event.data);
      if (channel == kChannelSample) ++log.digested_samples;
    }
    if (reader.stats().damaged_regions != damaged_so_far) {
      damaged_so_far = reader.stats().damaged_regions;
      if (!log.samples.empty() && (log.damage_before_sample.empty() ||
                                   log.damage_before_sample.back() != log.samples.size())) {
        log.damage_before_sample.push_back(log.samples.size());
      }
    }
    bool decoded = true;
    if (channel == kChannelSeal) {
      furuta::rig_log_seal_t seal;
      decoded = decode_exactly(event.data, seal);
      if (decoded && !log.seal) {
        log.seal = std::move(seal);
        log.digested_events = digest.events();
        const detail::Digest value = digest.value();
        log.digest_hex = detail::hex(value);
        log.seal_digest_matches = log.seal->digest_algorithm == detail::kDigestAlgorithm &&
                                  std::equal(log.seal->digest.begin(), log.seal->digest.end(),
                                             value.begin(), value.end());
        log.seal_header_matches =
            event.event_number == log.seal->events && event.utime == utime_before;
      }
    } else if (channel == kChannelSession) {
      furuta::rig_session_t session;
      decoded = decode_exactly(event.data, session);
      if (decoded) {
        if (session.event == furuta::rig_session_t::EVENT_START) {
          ++log.start_records;
          if (!log.start) log.start = std::move(session);
        } else if (session.event == furuta::rig_session_t::EVENT_END) {
          ++log.end_records;
          log.end = std::move(session);
        } else {
          decoded = false;  // a session record that is neither start nor end means nothing
        }
      }
    } else if (channel == kChannelSample) {
      furuta::rig_sample_t sample;
      decoded = decode_exactly(event.data, sample);
      if (decoded) {
        if (log.start && sample.session != log.start->session) ++log.foreign_samples;
        log.samples.push_back(std::move(sample));
      }
    } else if (channel == kChannelUsb) {
      furuta::rig_usb_report_t report;
      decoded = decode_exactly(event.data, report);
      if (decoded) log.usb_reports.push_back(std::move(report));
    } else if (channel == kChannelFault) {
      furuta::rig_fault_t fault;
      decoded = decode_exactly(event.data, fault);
      if (decoded) log.faults.push_back(std::move(fault));
    } else if (channel == kChannelControl) {
      furuta::rig_control_t control;
      decoded = decode_exactly(event.data, control);
      if (decoded) log.control.push_back(std::move(control));
    } else if (channel == kChannelController) {
      furuta::rig_controller_t controller;
      decoded = decode_exactly(event.data, controller);
      if (decoded && !log.controller) log.controller = std::move(controller);
    } else if (channel == kChannelSignedCommand) {
      furuta::rig_signed_command_t command;
      decoded = decode_exactly(event.data, command);
      if (decoded && !log.start_command) log.start_command = std::move(command);
    } else {
      ++log.unknown_channel_events;
    }
    if (!decoded) ++log.undecodable_events;
    utime_before = event.utime;
  }
  log.read_stats = reader.stats();
  if (!log.seal) {
    log.digested_events = digest.events();
    log.digest_hex = detail::hex(digest.value());
  }
  return log;
}

LogWriteStatus write_seal(LcmLogWriter& log, const std::string& session, std::int64_t samples,
                          const SealSource& source) {
  furuta::rig_log_seal_t seal;
  seal.session = session;
  seal.events = static_cast<std::int64_t>(log.events_written());
  seal.samples = samples;
  seal.digest_algorithm = detail::kDigestAlgorithm;
  seal.digest = log.digest();
  seal.digest_size = static_cast<std::int32_t>(seal.digest.size());
  seal.source = source.source;
  seal.source_integrity = source.integrity;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(seal.getEncodedSize()));
  seal.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return log.write(kChannelSeal, log.last_utime(), bytes);
}

double BoardTimeline::motor_report(std::int16_t packet_counter) {
  const auto counter = static_cast<std::uint8_t>(packet_counter);
  if (last_counter_) reports_ += static_cast<std::uint8_t>(counter - *last_counter_);
  last_counter_ = counter;
  return reports_;
}

double BoardTimeline::encoder_report(std::int32_t packet_ticks) {
  ticks_ = ticks_ ? *ticks_ + packet_ticks : 0.0;
  return *ticks_;
}

std::vector<MotorCommandWrite> motor_command_writes(const SessionLog& log,
                                                    std::string_view motor_board) {
  const auto board = bridge::make_motor_board(motor_board, {}, {});
  std::vector<MotorCommandWrite> out;
  for (const furuta::rig_usb_report_t& r : log.usb_reports) {
    if (r.board != furuta::rig_usb_report_t::BOARD_MOTOR ||
        r.kind != furuta::rig_usb_report_t::KIND_OUTPUT) {
      continue;
    }
    const std::optional<bridge::MotorWrite> w = board->read_write(r.bytes);
    if (!w) continue;
    out.push_back({r.time_ns, w->duty, w->acceleration_pct_per_s, w->braking_fraction});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.time_ns < b.time_ns; });
  return out;
}

std::vector<MotorInputReport> motor_input_reports(const SessionLog& log,
                                                  std::string_view motor_board) {
  const auto board = bridge::make_motor_board(motor_board, {}, {});
  std::vector<MotorInputReport> out;
  for (const furuta::rig_usb_report_t& r : log.usb_reports) {
    if (r.board != furuta::rig_usb_report_t::BOARD_MOTOR ||
        r.kind != furuta::rig_usb_report_t::KIND_INPUT) {
      continue;
    }
    const std::optional<bridge::MotorReading> m = board->read(r.bytes, r.time_ns);
    if (!m) continue;
    out.push_back(
        {r.time_ns, static_cast<std::int32_t>(m->position_counts), m->applied_duty, m->supply_v});
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.time_ns < b.time_ns; });
  return out;
}

bridge::UsbTrace usb_trace_from_log(const SessionLog& log, std::int8_t board) {
  const std::string where = " in " + log.path.string();
  if (board != furuta::rig_usb_report_t::BOARD_MOTOR &&
      board != furuta::rig_usb_report_t::BOARD_ENCODER) {
    throw std::invalid_argument("usb_trace_from_log: unknown board " + std::to_string(board));
  }
  if (!log.start) {
    throw std::runtime_error("usb_trace_from_log: no session start record" + where);
  }
  const bool motor = board == furuta::rig_usb_report_t::BOARD_MOTOR;
  const std::string& device_line = motor ? log.start->motor_device : log.start->encoder_device;
  if (device_line.empty()) {
    throw std::runtime_error(std::string("usb_trace_from_log: the start record has no ") +
                             (motor ? "motor" : "encoder") + " device" + where);
  }

  bridge::UsbTrace trace;
  trace.device = bridge::parse_trace_device_line(device_line);
  for (const furuta::rig_usb_report_t& r : log.usb_reports) {
    if (r.board != board) continue;
    bridge::TraceEvent e;
    e.time_ns = r.time_ns;
    switch (r.kind) {
      case furuta::rig_usb_report_t::KIND_INPUT:
        e.kind = bridge::TraceEventKind::input;
        // The same limit the trace parser applies: the replay buffer holds no more.
        if (r.bytes.size() > bridge::kMaxReportBytes) {
          throw std::runtime_error("usb_trace_from_log: input report of " +
                                   std::to_string(r.bytes.size()) + " bytes at " +
                                   std::to_string(r.time_ns) + " ns" + where);
        }
        e.bytes = r.bytes;
        break;
      case furuta::rig_usb_report_t::KIND_OUTPUT:
        e.kind = bridge::TraceEventKind::output;
        e.bytes = r.bytes;
        break;
      case furuta::rig_usb_report_t::KIND_ERROR: {
        e.kind = bridge::TraceEventKind::error;
        const std::optional<bridge::TransportStatus> status =
            bridge::transport_status_from_string(r.status);
        if (!status || *status == bridge::TransportStatus::ok) {
          throw std::runtime_error("usb_trace_from_log: USB error with status '" + r.status +
                                   "' at " + std::to_string(r.time_ns) + " ns" + where);
        }
        e.status = *status;
        break;
      }
      default:
        throw std::runtime_error("usb_trace_from_log: USB report of unknown kind " +
                                 std::to_string(r.kind) + " at " + std::to_string(r.time_ns) +
                                 " ns" + where);
    }
    trace.events.push_back(std::move(e));
  }
  if (log.end) {
    trace.events.push_back(
        bridge::TraceEvent{log.end->monotonic_ns, bridge::TraceEventKind::end, {}, {}});
  }
  return trace;
}

}  // namespace furuta::session_log
