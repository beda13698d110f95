// furutad: the rig daemon. Thin: configuration in, boards opened, the Daemon run until a signal.
#include <signal.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <iostream>
#include <thread>

#include "furuta/command_auth/command_auth.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/daemon/daemon.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/firmware_bridge/usb_trace.hpp"
#include "furuta/session_log/lcm_log.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"

namespace {

using namespace furuta;

// Signals are taken synchronously on one thread (sigwait), so no code runs in signal context and
// the loop thread never sees them.
sigset_t termination_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  return set;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"furutad: runs the rotary pendulum rig (excitation, safety, LCM, session logs)",
               "furutad"};
  // Every option whose default is a plain value shows it in --help (set before they are added).
  app.option_defaults()->always_capture_default();
  std::string config_path = config::default_rig_config_path().string();
  bool simulated = false;
  std::string replay_log;
  bool replay_not_intact = false;
  bool require_rt = false;
  std::string logs_dir;
  std::string lcm_url;
  std::string command_key;
  std::string daemon_key;
  std::string command_state;
  bool create_command_key = false;
  app.add_option("-c,--config", config_path, "Rig configuration (TOML) read at start")
      ->check(CLI::ExistingFile);
  app.add_flag("--sim", simulated, "Drive the simulated rig instead of the USB boards");
  app.add_option("--replay", replay_log,
                 "Run a logged session again against its recorded USB traffic, in real time, then "
                 "exit")
      ->check(CLI::ExistingFile);
  app.add_flag("--replay-not-intact", replay_not_intact,
               "Replay a log that is not intact (refused otherwise); the new log's seal records "
               "the source's problems, so it is not taken for a whole session either");
  app.add_flag("--require-rt", require_rt, "Fail if the real-time set-up is refused");
  app.add_option("--logs-dir", logs_dir, "Where session logs go (overrides the configuration)");
  app.add_option("--lcm-url", lcm_url, "LCM URL (overrides the configuration)");
  app.add_option("--command-key", command_key,
                 "The key starts are signed with (overrides [daemon] command_key_file); created "
                 "when missing");
  app.add_option("--daemon-key", daemon_key,
                 "The key this daemon signs its answers with (overrides [daemon] "
                 "daemon_key_file); its public half is then beside it, named .pub for its "
                 "extension");
  app.add_option("--command-state", command_state,
                 "Where the replay floor is kept across restarts (overrides [daemon] "
                 "command_state_file)");
  app.add_flag("--create-command-key", create_command_key,
               "Create the command key and the daemon's key pair where missing (the secrets "
               "mode 0640, group furuta; the public key 0644), check them, then exit: what the "
               "package and the unit's ExecStartPre run as root. Exit 2 when a key or its "
               "directory fails a check");
  app.set_version_flag("--version", daemon::kSoftwareVersion);
  app.footer(
      "Exit status: 0 stopped as asked (a signal, or the end of --replay); 1 the control loop "
      "failed while running; 2 not started: bad usage or configuration, the boards or LCM "
      "unusable, or --require-rt refused. An unusable logs directory does not stop it: it "
      "starts, says so, and refuses every session start until the directory can be written.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11's usage codes (100 and up) folded into the rule; --help and --version are 0.
    return app.exit(e) == 0 ? 0 : 2;
  }

  // Before any thread exists, so every thread inherits the mask.
  const sigset_t signals = termination_signals();
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  try {
    const config::RigConfig rig = config::load_rig_config(config_path);
    daemon::DaemonSettings settings = daemon::daemon_settings_from_config(rig);
    if (!logs_dir.empty()) settings.recorder.logs_dir = logs_dir;
    if (lcm_url.empty()) lcm_url = rig.daemon.lcm_url;
    if (require_rt) settings.realtime.enabled = true;

    // Who may start sessions, and the key the daemon's answers are signed with
    // (docs/security.md). Missing keys are made here on first start (the unit makes them as root
    // before, so they get group furuta); a key that cannot be read or made leaves the daemon
    // running, since stop and e-stop need no key: every start is refused, or the answers go out
    // unsigned.
    if (command_key.empty()) command_key = rig.daemon.command_key_file;
    std::filesystem::path public_key_path = rig.daemon.daemon_public_key_file;
    if (daemon_key.empty()) {
      daemon_key = rig.daemon.daemon_key_file;
    } else {
      public_key_path = std::filesystem::path(daemon_key).replace_extension(".pub");
    }
    settings.command_auth.state_file =
        command_state.empty() ? rig.daemon.command_state_file : command_state;
    std::vector<std::string> key_problems;
    for (const std::string& path : {command_key, daemon_key}) {
      if (std::string why = command_auth::key_directory_problem(path); !why.empty()) {
        key_problems.push_back(why);
        continue;
      }
      const command_auth::KeyCreation creation = command_auth::ensure_command_key(path, "furuta");
      if (creation.created) std::cerr << "furutad: created the key " << path << "\n";
      if (!creation.problem.empty()) key_problems.push_back(creation.problem);
    }
    command_auth::KeyFile key = command_auth::read_command_key(command_key);
    const command_auth::KeyFile signing_key = command_auth::read_command_key(daemon_key);
    if (signing_key.key) {
      const auto public_key = command_auth::daemon_public_key(*signing_key.key);
      if (create_command_key) {
        if (std::string why = command_auth::write_daemon_public_key(public_key_path, public_key);
            !why.empty()) {
          key_problems.push_back(why);
        }
      } else if (command_auth::read_daemon_public_key(public_key_path).key != public_key) {
        std::cerr << "furutad: WARNING: " << public_key_path.string()
                  << " is missing or is not the public half of " << daemon_key
                  << ": tools will not trust this daemon's answers (furutad "
                     "--create-command-key as root writes it)\n";
      }
    }
    if (create_command_key) {
      if (!key.key) key_problems.push_back(key.problem);
      if (!signing_key.key) key_problems.push_back(signing_key.problem);
      for (const std::string& why : key_problems) std::cerr << "furutad: " << why << "\n";
      return key_problems.empty() ? 0 : 2;
    }
    for (const std::string& why : key_problems) std::cerr << "furutad: WARNING: " << why << "\n";
    if (std::string why = command_auth::key_directory_problem(command_key); !why.empty()) {
      key.key.reset();  // a key anyone could have planted proves nothing
      key.problem = why;
    }
    if (key.key) {
      settings.command_key = key.key;
    } else {
      settings.command_key_problem = key.problem;
      std::cerr << "furutad: WARNING: " << key.problem
                << "; every start is refused (stop, e-stop and status still work)\n";
    }
    if (signing_key.key && command_auth::key_directory_problem(daemon_key).empty()) {
      settings.daemon_key = signing_key.key;
    } else {
      std::cerr << "furutad: WARNING: no key to sign answers with ("
                << (signing_key.key ? command_auth::key_directory_problem(daemon_key)
                                    : signing_key.problem)
                << "): tools that check answers will ignore this daemon's\n";
    }

    // A daemon that cannot log must say so now, not at the first start. It still comes up: it is
    // what writes the zero command to a motor board left driving by a daemon killed mid-session,
    // and a directory can come back (a mount, a permission) without a restart. Until then every
    // start is refused with this reason and the status says it (daemon/README.md, "Logs"). As a
    // systemd service, exiting here would leave no one to zero the motor and, with Restart=, loop
    // on the same error; running and refusing starts keeps the rig safe and the reason visible
    // in `furuta status` and the journal (the help's exit rule says so).
    if (std::string why = session_log::logs_dir_problem(settings.recorder.logs_dir, 0);
        !why.empty()) {
      std::cerr << "furutad: WARNING: cannot log sessions in "
                << settings.recorder.logs_dir.string() << ": " << why
                << "; every start is refused until it can (set [daemon] logs_dir or --logs-dir to "
                   "a writable directory; the systemd unit may write under /var/lib/furuta only)\n";
    }

    // A log that cannot be recovered now (an I/O error, the disk gone) stays as it is
    // for the next start; the daemon must still come up to keep the rig safe and say why.
    try {
      for (const auto& recovered : session_log::recover_partial_logs(settings.recorder.logs_dir)) {
        if (recovered.discarded) {
          std::cerr << "furutad: removed " << recovered.path.string()
                    << ": a session killed before its log held one whole event\n";
          continue;
        }
        std::cerr << "furutad: recovered a session cut short: " << recovered.path.string() << " ("
                  << recovered.stats.events << " events kept, " << recovered.bytes_dropped
                  << " bytes of unfinished tail dropped)\n";
      }
    } catch (const std::exception& e) {
      std::cerr << "furutad: cannot recover the logs of sessions cut short (left for the next "
                   "start): "
                << e.what() << "\n";
    }

    daemon::ConnectOptions connect;
    if (simulated) connect.backend = daemon::BackendChoice::simulated;
    std::optional<session_log::SessionLog> replayed;
    if (!replay_log.empty()) {
      replayed = session_log::load_session_log(replay_log);
      const auto problems = session_log::integrity_problems(*replayed);
      if (!replayed->start) throw std::runtime_error(replay_log + ": no session start record");
      if (!problems.empty() && !replay_not_intact) {
        std::cerr << "furutad: --replay " << replay_log
                  << " is not intact: " << session_log::describe(problems)
                  << "; refused (--replay-not-intact replays it, recording that in the new "
                     "log)\n";
        return 2;
      }
      if (replayed->samples.empty()) {
        std::cerr << "furutad: --replay " << replay_log << ": the log holds no samples to replay\n";
        return 2;
      }
      // The new log says where its data came from and in what state, so that a replay of a
      // damaged log never passes for a whole session.
      settings.recorder.seal_source = {
          replay_log + " sha256:" + replayed->digest_hex,
          problems.empty() ? std::string(session_log::kIntact) : session_log::describe(problems)};
      connect.backend = daemon::BackendChoice::replay;
      connect.replay_log = replay_log;
      // The loop's first cycle is the recorded session's first: the rest check passed back then.
      connect.virtual_start_ns = replayed->start->monotonic_ns - replayed->start->period_ns;
      settings.loop.rest_check_s = 0.0;
    }
    daemon::RigConnection rig_io = daemon::connect_rig(rig, connect);
    for (const std::string& warning : rig_io.warnings) std::cerr << "furutad: " << warning << "\n";
    settings.recorder.motor_device = bridge::format_trace_device_line(rig_io.motor->device_info());
    settings.recorder.encoder_device =
        bridge::format_trace_device_line(rig_io.encoder->device_info());

    lcm::LCM lcm(lcm_url);
    if (!lcm.good()) {
      std::cerr << "furutad: cannot open LCM at " << lcm_url << "\n";
      return 2;
    }
    settings.command_url = lcm_url;
    daemon::Daemon daemon(settings, *rig_io.motor_link, *rig_io.encoder_link, *rig_io.clock, lcm);
    if (!daemon.command_state_problem().empty()) {
      std::cerr << "furutad: WARNING: " << daemon.command_state_problem() << "\n";
    }
    if (const auto dir = settings.command_auth.state_file.parent_path();
        ::access(dir.empty() ? "." : dir.c_str(), W_OK) != 0) {
      std::cerr << "furutad: WARNING: cannot write the replay floor in " << dir.string() << ": "
                << std::strerror(errno)
                << "; every start is refused until it can ([daemon] command_state_file)\n";
    }
    if (replayed) {
      if (!daemon.start_replayed_session(*replayed->start,
                                         replayed->controller ? &*replayed->controller : nullptr)) {
        std::cerr << "furutad: cannot replay " << replay_log
                  << ": a balance session without a readable controller record\n";
        return 2;
      }
      daemon.loop().exit_when_idle();
    }
    const daemon::RealtimeResult rt = daemon.start();
    for (const std::string& refusal : rt.refused) {
      std::cerr << "furutad: real-time set-up refused: " << refusal << "\n";
    }
    if (require_rt && !rt.complete(settings.realtime)) {
      std::cerr << "furutad: --require-rt: stopping\n";
      daemon.stop(daemon::StopReason::signal);
      daemon.wait();
      return 2;
    }
    std::cerr << "furutad: running on " << rig_io.description << ", period "
              << settings.loop.period_ns / 1000 << " us, logs in "
              << settings.recorder.logs_dir.string() << ", LCM " << lcm_url << "\n";

    // The signal thread: the first SIGINT/SIGTERM stops the daemon (motor to zero, log closed).
    std::atomic<bool> done{false};
    std::thread signal_thread([&] {
      int signal_number = 0;
      // SIGTERM from ourselves wakes this thread when the daemon ends on its own.
      sigwait(&signals, &signal_number);
      if (!done.load()) {
        std::cerr << "furutad: " << strsignal(signal_number) << ": stopping\n";
        daemon.stop(daemon::StopReason::signal);
      }
    });

    // systemd: READY once the boards answer; the watchdog is fed only while the loop cycles.
    // STATUS (`systemctl status furutad`) says when sessions cannot be logged.
    std::thread notify_thread([&] {
      bool ready_sent = false;
      std::string logs_problem;
      std::int64_t last_heartbeat = -1;
      std::uint64_t watchdog_usec = 0;
      const bool watchdog = sd_watchdog_enabled(0, &watchdog_usec) > 0;
      while (!done.load()) {
        const bool announce = !ready_sent && daemon.ready();
        if (announce || (ready_sent && daemon.logs_problem() != logs_problem)) {
          logs_problem = daemon.logs_problem();
          const std::string state =
              std::string(announce ? "READY=1\n" : "") + "STATUS=running" +
              (logs_problem.empty() ? "" : "; starts refused: " + logs_problem);
          sd_notify(0, state.c_str());
          ready_sent = true;
        }
        const std::int64_t beat = daemon.heartbeat();
        if (watchdog && beat != last_heartbeat) sd_notify(0, "WATCHDOG=1");
        last_heartbeat = beat;
        std::this_thread::sleep_for(std::chrono::milliseconds(
            watchdog ? std::max<std::uint64_t>(watchdog_usec / 4000, 10) : 100));
      }
    });

    int status = 0;
    try {
      daemon.wait();
    } catch (const std::exception& e) {
      std::cerr << "furutad: control loop failed: " << e.what() << "\n";
      status = 1;
    }
    sd_notify(0, "STOPPING=1");
    done.store(true);
    pthread_kill(signal_thread.native_handle(), SIGTERM);
    signal_thread.join();
    notify_thread.join();
    return status;
  } catch (const config::ConfigError& e) {
    std::cerr << "furutad: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {  // before the loop ran: the boards, a log, the USB bus
    std::cerr << "furutad: " << e.what() << "\n";
    return 2;
  }
}
