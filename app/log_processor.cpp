// The identification trigger (log_processor.hpp) and `furuta process-logs [DIR] [--watch]`.
#include "log_processor.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/inotify.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <ctime>
#include <fstream>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <tuple>

#include "commands.hpp"
#include "furuta/daemon/rig_connection.hpp"
#include "furuta/pipeline/intake.hpp"
#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/json.hpp"
#include "furuta/report/outputs.hpp"
#include "furuta/report/run_directory.hpp"
#include "furuta/session_log/log_integrity.hpp"
#include "furuta/session_log/session_log.hpp"

namespace furuta::app {

namespace {

namespace fs = std::filesystem;

constexpr const char* kLogExtension = ".lcmlog";
constexpr const char* kJournal = ".commit";
constexpr const char* kTempPrefix = ".tmp-";

std::runtime_error system_error_for(const std::string& what, const fs::path& path) {
  return std::runtime_error(what + " " + path.string() + ": " + std::strerror(errno));
}

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// flock on the directory itself rather than on a lock file: opening a file for writing and closing
// it is an event for the path unit's PathChanged, and would trigger another pass after every pass.
class DirectoryLock {
 public:
  explicit DirectoryLock(const fs::path& dir)
      : fd_(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC)) {
    if (fd_.get() < 0) throw system_error_for("cannot open", dir);
    while (::flock(fd_.get(), LOCK_EX) != 0) {
      if (errno != EINTR) throw system_error_for("cannot lock", dir);
    }
  }

 private:
  FileDescriptor fd_;  // closing it releases the lock
};

// A rename or a new file is durable only once its directory is synced.
void sync_path(const fs::path& path, bool directory) {
  FileDescriptor fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC | (directory ? O_DIRECTORY : 0)));
  if (fd.get() < 0 || ::fsync(fd.get()) != 0) throw system_error_for("cannot sync", path);
}
void sync_directory(const fs::path& dir) {
  sync_path(dir, true);
}

// Every file of an identification reaches the disk before the directory is renamed into place:
// after a power cut, a directory under its final name is complete.
void sync_tree(const fs::path& dir) {
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    sync_path(entry.path(), entry.is_directory());
  }
  sync_directory(dir);
}

// Written beside, synced, renamed over: readers see the old text or the new, never half.
void write_durably(const fs::path& path, const std::string& text) {
  const fs::path temp = path.parent_path() / ("." + path.filename().string() + ".tmp");
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) throw std::runtime_error("cannot write " + temp.string());
  }
  sync_path(temp, false);
  fs::rename(temp, path);
  sync_directory(path.parent_path());
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Session names are unique across the logs directory and its done/ and failed/ (the daemon checks),
// so a clash means a log was copied back by hand: keep both rather than overwrite.
fs::path free_name_in(const fs::path& dir, const fs::path& leaf) {
  fs::path target = dir / leaf;
  std::string stem = leaf.string();
  std::string extension;
  if (stem.size() > std::strlen(kLogExtension) &&
      stem.ends_with(kLogExtension)) {  // keep .lcmlog last
    extension = kLogExtension;
    stem.resize(stem.size() - extension.size());
  }
  for (int n = 2; fs::exists(target); ++n) {
    target = dir / (stem + "-" + std::to_string(n) + extension);
  }
  return target;
}

fs::path move_into(const fs::path& file, const fs::path& dir) {
  const fs::path target = free_name_in(dir, file.filename());
  fs::rename(file, target);
  return target;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return stamp;
}

std::string trimmed(std::string text) {
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  return text;
}

// The logs directory is the daemon's (or the user's): never created here, where a mistyped name
// would become an empty tree and a pass that finds nothing to do.
void require_logs_directory(const fs::path& dir) {
  const fs::file_status status = fs::status(dir);
  if (!fs::exists(status)) throw std::runtime_error(dir.string() + ": no such directory");
  if (!fs::is_directory(status)) throw std::runtime_error(dir.string() + ": not a directory");
}

// Why the identifications cannot go to `identifications_dir`, or "" when they can (it is created
// here when absent). Checked before done/ and failed/ are made, so that an unusable one changes
// nothing. Never the logs directory or one of the trigger's own directories in it: logs and
// identifications would mix, and the pass would wait forever on the lock it already holds.
std::string identifications_dir_problem(const fs::path& logs_dir,
                                        const fs::path& identifications_dir) {
  if (identifications_dir.empty()) return "an empty path names no directory";
  for (const fs::path& own :
       {logs_dir, logs_dir / "done", logs_dir / "failed", logs_dir / ".partial"}) {
    if (report::same_file(identifications_dir, own)) {
      return "is " +
             (own == logs_dir ? "the logs directory"
                              : own.string() +
                                    ", inside the logs "
                                    "directory " +
                                    logs_dir.string()) +
             ": the identifications need a directory of their own";
    }
  }
  return report::writable_directory_problem(identifications_dir).value_or("");
}

// A complete log waiting in the directory, as far as the trigger needs to know it.
struct PendingLog {
  fs::path path;
  std::string label;
  std::string problem;  // empty: fit to identify
  std::int64_t started_wall_ns = 0;
};

// Only a complete, undamaged session goes into an automatic identification; anything else is
// set aside with what is wrong, for a person to look at.
PendingLog examine(const fs::path& path) {
  PendingLog pending{path, "", "", 0};
  session_log::SessionLog log;
  try {
    log = session_log::load_session_log(path);
  } catch (const std::exception& e) {
    pending.problem = std::string("cannot be read: ") + e.what();
    return pending;
  }
  // The rule every log command applies (session_log/log_integrity.hpp).
  const auto problems = session_log::integrity_problems(log);
  std::ostringstream problem;
  if (!problems.empty()) {
    problem << session_log::describe(problems);
    if (log.start) {
      problem << "; to identify it by hand from what is intact: furuta identify "
                 "--use-intact-part";
    }
  } else if (log.samples.empty()) {
    problem << "the session has no samples (it ended: " << log.end->end_reason << ")";
  }
  pending.problem = problem.str();
  if (log.start) {
    pending.label = log.start->label;
    pending.started_wall_ns = log.start->wall_time_ns;
  }
  return pending;
}

struct Batch {
  std::string name;  // the first fitted session's, unique like it
  std::vector<PendingLog> fit;
  std::optional<PendingLog> validation;

  std::vector<fs::path> paths() const {
    std::vector<fs::path> all;
    for (const auto& log : fit) all.push_back(log.path);
    if (validation) all.push_back(validation->path);
    return all;
  }
  std::string describe() const {
    std::string text = "fitted";
    for (std::size_t i = 0; i < fit.size(); ++i) {
      text += (i == 0 ? " " : ", ") + fit[i].path.filename().string();
    }
    if (validation) text += "; held out " + validation->path.filename().string();
    return text;
  }
};

report::BatchManifest manifest(const Batch& batch, const fs::path& logs_dir) {
  report::BatchManifest m;
  m.identification = batch.name;
  m.identified_at = utc_now();
  m.logs_dir = logs_dir.string();
  const auto entry = [](const PendingLog& log) {
    return report::BatchManifest::Log{"done/" + log.path.filename().string(), log.label};
  };
  for (const auto& log : batch.fit) m.fit.push_back(entry(log));
  if (batch.validation) m.validation = entry(*batch.validation);
  return m;
}

class Processor {
 public:
  Processor(const LogProcessorOptions& options, std::ostream& out, std::ostream& err)
      : o_(options),
        done_(options.logs_dir / "done"),
        failed_(options.logs_dir / "failed"),
        out_(out),
        err_(err) {}

  ProcessingPass run() {
    require_logs_directory(o_.logs_dir);
    if (const std::string problem =
            identifications_dir_problem(o_.logs_dir, o_.identifications_dir);
        !problem.empty()) {
      throw std::runtime_error("identifications directory " + o_.identifications_dir.string() +
                               ": " + problem);
    }
    fs::create_directories(done_);
    fs::create_directories(failed_);
    fs::create_directories(o_.identifications_dir);
    // Logs first, then identifications: every pass locks in the same order.
    const DirectoryLock logs_lock(o_.logs_dir);
    const DirectoryLock identifications_lock(o_.identifications_dir);
    pass_.recovered = finish_journal();
    pass_.recovered = remove_stale_temporaries() || pass_.recovered;
    while (one_round()) {
    }
    return pass_;
  }

 private:
  // One listing and what it allows; true when something moved (the next listing may differ).
  bool one_round() {
    std::vector<fs::path> listed;
    for (const auto& entry : fs::directory_iterator(o_.logs_dir)) {
      const std::string leaf = entry.path().filename().string();
      if (entry.is_regular_file() && leaf.ends_with(kLogExtension) && !leaf.starts_with(".")) {
        listed.push_back(entry.path());
      }
    }
    std::vector<PendingLog> examined;
    for (const fs::path& path : listed) examined.push_back(examine(path));
    // The order they ran in, from their start records: names have whole seconds, and sessions
    // started within one second are told apart by a suffix that does not sort (-2 before -10).
    std::sort(examined.begin(), examined.end(), [](const PendingLog& a, const PendingLog& b) {
      return std::tie(a.started_wall_ns, a.path) < std::tie(b.started_wall_ns, b.path);
    });
    bool moved = false;
    std::vector<PendingLog> fits, validations;
    const config::AutomationConfig& a = o_.automation;
    for (PendingLog& log : examined) {
      const fs::path path = log.path;
      if (!log.problem.empty()) {
        fail({path}, log.problem);
        moved = true;
      } else if (std::find(a.fit_labels.begin(), a.fit_labels.end(), log.label) !=
                 a.fit_labels.end()) {
        fits.push_back(std::move(log));
      } else if (!a.validation_label.empty() && log.label == a.validation_label) {
        validations.push_back(std::move(log));
      } else {
        const fs::path target = move_into(path, done_);
        sync_directory(done_);
        sync_directory(o_.logs_dir);
        out_ << path.filename().string() << ": not identified: label '" << log.label
             << "' is not in [automation] (fit_labels " << describe_fit_labels()
             << (a.validation_label.empty() ? "" : ", validation_label " + a.validation_label)
             << "); moved to " << target.string() << " for a manual `furuta identify`\n";
        ++pass_.logs_not_identified;
        moved = true;
      }
    }
    const auto fit_count = static_cast<std::size_t>(a.fit_sessions);
    std::size_t used_fits = 0, used_validations = 0;
    while (fits.size() - used_fits >= fit_count &&
           (a.validation_label.empty() || validations.size() > used_validations)) {
      Batch batch;
      batch.fit.assign(fits.begin() + static_cast<std::ptrdiff_t>(used_fits),
                       fits.begin() + static_cast<std::ptrdiff_t>(used_fits + fit_count));
      used_fits += fit_count;
      if (!a.validation_label.empty()) batch.validation = validations[used_validations++];
      batch.name = batch.fit.front().path.stem().string();
      identify(batch);
      moved = true;
    }
    pass_.logs_waiting =
        static_cast<int>(fits.size() - used_fits + validations.size() - used_validations);
    if (!moved && pass_.logs_waiting > 0) {
      // Each log left pending, and what its batch still lacks.
      const std::size_t fits_left = fits.size() - used_fits;
      const std::size_t validations_left = validations.size() - used_validations;
      std::ostringstream batch;
      batch << std::min(fits_left, fit_count) << " of " << fit_count << " '"
            << describe_fit_labels() << "' session(s)";
      if (!a.validation_label.empty()) {
        batch << " and " << std::min<std::size_t>(validations_left, 1) << " of 1 '"
              << a.validation_label << "'";
      }
      const auto say = [&](const PendingLog& log) {
        out_ << log.path.filename().string() << ": waiting for its batch: " << batch.str() << " ("
             << o_.logs_dir.string() << ")\n";
      };
      std::for_each(fits.begin() + static_cast<std::ptrdiff_t>(used_fits), fits.end(), say);
      std::for_each(validations.begin() + static_cast<std::ptrdiff_t>(used_validations),
                    validations.end(), say);
    }
    return moved;
  }

  std::string describe_fit_labels() const {
    std::string text;
    for (const auto& label : o_.automation.fit_labels) text += (text.empty() ? "" : "/") + label;
    return text;
  }

  void identify(const Batch& batch) {
    const fs::path temp = o_.identifications_dir / (kTempPrefix + batch.name);
    fs::remove_all(temp);
    pipeline::BatchRequest request;
    for (const auto& log : batch.fit) request.logs.push_back(log.path);
    if (batch.validation) request.validate = batch.validation->path;
    // The report and results.json name the logs where they will be: the batch moves to done/ as
    // a whole once its files are in place.
    request.files_listed_in = done_;
    request.config_path = o_.fit_config;
    request.overrides.sivia = o_.automation.sivia;
    request.overrides.guaranteed = o_.automation.guaranteed;
    request.overrides.simulate = o_.automation.simulate;
    request.overrides.simulate_seconds = o_.automation.simulate_seconds;
    std::string problems;
    std::optional<pipeline::Run> run;
    try {
      const pipeline::Intake intake = pipeline::load_batch(request);
      for (const std::string& refusal : intake.refusals) problems += refusal + "\n";
      // A log the intake refuses on its own (too short, no samples) goes to failed/ alone; the
      // rest of its batch stays pending for a batch without it.
      if (!intake.batch && fail_unusable_alone(batch, request)) return;
      if (intake.batch) {
        run = pipeline::run(*intake.batch, intake.settings);
        report::write_identification(temp, *run, daemon::kSoftwareVersion);
      }
    } catch (const std::exception& e) {
      run.reset();
      problems += std::string(e.what()) + "\n";
    }
    if (!run) {
      fs::remove_all(temp);
      fail(batch.paths(), "identification " + batch.name + " (" + batch.describe() +
                              ") failed: " + trimmed(problems));
      return;
    }
    report::write_text_file(temp / "batch.json",
                            report::json_text(report::batch_json(manifest(batch, o_.logs_dir))));
    sync_tree(temp);

    const fs::path final_dir = free_name_in(o_.identifications_dir, batch.name);
    std::string journal = "done " + final_dir.filename().string() + "\n";
    for (const auto& path : batch.paths()) journal += path.filename().string() + "\n";
    write_durably(o_.logs_dir / kJournal, journal);
    fs::rename(temp, final_dir);
    sync_directory(o_.identifications_dir);
    for (const auto& path : batch.paths()) move_into(path, done_);
    finish_moves();

    print_identification(out_, *run, final_dir);
    out_ << "identification " << final_dir.filename().string() << ": " << batch.describe()
         << "; logs moved to " << done_.string() << "\n";
    pass_.identifications.push_back(final_dir);
    pass_.logs_done += static_cast<int>(batch.paths().size());
  }

  // Each log of the batch through the intake alone, as the batch's only fitted log; those it
  // refuses go to failed/ with their own reasons. False when every log passes alone: what is
  // wrong is between them (different rigs), and the batch fails together.
  bool fail_unusable_alone(const Batch& batch, const pipeline::BatchRequest& batch_request) {
    std::vector<std::pair<fs::path, std::string>> unusable;
    for (const fs::path& path : batch.paths()) {
      pipeline::BatchRequest alone = batch_request;
      alone.logs = {path};
      alone.validate.clear();
      const pipeline::Intake intake = pipeline::load_batch(alone);
      if (intake.batch) continue;
      std::string reasons;
      for (const std::string& refusal : intake.refusals) reasons += refusal + "\n";
      unusable.emplace_back(path, trimmed(reasons));
    }
    // When none is left to wait, the batch fails together with every reason.
    if (unusable.empty() || unusable.size() == batch.paths().size()) return false;
    for (const auto& [path, reason] : unusable) {
      fail({path},
           "refused on its own, so left out of its batch (the others stay pending): " + reason);
    }
    return true;
  }

  // Each log gets its reason before it moves; the journal makes a batch move all or nothing.
  void fail(const std::vector<fs::path>& logs, const std::string& reason) {
    std::string journal = "failed\n";
    for (const auto& path : logs) {
      const fs::path reason_file = failed_ / (path.stem().string() + ".reason.txt");
      write_durably(reason_file, path.filename().string() + ": " + reason + "\n");
      journal += path.filename().string() + "\n";
    }
    if (logs.size() > 1) write_durably(o_.logs_dir / kJournal, journal);
    for (const auto& path : logs) {
      move_into(path, failed_);
      err_ << "furuta process-logs: " << path.filename().string() << " -> " << failed_.string()
           << "/: " << reason << "\n";
    }
    finish_moves();
    pass_.logs_failed += static_cast<int>(logs.size());
  }

  void finish_moves() {
    sync_directory(done_);
    sync_directory(failed_);
    sync_directory(o_.logs_dir);
    if (fs::remove(o_.logs_dir / kJournal)) sync_directory(o_.logs_dir);
  }

  // A journal left behind means a pass died while committing: completes what is complete.
  bool finish_journal() {
    const fs::path journal_path = o_.logs_dir / kJournal;
    if (!fs::exists(journal_path)) return false;
    std::istringstream journal(read_text(journal_path));
    std::string kind, identification, leaf;
    journal >> kind;
    if (kind == "done") journal >> identification;
    std::vector<fs::path> still_pending;
    while (journal >> leaf) {
      if (fs::exists(o_.logs_dir / leaf)) still_pending.push_back(o_.logs_dir / leaf);
    }
    if (kind == "done" && !identification.empty() &&
        fs::is_directory(o_.identifications_dir / identification)) {
      for (const auto& path : still_pending) move_into(path, done_);
      pass_.logs_done += static_cast<int>(still_pending.size());
      out_ << "recovered: identification " << identification << " was complete; "
           << still_pending.size() << " of its logs moved to " << done_.string() << "\n";
    } else if (kind == "failed") {
      for (const auto& path : still_pending) {
        if (!fs::exists(failed_ / (path.stem().string() + ".reason.txt"))) continue;
        move_into(path, failed_);
        ++pass_.logs_failed;
      }
      out_ << "recovered: a failed batch's logs moved to " << failed_.string() << "\n";
    } else {
      // Died before the identification was in place: its logs are still pending, and are
      // identified again below.
      out_ << "recovered: an identification interrupted before it was complete is redone\n";
    }
    finish_moves();
    return true;
  }

  bool remove_stale_temporaries() {
    bool removed = false;
    for (const auto& entry : fs::directory_iterator(o_.identifications_dir)) {
      if (entry.path().filename().string().starts_with(kTempPrefix)) {
        fs::remove_all(entry.path());
        out_ << "recovered: removed " << entry.path().string()
             << " (an identification interrupted by a crash)\n";
        removed = true;
      }
    }
    if (removed) sync_directory(o_.identifications_dir);
    return removed;
  }

  const LogProcessorOptions& o_;
  const fs::path done_, failed_;
  std::ostream& out_;
  std::ostream& err_;
  ProcessingPass pass_;
};

// A log has landed: the daemon renames <name>.lcmlog into the directory (or it was copied in).
bool log_landed(int inotify_fd) {
  alignas(inotify_event) char buffer[16 * 1024];
  bool landed = false;
  for (;;) {
    const ssize_t n = ::read(inotify_fd, buffer, sizeof buffer);
    if (n <= 0) break;  // EAGAIN: drained
    for (ssize_t at = 0; at < n;) {
      const auto* event = reinterpret_cast<const inotify_event*>(buffer + at);
      const std::string leaf = event->len > 0 ? std::string(event->name) : std::string();
      if ((event->mask & IN_Q_OVERFLOW) != 0 ||
          (leaf.ends_with(kLogExtension) && !leaf.starts_with("."))) {
        landed = true;
      }
      at += static_cast<ssize_t>(sizeof(inotify_event) + event->len);
    }
  }
  return landed;
}

std::atomic<bool> g_stop_requested{false};
extern "C" void request_stop(int) {
  g_stop_requested.store(true);
}

}  // namespace

ProcessingPass process_logs(const LogProcessorOptions& options, std::ostream& out,
                            std::ostream& err) {
  return Processor(options, out, err).run();
}

void watch_logs(const LogProcessorOptions& options, const std::function<bool()>& keep_going,
                std::chrono::milliseconds rescan_interval, std::ostream& out, std::ostream& err) {
  require_logs_directory(options.logs_dir);
  const FileDescriptor inotify(::inotify_init1(IN_NONBLOCK | IN_CLOEXEC));
  if (inotify.get() < 0) throw system_error_for("inotify for", options.logs_dir);
  if (::inotify_add_watch(inotify.get(), options.logs_dir.c_str(), IN_MOVED_TO | IN_CLOSE_WRITE) <
      0) {
    throw system_error_for("cannot watch", options.logs_dir);
  }
  using Clock = std::chrono::steady_clock;
  // The first pass takes whatever landed before the watch began.
  bool due = true;
  Clock::time_point last_pass = Clock::now();
  while (keep_going()) {
    if (due || Clock::now() - last_pass >= rescan_interval) {
      try {
        process_logs(options, out, err);
      } catch (const std::exception& e) {
        // A full disk or a permission problem may pass: report it and try again later.
        err << "furuta process-logs: " << e.what() << "\n";
      }
      out.flush();
      last_pass = Clock::now();
      due = false;
    }
    pollfd watch{inotify.get(), POLLIN, 0};
    if (::poll(&watch, 1, 250) > 0) due = log_landed(inotify.get());
  }
}

int run_process_logs_command(const ProcessLogsOptions& options, std::ostream& out,
                             std::ostream& err) {
  const config::RigConfig rig = config::load_rig_config(options.config_path);
  LogProcessorOptions processor;
  processor.logs_dir = options.logs_dir.empty() ? fs::path(rig.daemon.logs_dir) : options.logs_dir;
  processor.identifications_dir = options.identifications_dir.empty()
                                      ? fs::path(rig.automation.identifications_dir)
                                      : options.identifications_dir;
  processor.automation = rig.automation;
  if (options.config_named) processor.fit_config = options.config_path;
  // Which directory, and why that one: with no DIR it is the configuration's, which may not be
  // the one the user thought of.
  const std::string logs_from =
      options.logs_dir.empty() ? " (the [daemon] logs_dir of " + options.config_path.string() + ")"
                               : std::string();
  const fs::file_status status = fs::status(processor.logs_dir);
  if (!fs::is_directory(status)) {
    err << "furuta process-logs: " << processor.logs_dir.string() << logs_from << ": "
        << (fs::exists(status) ? "not a directory" : "no such directory (nothing was created)")
        << "; give the directory the daemon writes its logs to"
        << (options.logs_dir.empty() ? " as DIR, or set logs_dir" : "") << "\n";
    return 2;
  }
  if (const std::string problem =
          identifications_dir_problem(processor.logs_dir, processor.identifications_dir);
      !problem.empty()) {
    err << "furuta process-logs: "
        << (options.identifications_dir.empty()
                ? "the [automation] identifications_dir of " + options.config_path.string() + ", "
                : std::string("-o "))
        << processor.identifications_dir.string() << ": " << problem << "\n";
    return 2;
  }
  out << "logs in " << processor.logs_dir.string() << logs_from << ", identifications in "
      << processor.identifications_dir.string() << "\n";
  if (options.watch) {
    g_stop_requested.store(false);
    struct sigaction action {};
    action.sa_handler = request_stop;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
    out << "watching " << processor.logs_dir.string() << "; Ctrl-C stops\n";
    out.flush();
    watch_logs(
        processor, [] { return !g_stop_requested.load(); }, std::chrono::seconds(60), out, err);
    return 0;
  }
  const ProcessingPass pass = process_logs(processor, out, err);
  out << "process-logs: " << pass.identifications.size() << " identification(s), " << pass.logs_done
      << " log(s) identified to done/, " << pass.logs_not_identified
      << " not identified (label not in [automation]) to done/, " << pass.logs_failed
      << " to failed/, " << pass.logs_waiting << " waiting\n";
  // Done in part (1) when a log was set aside or left unidentified, so `systemctl --failed` shows
  // that someone should look: a log of a label [automation] does not name was recorded and not
  // fitted, which is what the README's exit rule calls "not identified" (each is named above).
  // Logs still waiting for their batch are not set aside: a later pass takes them.
  return pass.logs_failed > 0 || pass.logs_not_identified > 0 ? kExitPartOrRefused : kExitDone;
}

}  // namespace furuta::app
