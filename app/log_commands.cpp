// `furuta log info|export-csv` and `furuta replay`: what a session log holds, its samples as CSV,
// and its USB traffic replayed through the daemon.
#include <unistd.h>

#include <bit>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <optional>
#include <ostream>
#include <sstream>
#include <unordered_map>

#include "balance_text.hpp"
#include "commands.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/board_roles.hpp"
#include "furuta/report/run_directory.hpp"
#include "furuta/rig_usb_report_t.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::app {

namespace {

// The last command written to the motor board as the log recorded it: on every way a session ends
// it must be the zero command, so this is what to look at after a fault.
// The motor board's adapter name as the log's carried configuration says (the default without one).
std::string motor_board_of(const session_log::SessionLog& log) {
  if (log.start) {
    try {
      return config::parse_rig_config(log.start->rig_config_toml, "").motor_board.model;
    } catch (const std::exception&) {
      // A configuration that does not load names no board: the default's, as the daemon's.
    }
  }
  return config::RigConfig{}.motor_board.model;
}

std::string last_motor_command(const session_log::SessionLog& log) {
  const furuta::rig_usb_report_t* last = nullptr;
  for (const auto& r : log.usb_reports) {
    if (r.board == furuta::rig_usb_report_t::BOARD_MOTOR &&
        (r.kind == furuta::rig_usb_report_t::KIND_OUTPUT ||
         r.kind == furuta::rig_usb_report_t::KIND_ERROR)) {
      last = &r;
    }
  }
  if (!last) return "no command logged";
  const std::optional<bridge::MotorWrite> write =
      bridge::make_motor_board(motor_board_of(log), {}, {})->read_write(last->bytes);
  if (!write) {
    return "last command undecodable (" + std::to_string(last->bytes.size()) + " bytes)";
  }
  std::ostringstream text;
  text << "last command duty " << write->duty << ", braking " << write->braking_fraction;
  if (last->kind == furuta::rig_usb_report_t::KIND_ERROR)
    text << " (write failed: " << last->status << ")";
  return text.str();
}

// The one rule (session_log::integrity_problems) as every log command reports it: the problems
// under "integrity", a line on err naming the command and the file. 0: intact; 1: a session log
// that is not intact; 2: not a session log at all.
int report_integrity(const char* command, const session_log::SessionLog& log, std::ostream& out,
                     std::ostream& err) {
  const auto problems = session_log::integrity_problems(log);
  if (problems.empty()) {
    out << "  integrity intact\n";
    return 0;
  }
  out << "  integrity not intact\n";
  for (const auto& p : problems) out << "            - " << p.text << "\n";
  const bool foreign =
      session_log::has_problem(problems, session_log::LogProblem::Kind::not_a_session_log);
  err << "furuta " << command << ": " << log.path.string() << (foreign ? ": " : " is not intact: ")
      << session_log::describe(problems) << "\n";
  return foreign ? 2 : 1;
}

// The first field in which a replayed sample differs from the logged one, or "" when none does:
// every field the sample carries, except the session's name (a replay is a session of its own)
// and the wall clock (for people only; a replay runs in virtual time).
std::string_view first_differing_field(const furuta::rig_sample_t& a,
                                       const furuta::rig_sample_t& b) {
  // Doubles compare by their bits: a NaN logged must come back a NaN, and 0.0 is not -0.0.
  const auto same = [](double x, double y) {
    return std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y);
  };
  const std::pair<std::string_view, bool> fields[] = {
      {"seq", a.seq == b.seq},
      {"monotonic_ns", a.monotonic_ns == b.monotonic_ns},
      {"arm_counts", a.arm_counts == b.arm_counts},
      {"pendulum_counts", a.pendulum_counts == b.pendulum_counts},
      {"arm_angle_rad", same(a.arm_angle_rad, b.arm_angle_rad)},
      {"pendulum_angle_rad", same(a.pendulum_angle_rad, b.pendulum_angle_rad)},
      {"commanded_duty", same(a.commanded_duty, b.commanded_duty)},
      {"applied_duty", same(a.applied_duty, b.applied_duty)},
      {"motor_current_a", same(a.motor_current_a, b.motor_current_a)},
      {"supply_voltage_v", same(a.supply_voltage_v, b.supply_voltage_v)},
      {"motor_status_flags", a.motor_status_flags == b.motor_status_flags},
      {"encoder_flags", a.encoder_flags == b.encoder_flags},
      {"motor_report_host_ns", a.motor_report_host_ns == b.motor_report_host_ns},
      {"motor_packet_counter", a.motor_packet_counter == b.motor_packet_counter},
      {"motor_encoder_time", a.motor_encoder_time == b.motor_encoder_time},
      {"encoder_report_host_ns", a.encoder_report_host_ns == b.encoder_report_host_ns},
      {"encoder_packet_ticks", a.encoder_packet_ticks == b.encoder_packet_ticks},
      {"encoder_delta_counts", a.encoder_delta_counts == b.encoder_delta_counts},
      {"motor_lost_reports", a.motor_lost_reports == b.motor_lost_reports},
      {"encoder_lost_reports", a.encoder_lost_reports == b.encoder_lost_reports},
      {"overruns", a.overruns == b.overruns},
      {"flags", a.flags == b.flags},
  };
  for (const auto& [name, equal] : fields) {
    if (!equal) return name;
  }
  return {};
}

}  // namespace

int run_log_info_command(const std::filesystem::path& path, std::ostream& out, std::ostream& err) {
  const session_log::SessionLog log = session_log::load_session_log(path);
  out << path.string() << "\n";
  if (log.start) {
    const auto& s = *log.start;
    out << "  session   " << s.session << (s.label.empty() ? "" : " (" + s.label + ")") << "\n";
    out << "  profile   " << s.profile << ", amplitude " << s.amplitude_duty << ", duration "
        << s.duration_s << " s, seed " << s.seed << ", period " << s.period_ns / 1000 << " us\n";
    out << "  software  " << s.software_version << "\n";
    // Who started it: the signed start the daemon logged (its tag can be checked with the key).
    out << "  started   "
        << (log.start_command ? "by " + log.start_command->sender + " (signed command)"
                              : std::string("unsigned (in-process, a replay, or an older furutad)"))
        << "\n";
  } else {
    out << "  no session start record\n";
  }
  out << "  samples   " << log.samples.size();
  const auto missing = log.missing_sequence_numbers();
  if (!missing.empty()) out << " (" << missing.size() << " sequence numbers missing)";
  out << "\n  usb       " << log.usb_reports.size() << " raw reports\n";
  out << "  faults    " << log.faults.size();
  for (const auto& f : log.faults) {
    if (f.fatal) out << "; fatal: " << f.reason << (f.detail.empty() ? "" : " (" + f.detail + ")");
  }
  if (const auto balance = pipeline::summarize_balance(log))
    out << "\n" << balance_text(*balance);
  else
    out << "\n";
  out << "  motor     " << last_motor_command(log);
  out << "\n  end       "
      << (log.end ? log.end->end_reason + ", " + std::to_string(log.end->samples) + " samples"
                  : std::string("missing: the session was cut short"))
      << "\n";
  const auto& st = log.read_stats;
  out << "  file      " << st.events << " events";
  if (st.damaged_regions > 0) {
    out << ", " << st.damaged_regions << " damaged regions (" << st.bytes_skipped
        << " bytes skipped)";
  }
  if (st.truncated_tail) out << ", truncated tail";
  if (log.undecodable_events > 0) out << ", " << log.undecodable_events << " undecodable";
  out << "\n  digest    sha256:" << log.digest_hex << " over " << log.digested_events << " events";
  if (log.seal) {
    out << (log.seal_digest_matches ? ", as sealed" : ", NOT the sealed one");
  } else {
    out << ", no seal";
  }
  out << "\n";
  if (log.seal && !log.seal->source.empty()) {
    out << "  source    a replay of " << log.seal->source << " (" << log.seal->source_integrity
        << ")\n";
  }
  for (const std::string& note : session_log::integrity_notes(log)) {
    out << "  note      " << note << "\n";
  }
  return report_integrity("log info", log, out, err);
}

int run_log_export_csv_command(const std::filesystem::path& path,
                               const std::filesystem::path& csv_path, std::ostream& out,
                               std::ostream& err) {
  if (csv_path.empty()) {
    err << "furuta log export-csv: -o is empty: give the CSV file to write\n";
    return 2;
  }
  // Opening the output truncates it: were it the log, the log would be gone before it was read.
  if (report::same_file(csv_path, path)) {
    err << "furuta log export-csv: -o " << csv_path.string() << " is the log " << path.string()
        << " itself: writing the CSV would overwrite it; give another file\n";
    return 2;
  }
  const session_log::SessionLog log = session_log::load_session_log(path);
  const auto problems = session_log::integrity_problems(log);
  if (session_log::has_problem(problems, session_log::LogProblem::Kind::not_a_session_log)) {
    err << "furuta log export-csv: " << path.string() << ": " << session_log::describe(problems)
        << "; nothing written\n";
    return 2;
  }
  std::ofstream csv(csv_path);
  if (!csv) {
    err << "furuta log export-csv: cannot write " << csv_path.string() << "\n";
    return 2;
  }
  // Beside each row's values, when each was taken (docs/csv-import.md reads them back): the host
  // time of the newest report behind each angle and its time on the board's own clock
  // (session_log::BoardTimeline; a row without a new report repeats the last), and the command in
  // force on the motor board at the row's end as the board received it (its byte's duty) with the
  // time it was written.
  csv << "seq,t_s,arm_counts,pendulum_counts,q1_rad,q2_rad,commanded_duty,applied_duty,"
         "current_a,supply_v,motor_flags,encoder_flags,motor_lost,encoder_lost,overruns,flags,"
         "arm_time_s,pendulum_time_s,written_duty,written_s,arm_board_reports,pendulum_board_"
         "ticks\n";
  csv << std::setprecision(10);
  const std::int64_t t0 = log.samples.empty() ? 0 : log.samples.front().monotonic_ns;
  const auto seconds = [t0](std::int64_t ns) { return static_cast<double>(ns - t0) * 1e-9; };
  const std::vector<session_log::MotorCommandWrite> writes =
      session_log::motor_command_writes(log, motor_board_of(log));
  std::size_t next_write = 0;
  std::optional<session_log::MotorCommandWrite> written;
  std::optional<std::int64_t> arm_ns, pendulum_ns;
  session_log::BoardTimeline board_time;
  double arm_board = 0, pendulum_board = 0;
  for (std::size_t i = 0; i < log.samples.size(); ++i) {
    const auto& s = log.samples[i];
    if (s.n_motor_reports > 0) arm_ns = s.motor_report_host_ns.back();
    if (s.n_encoder_reports > 0) pendulum_ns = s.encoder_report_host_ns.back();
    for (const std::int16_t counter : s.motor_packet_counter) {
      arm_board = board_time.motor_report(counter);
    }
    for (const std::int32_t ticks : s.encoder_packet_ticks) {
      pendulum_board = board_time.encoder_report(ticks);
    }
    const std::int64_t row_end = i + 1 < log.samples.size()
                                     ? log.samples[i + 1].monotonic_ns
                                     : std::numeric_limits<std::int64_t>::max();
    while (next_write < writes.size() && writes[next_write].time_ns < row_end) {
      written = writes[next_write++];
    }
    csv << s.seq << ',' << seconds(s.monotonic_ns) << ',' << s.arm_counts << ','
        << s.pendulum_counts << ',' << s.arm_angle_rad << ',' << s.pendulum_angle_rad << ','
        << s.commanded_duty << ',' << s.applied_duty << ',' << s.motor_current_a << ','
        << s.supply_voltage_v << ',' << s.motor_status_flags << ',' << s.encoder_flags << ','
        << s.motor_lost_reports << ',' << s.encoder_lost_reports << ',' << s.overruns << ','
        << s.flags << ',' << seconds(arm_ns.value_or(s.monotonic_ns)) << ','
        << seconds(pendulum_ns.value_or(s.monotonic_ns)) << ',' << (written ? written->duty : 0.0)
        << ',' << seconds(written ? written->time_ns : s.monotonic_ns) << ',' << arm_board << ','
        << pendulum_board << '\n';
  }
  csv.close();
  if (!csv) {
    err << "furuta log export-csv: error writing " << csv_path.string() << "\n";
    return 2;
  }
  out << "wrote " << log.samples.size() << " samples to " << csv_path.string() << "\n";
  // The header alone still replaces an older export: the file never shows another log's samples.
  if (log.samples.empty()) {
    err << "furuta log export-csv: " << path.string() << " has no samples"
        << (log.end ? " (the session ended: " + log.end->end_reason + ")" : std::string())
        << (problems.empty() ? "" : "; " + session_log::describe(problems)) << "; wrote "
        << csv_path.string() << " with the header only\n";
    return 1;
  }
  if (!problems.empty()) {
    err << "furuta log export-csv: " << path.string()
        << " is not intact: " << session_log::describe(problems) << "; wrote the "
        << log.samples.size() << " samples it has"
        << (session_log::has_problem(problems, session_log::LogProblem::Kind::missing_samples)
                ? " (the seq column shows where samples are missing)"
                : "")
        << "\n";
    return 1;
  }
  return 0;
}

int run_replay_command(const std::filesystem::path& path, const std::filesystem::path& config_path,
                       std::ostream& out, std::ostream& err) {
  const session_log::SessionLog log = session_log::load_session_log(path);
  const auto problems = session_log::integrity_problems(log);
  if (!log.start) {
    err << "furuta replay: " << path.string() << ": " << session_log::describe(problems) << "\n";
    return 2;
  }
  // The log carries the configuration it ran with; a given file overrides it.
  const config::RigConfig rig =
      config_path.empty()
          ? config::parse_rig_config(log.start->rig_config_toml, path.string() + " (rig config)")
          : config::load_rig_config(config_path);
  daemon::DaemonSettings settings = daemon::daemon_settings_from_config(rig);
  const auto temp =
      std::filesystem::temp_directory_path() / ("furuta-replay-" + std::to_string(::getpid()));
  settings.recorder.logs_dir = temp;
  settings.loop.wait_when_queue_full = true;
  // The loop's first cycle falls on the recorded session's first deadline and the session starts
  // there: the original already passed the rest check (the replayed traffic starts with the
  // session).
  settings.loop.rest_check_s = 0.0;
  daemon::ConnectOptions connect{daemon::BackendChoice::replay, path, true,
                                 log.start->monotonic_ns - log.start->period_ns};
  daemon::RigConnection rig_io = daemon::connect_rig(rig, connect);
  settings.recorder.motor_device = log.start->motor_device;
  settings.recorder.encoder_device = log.start->encoder_device;
  lcm::LCM lcm("memq://");
  std::optional<std::filesystem::path> replay_log;
  {
    daemon::Daemon daemon(settings, *rig_io.motor_link, *rig_io.encoder_link, *rig_io.clock, lcm);
    if (!daemon.start_replayed_session(*log.start, log.controller ? &*log.controller : nullptr)) {
      err << "furuta replay: " << path.string()
          << ": a balance session without a readable controller record\n";
      return 2;
    }
    daemon.loop().exit_when_idle();
    daemon.start();
    daemon.wait();
    replay_log = daemon.recorder().last_log();
  }
  if (!replay_log) {
    err << "furuta replay: the replayed session wrote no log\n";
    std::filesystem::remove_all(temp);
    return 2;
  }
  const session_log::SessionLog again = session_log::load_session_log(*replay_log);
  std::filesystem::remove_all(temp);
  // Matched by sequence number, so that samples missing from the log do not shift the rest; only
  // what both have is compared.
  std::unordered_map<std::int64_t, const furuta::rig_sample_t*> replayed;
  for (const auto& b : again.samples) replayed.emplace(b.seq, &b);
  std::size_t compared = 0, differing = 0;
  std::optional<std::int64_t> first_difference;
  std::string first_field;
  for (const auto& a : log.samples) {
    const auto found = replayed.find(a.seq);
    if (found == replayed.end()) continue;
    ++compared;
    const std::string_view field = first_differing_field(a, *found->second);
    if (!field.empty()) {
      ++differing;
      if (!first_difference) {
        first_difference = a.seq;
        first_field = field;
      }
    }
  }
  const std::size_t logged = log.samples.size();
  out << "replayed " << compared << " of " << logged << " samples";
  if (again.samples.size() > compared) {
    out << " (and " << again.samples.size() - compared << " the log does not have)";
  }
  if (differing > 0) {
    out << ": " << differing << " differ (first at seq " << *first_difference << ", in "
        << first_field << ")\n";
  } else if (compared == logged && again.samples.size() == logged && problems.empty()) {
    out << ": identical\n";
    return 0;
  } else {
    out << ": none of them differ\n";
  }
  if (!problems.empty()) {
    err << "furuta replay: " << path.string()
        << " is not intact: " << session_log::describe(problems) << "; only the " << compared
        << " samples both the log and the replay have were compared\n";
  } else if (compared < logged) {
    err << "furuta replay: the replay stopped after " << compared << " of the log's " << logged
        << " samples\n";
  }
  return 1;
}

}  // namespace furuta::app
