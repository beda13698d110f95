// furuta_crash_trials: the real furutad on the simulated rig, as a separate process talking UDP
// multicast LCM, treated badly: killed with SIGKILL at seeded random moments, starved of disk (a
// file size limit or a small file system), its logs directory removed or made read-only in the
// middle of a session. After each, the logs are checked with the project's reader and with
// lcm-logplayer, and the samples lost are compared with the flush interval.
//
// Run by tests/daemon/crash_trials_test.sh (inside a network namespace with multicast on lo) and by
// scripts/crash_trials.sh for the long version. Prints `[ measured ]` lines; exits 0 when every
// check passed, 1 otherwise.

#include <fcntl.h>
#include <linux/capability.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "furuta/command_auth/command_auth.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/rig_command_t.hpp"
#include "furuta/rig_fault_t.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/rig_status_t.hpp"
#include "furuta/session_log/session_log.hpp"

namespace {

namespace fs = std::filesystem;
using namespace furuta;
using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

struct Options {
  std::string furutad;
  std::string config;
  std::string work;
  std::string lcm_url;
  std::string scenario = "kill";
  int trials = 200;
  std::uint64_t seed = 1;
  int max_kill_ms = 800;
  int flush_ms = 50;
  int period_ms = 16;
  std::uint64_t fsize_bytes = 96 * 1024;
  bool verbose = false;
  std::string command_key;  // <work>/command.key: starts are signed with it (docs/security.md)
};

// The key furutad is given and starts are signed with.
command_auth::CommandKey g_command_key{};

int g_failures = 0;
void fail(const std::string& what) {
  ++g_failures;
  std::cout << "FAIL: " << what << std::endl;
}

// furutad as a child process. Killed with SIGKILL if still running when this goes away.
class DaemonProcess {
 public:
  DaemonProcess(const Options& options, const fs::path& logs_dir, const fs::path& output,
                std::optional<std::uint64_t> fsize_limit = std::nullopt) {
    std::vector<std::string> args{options.furutad,
                                  "--sim",
                                  "-c",
                                  options.config,
                                  "--logs-dir",
                                  logs_dir.string(),
                                  "--lcm-url",
                                  options.lcm_url,
                                  "--command-key",
                                  options.command_key,
                                  "--daemon-key",
                                  (fs::path(options.work) / "daemon.key").string(),
                                  "--command-state",
                                  (fs::path(options.work) / "command-replay.state").string()};
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      const int fd = ::open(output.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      if (fsize_limit) {
        // An ignored SIGXFSZ survives exec: the writes past the limit then fail with EFBIG.
        ::signal(SIGXFSZ, SIG_IGN);
        const rlimit limit{*fsize_limit, *fsize_limit};
        if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(120);
      }
      if (options.scenario == "dir-readonly") {
        // Root (or root of a user namespace, as in the test) passes any permission check: out of
        // the bounding set, these capabilities are gone after exec too, so a mode of 0555 holds.
        for (const int capability : {CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH, CAP_FOWNER}) {
          if (::prctl(PR_CAPBSET_DROP, capability, 0, 0, 0) != 0 && ::geteuid() == 0) ::_exit(121);
        }
      }
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
  }
  ~DaemonProcess() {
    if (running()) {
      signal(SIGKILL);
      wait();
    }
  }
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  bool running() {
    if (status_) return false;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) status_ = status;
    return !status_;
  }
  void signal(int number) const { ::kill(pid_, number); }
  int wait() {
    if (!status_) {
      int status = 0;
      while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
      }
      status_ = status;
    }
    return *status_;
  }
  // Waits up to `limit` for the exit; nullopt if it is still running.
  std::optional<int> wait_for(milliseconds limit) {
    const auto end = Clock::now() + limit;
    while (running() && Clock::now() < end) std::this_thread::sleep_for(milliseconds(10));
    return status_;
  }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
};

// What the test hears of one session on LCM.
struct HeardSession {
  std::string name;
  std::int64_t samples = 0;
  std::int64_t max_seq = -1;
  std::int64_t last_sample_monotonic_ns = 0;
  bool started = false;
  std::optional<std::string> end_reason;
};

// Everything furutad publishes, by session; replies by request id.
class RigListener {
 public:
  explicit RigListener(const std::string& url) : lcm_(url) {
    if (!lcm_.good()) throw std::runtime_error("cannot open LCM at " + url);
    lcm_.subscribe(session_log::kChannelSample, &RigListener::on_sample, this);
    lcm_.subscribe(session_log::kChannelSession, &RigListener::on_session, this);
    lcm_.subscribe(session_log::kChannelStatus, &RigListener::on_status, this);
    lcm_.subscribe(session_log::kChannelFault, &RigListener::on_fault, this);
  }

  void pump(milliseconds duration) {
    const auto end = Clock::now() + duration;
    for (auto now = Clock::now(); now < end; now = Clock::now()) {
      const auto left = std::chrono::duration_cast<milliseconds>(end - now).count();
      lcm_.handleTimeout(static_cast<int>(std::max<std::int64_t>(1, left)));
    }
  }
  // Until the channel has been quiet for `quiet` (what a killed daemon sent is all in).
  void drain(milliseconds quiet) {
    while (lcm_.handleTimeout(static_cast<int>(quiet.count())) > 0) {
    }
  }
  template <typename Predicate>
  bool pump_until(milliseconds limit, Predicate done) {
    const auto end = Clock::now() + limit;
    while (!done()) {
      if (Clock::now() >= end) return false;
      lcm_.handleTimeout(10);
    }
    return true;
  }

  std::int64_t send(std::int8_t kind, const std::string& label = "", double duration_s = 60.0) {
    furuta::rig_command_t command{};
    command.request_id = ++last_request_id_;
    command.kind = kind;
    command.profile = "bang_bang";
    command.amplitude_duty = 0.15;  // see crash_trials_test.sh: room for the loop's stalls
    command.duration_s = duration_s;
    command.label = label;
    command.seed = 7;
    if (command_auth::moves_motor(command)) {
      const auto signed_command =
          command_auth::sign_command_now(command, g_command_key, "crash-trials");
      lcm_.publish(session_log::kChannelSignedCommand, &signed_command);
    } else {
      lcm_.publish(session_log::kChannelCommand, &command);
    }
    return command.request_id;
  }
  std::optional<furuta::rig_status_t> reply(std::int64_t request_id) const {
    const auto it = replies_.find(request_id);
    if (it == replies_.end()) return std::nullopt;
    return it->second;
  }
  // The session whose name ends with "_label", if heard of.
  HeardSession* session_labelled(const std::string& label) {
    for (auto& [name, s] : sessions_) {
      if (name.size() > label.size() && name.ends_with("_" + label)) return &s;
    }
    return nullptr;
  }
  std::int64_t statuses() const { return statuses_; }
  const furuta::rig_status_t& last_status() const { return last_status_; }
  std::int64_t start_refusals() const { return start_refusals_; }

 private:
  void on_sample(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_sample_t* m) {
    HeardSession& s = sessions_[m->session];
    s.name = m->session;
    ++s.samples;
    if (m->seq > s.max_seq) {
      s.max_seq = m->seq;
      s.last_sample_monotonic_ns = m->monotonic_ns;
    }
  }
  void on_session(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_session_t* m) {
    HeardSession& s = sessions_[m->session];
    s.name = m->session;
    if (m->event == furuta::rig_session_t::EVENT_START) s.started = true;
    if (m->event == furuta::rig_session_t::EVENT_END) s.end_reason = m->end_reason;
  }
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_status_t* m) {
    ++statuses_;
    last_status_ = *m;
    if (m->reply_to_request_id != 0) replies_[m->reply_to_request_id] = *m;
  }
  void on_fault(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_fault_t* m) {
    if (m->reason == "start_refused") ++start_refusals_;
  }

  lcm::LCM lcm_;
  std::map<std::string, HeardSession> sessions_;
  std::map<std::int64_t, furuta::rig_status_t> replies_;
  furuta::rig_status_t last_status_{};
  std::int64_t statuses_ = 0;
  std::int64_t start_refusals_ = 0;
  std::int64_t last_request_id_ = 0;
};

// Starts a session labelled `label`: retries while the daemon or its loop refuses (not ready, not
// at rest, rate limit). Returns the session as heard, or null. A start the daemon accepted is never
// sent again while it may still begin: on a starved machine it can take over a second to be heard
// of, and a second start sent then would run, after a short first one, as a second session with
// the same label.
HeardSession* start_session(RigListener& lcm, const std::string& label, double duration_s,
                            milliseconds limit = milliseconds(10'000)) {
  const auto end = Clock::now() + limit;
  const auto left = [&] {
    return std::max(milliseconds(0), std::chrono::duration_cast<milliseconds>(end - Clock::now()));
  };
  const auto started = [&] {
    const HeardSession* s = lcm.session_labelled(label);
    return s != nullptr && s->started;
  };
  while (Clock::now() < end) {
    const std::int64_t refusals = lcm.start_refusals();
    const std::int64_t id = lcm.send(furuta::rig_command_t::KIND_START_SESSION, label, duration_s);
    lcm.pump_until(std::min(left(), milliseconds(5000)),
                   [&] { return started() || lcm.reply(id).has_value(); });
    if (!started()) {
      const auto reply = lcm.reply(id);
      if (!reply) continue;  // no answer (yet): ask again
      if (reply->request_accepted) {
        // Accepted: the loop starts it or refuses it (a fault); wait for either.
        lcm.pump_until(left(), [&] { return started() || lcm.start_refusals() > refusals; });
      }
    }
    if (started()) return lcm.session_labelled(label);
    lcm.pump(milliseconds(220));  // the rate limit allows 5 commands a second
  }
  return nullptr;
}

// --- checking a log ---

struct LogCheck {
  bool ok = false;
  std::int64_t events = 0;
  std::int64_t samples = 0;
  std::int64_t max_seq = -1;
  std::int64_t last_sample_monotonic_ns = 0;
  bool complete = false;
  std::string end_reason;
};

// Whether lcm-logplayer plays the log to its end: it prints one line per event with -v.
bool logplayer_plays(const fs::path& log, std::int64_t events, std::string& why) {
  const std::string command = "lcm-logplayer -v -s 1000 -l memq:// '" + log.string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) {
    why = "popen failed";
    return false;
  }
  std::int64_t played = 0;
  char line[512];
  while (std::fgets(line, sizeof line, pipe)) {
    if (std::strstr(line, "Channel ")) ++played;
  }
  const int status = ::pclose(pipe);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    why = "lcm-logplayer exited with status " + std::to_string(status);
    return false;
  }
  if (played != events) {
    why = "lcm-logplayer played " + std::to_string(played) + " of " + std::to_string(events) +
          " events";
    return false;
  }
  return true;
}

LogCheck check_log(const fs::path& path, const std::string& context) {
  LogCheck c;
  const session_log::SessionLog log = session_log::load_session_log(path);
  const auto& st = log.read_stats;
  c.events = static_cast<std::int64_t>(st.events);
  c.samples = static_cast<std::int64_t>(log.samples.size());
  c.complete = log.complete();
  if (log.end) c.end_reason = log.end->end_reason;
  const auto bad = [&](const std::string& what) {
    fail(context + ": " + path.filename().string() + ": " + what);
    return c;
  };
  if (st.damaged_regions != 0 || st.truncated_tail || st.bytes_skipped != 0) {
    return bad("not clean after recovery: " + std::to_string(st.damaged_regions) +
               " damaged regions, " + std::to_string(st.bytes_skipped) + " bytes skipped" +
               (st.truncated_tail ? ", truncated tail" : ""));
  }
  if (log.undecodable_events != 0 || log.unknown_channel_events != 0) {
    return bad(std::to_string(log.undecodable_events) + " undecodable events");
  }
  if (!log.start) return bad("no start record (" + std::to_string(st.events) + " events)");
  if (!log.missing_sequence_numbers().empty()) return bad("sample sequence numbers missing");
  if (!log.samples.empty()) {
    if (log.samples.front().seq != 0) return bad("samples do not start at 0");
    c.max_seq = log.samples.back().seq;
    c.last_sample_monotonic_ns = log.samples.back().monotonic_ns;
  }
  std::string why;
  if (!logplayer_plays(path, c.events, why)) return bad(why);
  c.ok = true;
  return c;
}

// Logs of a session labelled `label` in `logs_dir` (finished or recovered).
std::vector<fs::path> logs_labelled(const fs::path& logs_dir, const std::string& label) {
  std::vector<fs::path> found;
  std::error_code ec;
  for (fs::directory_iterator it(logs_dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string leaf = it->path().filename().string();
    if (leaf.find("_" + label + ".") != std::string::npos ||
        leaf.find("_" + label + "-") != std::string::npos) {
      found.push_back(it->path());
    }
  }
  return found;
}

std::size_t partial_logs(const fs::path& logs_dir) {
  std::size_t n = 0;
  std::error_code ec;
  for (fs::directory_iterator it(logs_dir / ".partial", ec), end; !ec && it != end;
       it.increment(ec)) {
    ++n;
  }
  return n;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())) - 1);
  return values[std::min(i, values.size() - 1)];
}

// --- SIGKILL trials ---

struct KillTrial {
  int index = 0;
  std::string label;
  bool early = false;  // killed before asking for a session (start-up, recovery)
  bool short_session = false;
  std::optional<HeardSession> heard;
  std::int64_t kill_monotonic_ns = 0;
};

int run_kill_trials(const Options& options) {
  const fs::path work = options.work;
  const fs::path logs = work / "logs";
  fs::create_directories(logs);
  RigListener lcm(options.lcm_url);
  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<int> kill_after_ms(0, options.max_kill_ms);
  std::uniform_int_distribution<int> early_kill_ms(0, 250);
  std::uniform_int_distribution<int> percent(0, 99);
  const std::int64_t allowed_lost =
      (options.flush_ms + options.period_ms - 1) / options.period_ms + 1;

  std::vector<KillTrial> pending;
  std::vector<double> lost_samples, lost_ms, trial_s;
  int mid_session = 0, early = 0, finished_before_kill = 0, no_session = 0, logs_checked = 0;
  int started_without_log = 0;
  std::int64_t events_checked = 0;

  // Checks every pending trial: their daemon was killed and a later start has recovered the logs.
  const auto check_pending = [&] {
    if (partial_logs(logs) != 0) return;  // recovery cut short too: the next start finishes it
    for (const KillTrial& t : pending) {
      const std::string context = "trial " + std::to_string(t.index);
      const auto found = logs_labelled(logs, t.label);
      // A published sample means its start record had been synced (the recorder forces that sync
      // before any sample): such a session must have left a log. One killed between its start and
      // that sync leaves none (recovery removes a log without one whole event).
      const bool heard_samples = t.heard && t.heard->samples > 0;
      if (found.size() > 1) fail(context + ": " + std::to_string(found.size()) + " logs");
      if (found.empty()) {
        if (heard_samples) fail(context + ": session " + t.heard->name + " left no log");
        if (t.heard && t.heard->started) ++started_without_log;
        continue;
      }
      const LogCheck c = check_log(found.front(), context);
      ++logs_checked;
      events_checked += c.events;
      if (!c.ok || !t.heard) continue;
      const std::int64_t lost = t.heard->max_seq - c.max_seq;
      if (c.complete) {
        if (lost != 0)
          fail(context + ": a finished log lacks " + std::to_string(lost) + " samples");
        continue;
      }
      lost_samples.push_back(static_cast<double>(lost));
      if (c.max_seq >= 0) {
        lost_ms.push_back(static_cast<double>(t.kill_monotonic_ns - c.last_sample_monotonic_ns) *
                          1e-6);
      }
      if (lost > allowed_lost) {
        fail(context + ": " + std::to_string(lost) + " samples lost (published up to seq " +
             std::to_string(t.heard->max_seq) + ", logged up to " + std::to_string(c.max_seq) +
             "; at most " + std::to_string(allowed_lost) + " allowed by flush_interval_ms " +
             std::to_string(options.flush_ms) + ")");
      }
    }
    pending.clear();
  };

  const auto started_at = Clock::now();
  for (int i = 0; i < options.trials; ++i) {
    const auto trial_start = Clock::now();
    KillTrial t;
    t.index = i;
    char label[16];
    std::snprintf(label, sizeof label, "k%05d", i);
    t.label = label;
    t.early = percent(rng) < 10;
    t.short_session = percent(rng) < 10;
    const int kill_ms = t.early ? early_kill_ms(rng) : kill_after_ms(rng);
    {
      const std::int64_t statuses = lcm.statuses();
      DaemonProcess daemon(options, logs, work / "furutad.out");
      if (t.early) {
        lcm.pump(milliseconds(kill_ms));
        ++early;
      } else {
        // The first status comes after recovery: the previous trials' logs are ready.
        if (!lcm.pump_until(milliseconds(20'000), [&] { return lcm.statuses() > statuses; })) {
          fail("trial " + std::to_string(i) + ": furutad did not come up");
          break;
        }
        check_pending();
        HeardSession* s = start_session(lcm, t.label, t.short_session ? 0.3 : 60.0);
        if (!s) {
          fail("trial " + std::to_string(i) + ": no session started");
        } else {
          lcm.pump(milliseconds(kill_ms));
        }
      }
      daemon.signal(SIGKILL);
      t.kill_monotonic_ns = monotonic_ns();
      daemon.wait();
    }
    lcm.drain(milliseconds(20));
    if (HeardSession* s = lcm.session_labelled(t.label)) {
      t.heard = *s;
      if (s->end_reason) {
        ++finished_before_kill;
      } else {
        ++mid_session;
      }
    } else {
      ++no_session;
    }
    if (options.verbose) {
      std::cout << "trial " << i << (t.early ? " early" : "") << " kill after " << kill_ms
                << " ms, heard " << (t.heard ? t.heard->samples : 0) << " samples" << std::endl;
    }
    pending.push_back(t);
    trial_s.push_back(std::chrono::duration<double>(Clock::now() - trial_start).count());
  }
  // A last start recovers the last trial's log; then it is stopped the ordinary way.
  {
    const std::int64_t statuses = lcm.statuses();
    DaemonProcess daemon(options, logs, work / "furutad.out");
    if (!lcm.pump_until(milliseconds(20'000), [&] { return lcm.statuses() > statuses; })) {
      fail("the final furutad did not come up");
    }
    check_pending();
    daemon.signal(SIGTERM);
    const auto status = daemon.wait_for(milliseconds(20'000));
    if (!status || !WIFEXITED(*status) || WEXITSTATUS(*status) != 0) {
      fail("the final furutad did not exit 0 on SIGTERM");
    }
  }
  if (!pending.empty()) fail(std::to_string(pending.size()) + " trials never checked");
  const double total_s = std::chrono::duration<double>(Clock::now() - started_at).count();

  std::cout << "[ measured ] kill trials: " << options.trials << " (seed " << options.seed
            << ", flush_interval_ms " << options.flush_ms << ", kill within " << options.max_kill_ms
            << " ms of the session start; " << early << " killed during start-up/recovery, "
            << mid_session << " mid-session, " << finished_before_kill
            << " after their session had ended, " << no_session << " before any session)"
            << std::endl;
  std::cout << "[ measured ] logs checked: " << logs_checked << " (" << events_checked
            << " events), all readable by load_session_log and lcm-logplayer: "
            << (g_failures == 0 ? "yes" : "NO") << "; " << started_without_log
            << " sessions killed before their first sync left no log" << std::endl;
  std::cout << "[ measured ] samples lost per killed session: max "
            << (lost_samples.empty() ? 0
                                     : *std::max_element(lost_samples.begin(), lost_samples.end()))
            << ", p99 " << quantile(lost_samples, 0.99) << ", median "
            << quantile(lost_samples, 0.5) << " (allowed " << allowed_lost
            << " = flush interval / period + 1)" << std::endl;
  std::cout << "[ measured ] time from the last logged sample to the kill: max "
            << (lost_ms.empty() ? 0 : *std::max_element(lost_ms.begin(), lost_ms.end()))
            << " ms, p99 " << quantile(lost_ms, 0.99) << " ms, median " << quantile(lost_ms, 0.5)
            << " ms" << std::endl;
  std::cout << "[ measured ] " << total_s << " s in all, " << quantile(trial_s, 0.5)
            << " s per trial (median)" << std::endl;
  return g_failures == 0 ? 0 : 1;
}

// --- disk full, logs directory removed or read-only ---

// The last command the log shows written to the motor board: every end must leave it at zero.
std::optional<double> last_logged_duty(const fs::path& path) {
  const session_log::SessionLog log = session_log::load_session_log(path);
  std::optional<double> duty;
  for (const auto& r : log.usb_reports) {
    if (r.board != furuta::rig_usb_report_t::BOARD_MOTOR ||
        r.kind == furuta::rig_usb_report_t::KIND_INPUT) {
      continue;
    }
    bridge::MotorOutput1065 output;
    if (bridge::decode_output_1065(r.bytes, output) == bridge::CodecStatus::ok) {
      duty = output.duty_cycle();
    }
  }
  return duty;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// One scenario: a session that loses its disk or its directory, what the daemon says and does, a
// second session, a clean stop, and then a fresh start that recovers the logs.
int run_disk_scenario(const Options& options) {
  const std::string& scenario = options.scenario;
  const fs::path work = options.work;
  const fs::path logs = work / "logs";  // small-fs: the script mounted a small tmpfs here
  fs::create_directories(logs);
  RigListener lcm(options.lcm_url);
  const std::int64_t allowed_lost =
      (options.flush_ms + options.period_ms - 1) / options.period_ms + 1;
  std::optional<std::uint64_t> fsize;
  if (scenario == "fsize") fsize = options.fsize_bytes;

  std::string first_end, second_outcome;
  std::int64_t first_heard_max_seq = -1;
  {
    const std::int64_t statuses = lcm.statuses();
    DaemonProcess daemon(options, logs, work / "furutad.out", fsize);
    if (!lcm.pump_until(milliseconds(20'000), [&] { return lcm.statuses() > statuses; })) {
      fail(scenario + ": furutad did not come up");
      return 1;
    }
    HeardSession* first = start_session(lcm, "first", 60.0);
    if (!first) {
      fail(scenario + ": the first session did not start");
      return 1;
    }
    lcm.pump(milliseconds(400));
    if (scenario == "dir-removed") {
      fs::remove_all(logs);
    } else if (scenario == "dir-readonly") {
      fs::permissions(logs / ".partial", fs::perms(0555));
      fs::permissions(logs, fs::perms(0555));
      lcm.pump(milliseconds(200));
      lcm.send(furuta::rig_command_t::KIND_STOP);
    }
    // A full disk or a lost directory must end the session by itself, within a few flush
    // intervals of the failure (fsize and small-fs: when the limit is reached).
    if (!lcm.pump_until(milliseconds(30'000), [&] { return first->end_reason.has_value(); })) {
      fail(scenario + ": the first session did not end (" + std::to_string(first->samples) +
           " samples)");
      return 1;
    }
    lcm.drain(milliseconds(50));
    first_end = *first->end_reason;
    first_heard_max_seq = first->max_seq;
    if (!daemon.running()) fail(scenario + ": furutad exited after the failure");
    const std::int64_t id = lcm.send(furuta::rig_command_t::KIND_STATUS_REQUEST);
    lcm.pump_until(milliseconds(2000), [&] { return lcm.reply(id).has_value(); });
    const auto status = lcm.reply(id);
    if (!status) {
      fail(scenario + ": no status reply after the failure");
    } else {
      std::cout << "[ measured ] " << scenario << ": first session ended \"" << first_end
                << "\" after " << first->samples << " samples; status: state " << int(status->state)
                << ", last fault \"" << status->last_fault << "\"" << std::endl;
      if (scenario != "dir-readonly" && !contains(first_end, "log_error")) {
        fail(scenario + ": the first session ended \"" + first_end + "\", not log_error");
      }
      if ((scenario == "fsize" || scenario == "small-fs") &&
          !contains(status->last_fault, "disk_full")) {
        fail(scenario + ": the fault does not say disk_full: " + status->last_fault);
      }
      if (status->last_fault.empty()) fail(scenario + ": no fault in the status");
    }

    // The next session: refused with a reason, or started and ended by the same failure; never a
    // session that runs without a log.
    lcm.pump(milliseconds(250));
    const std::int64_t start_id =
        lcm.send(furuta::rig_command_t::KIND_START_SESSION, "second", 60.0);
    lcm.pump_until(milliseconds(2000), [&] { return lcm.reply(start_id).has_value(); });
    const auto reply = lcm.reply(start_id);
    if (!reply) {
      fail(scenario + ": no reply to the second start");
    } else if (!reply->request_accepted) {
      second_outcome = "refused: " + reply->request_reason;
    } else {
      HeardSession* second = nullptr;
      lcm.pump_until(milliseconds(5000), [&] {
        second = lcm.session_labelled("second");
        return second != nullptr;
      });
      const bool log_works = scenario == "dir-removed" || scenario == "fsize";
      const auto limit = milliseconds(log_works ? (scenario == "fsize" ? 30'000 : 1000) : 5000);
      if (second) lcm.pump_until(limit, [&] { return second->end_reason.has_value(); });
      if (second && !second->end_reason && scenario == "dir-removed") {
        lcm.send(furuta::rig_command_t::KIND_STOP);
        lcm.pump_until(milliseconds(5000), [&] { return second->end_reason.has_value(); });
      }
      if (!second || !second->end_reason) {
        fail(scenario + ": the second session neither refused nor ended");
      } else {
        second_outcome = "accepted, ended \"" + *second->end_reason + "\" after " +
                         std::to_string(second->samples) + " samples";
        if (!log_works && !contains(*second->end_reason, "log_error")) {
          fail(scenario + ": the second session ran without a log: " + second_outcome);
        }
      }
    }
    std::cout << "[ measured ] " << scenario << ": second session " << second_outcome << std::endl;
    daemon.signal(SIGTERM);
    const auto exit_status = daemon.wait_for(milliseconds(20'000));
    if (!exit_status || !WIFEXITED(*exit_status) || WEXITSTATUS(*exit_status) != 0) {
      fail(scenario + ": furutad did not exit 0 on SIGTERM");
    }
  }

  // The stopped daemon's last status must not pass for the next one's first.
  lcm.drain(milliseconds(200));
  // Put things right, start again: recovery keeps what was written.
  if (scenario == "dir-readonly") {
    fs::permissions(logs, fs::perms(0755));
    fs::permissions(logs / ".partial", fs::perms(0755));
  }
  {
    const std::int64_t statuses = lcm.statuses();
    DaemonProcess daemon(options, logs, work / "furutad.out");
    if (!lcm.pump_until(milliseconds(20'000), [&] { return lcm.statuses() > statuses; })) {
      fail(scenario + ": furutad did not come up after the failure");
    }
    daemon.signal(SIGTERM);
    daemon.wait_for(milliseconds(20'000));
  }
  if (partial_logs(logs) != 0) fail(scenario + ": .part files left after recovery");
  const auto first_logs = logs_labelled(logs, "first");
  if (first_logs.size() != 1) {
    fail(scenario + ": " + std::to_string(first_logs.size()) + " logs of the first session");
  } else {
    const LogCheck c = check_log(first_logs.front(), scenario);
    const std::int64_t lost = first_heard_max_seq - c.max_seq;
    std::cout << "[ measured ] " << scenario << ": first log " << first_logs.front().filename()
              << ": " << c.samples << " samples, " << c.events << " events, "
              << (c.complete ? "complete" : "incomplete") << ", readable: " << (c.ok ? "yes" : "NO")
              << "; " << lost << " samples published but not in the log (allowed " << allowed_lost
              << ")" << std::endl;
    if (c.ok && c.samples == 0) fail(scenario + ": nothing of the first session was kept");
    if (c.ok && lost > allowed_lost) fail(scenario + ": too many samples lost");
    // A removed directory is found at a sync, everything written so far saved again, and the log
    // goes on: nothing is lost and the log ends as any other.
    if (scenario == "dir-removed" && c.ok && (lost != 0 || !c.complete)) {
      fail(scenario + ": the log written again after the removal is not whole");
    }
    if (c.ok && c.complete) {
      const auto duty = last_logged_duty(first_logs.front());
      if (!duty || *duty != 0.0) fail(scenario + ": the log's last motor command is not zero");
    }
  }
  for (const fs::path& p : logs_labelled(logs, "second")) check_log(p, scenario + " second");
  return g_failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"furuta_crash_trials: furutad killed, out of disk, or without its logs directory"};
  Options o;
  app.add_option("--furutad", o.furutad)->required();
  app.add_option("--config", o.config, "rig.toml with short flush_interval_ms, rest_check_s 0")
      ->required();
  app.add_option("--work", o.work, "an empty directory")->required();
  app.add_option("--lcm-url", o.lcm_url)->required();
  app.add_option("--scenario", o.scenario)
      ->check(CLI::IsMember({"kill", "fsize", "small-fs", "dir-removed", "dir-readonly"}));
  app.add_option("--trials", o.trials);
  app.add_option("--seed", o.seed);
  app.add_option("--max-kill-ms", o.max_kill_ms);
  app.add_option("--flush-ms", o.flush_ms, "the config's flush_interval_ms");
  app.add_option("--fsize-bytes", o.fsize_bytes);
  app.add_flag("-v,--verbose", o.verbose);
  CLI11_PARSE(app, argc, argv);
  try {
    o.command_key = (fs::path(o.work) / "command.key").string();
    const command_auth::KeyCreation made = command_auth::ensure_command_key(o.command_key, "");
    if (!made.problem.empty()) throw std::runtime_error(made.problem);
    const command_auth::KeyFile key = command_auth::read_command_key(o.command_key);
    if (!key.key) throw std::runtime_error(key.problem);
    g_command_key = *key.key;
    if (o.scenario == "kill") return run_kill_trials(o);
    return run_disk_scenario(o);
  } catch (const std::exception& e) {
    std::cout << "FAIL: " << e.what() << std::endl;
    return 1;
  }
}
