// `furuta estop` under a flood of wrongly signed starts: how long the e-stop takes to be answered
// and to take effect while RIG_COMMAND_SIGNED carries `--rate` commands a second that the daemon
// must refuse. A figure, not a pass/fail test (the target: answered and in effect within
// 100 ms in 20 of 20 tries, at 100,000 commands a second).
//
//   estop_under_flood --lcm-url URL --config RIG.toml --command-key KEY [--tries 20]
//                     [--rate 100000] [--flood-threads 2] [--sign-each] [--json FILE]
//
// Runs against a furutad that is already up on the same machine (--sim;
// bench/run_estop_under_flood.sh starts one in a private network namespace). Besides the main
// thread, threads with an LCM instance each:
// - the flood threads publish start commands signed with a random key that is not the rig's, each
//   with its own request id, nonce and signing time, paced in 1 ms batches against steady_clock;
// - the observer listens to RIG_STATUS and notes, per try, when the daemon's reply to the e-stop
//   and the first status naming the e-stop's end arrived.
// docs/measurements/estop-under-flood.md says what each figure is.
// The main thread starts each session and sends each e-stop through the CLI's own code
// (run_remote_command) and times the call; the session's log then gives when the loop wrote the
// zero command to the 1065 (the e-stop in effect), on the same monotonic clock.
// Every wait has a limit; the program ends on its own (--time-limit-s over all).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "furuta/command_auth/command_auth.hpp"
#include "furuta/config/rig_config.hpp"
#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/rig_command_t.hpp"
#include "furuta/rig_signed_command_t.hpp"
#include "furuta/rig_status_t.hpp"
#include "furuta/session_log/session_log.hpp"

namespace {

using namespace std::chrono_literals;
using furuta::app::RemoteKind;
using SteadyClock = std::chrono::steady_clock;

// The flood's request ids have this bit set; the CLI's are below 2^62 (new_request_id), so a reply
// to a flood command is never taken for the reply to the e-stop.
constexpr std::int64_t kFloodIdBit = std::int64_t{1} << 62;
constexpr int kTargetMs = 100;

// The clock furutad's loop stamps its cycles and USB writes with (CLOCK_MONOTONIC), so the times
// in a session log can be set against this process's.
std::int64_t monotonic_ns() {
  return furuta::bridge::MonotonicClock{}.now_ns();
}

std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.compare(0, prefix.size(), prefix) == 0;
}

// LCM's wire format for a message that fits one datagram (lcm_udpm.c): the magic "LC02" and a
// sequence number, both big-endian, the channel and its NUL, the encoded message. With it the
// flood goes out through one UDP socket, 64 datagrams a sendmmsg call, so generating it costs a
// fraction of what lcm_publish does (a syscall and a copy each): on a 2-core machine, the CPU the
// flood's maker saves is left to the daemon, as it would be for a flood sent from another host.
class RawMulticast {
 public:
  // `url`: udpm://GROUP:PORT?...; ttl 0 (the loopback only), loop on.
  explicit RawMulticast(const std::string& url) {
    const auto at = url.find("://");
    const auto colon = url.find(':', at + 3);
    const auto end = url.find_first_of("?/", colon);
    if (at == std::string::npos || colon == std::string::npos) return;
    const std::string group = url.substr(at + 3, colon - at - 3);
    const int port = std::stoi(url.substr(colon + 1, end - colon - 1));
    to_.sin_family = AF_INET;
    to_.sin_port = htons(static_cast<std::uint16_t>(port));
    if (::inet_pton(AF_INET, group.c_str(), &to_.sin_addr) != 1) return;
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    const unsigned char ttl = 0, loop = 1;
    if (fd_ >= 0 && (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl) != 0 ||
                     ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop) != 0)) {
      ::close(fd_);
      fd_ = -1;
    }
  }
  ~RawMulticast() {
    if (fd_ >= 0) ::close(fd_);
  }
  RawMulticast(const RawMulticast&) = delete;
  RawMulticast& operator=(const RawMulticast&) = delete;
  bool good() const { return fd_ >= 0; }

  // Queues one message; sent when 64 are queued or at flush().
  void add(const std::string& channel, const furuta::rig_signed_command_t& message) {
    std::vector<std::uint8_t>& d = datagrams_[queued_];
    const int size = message.getEncodedSize();
    d.resize(8 + channel.size() + 1 + static_cast<std::size_t>(size));
    const std::uint32_t magic = 0x4c433032, seqno = sequence_++;
    for (int i = 0; i < 4; ++i) {
      d[i] = static_cast<std::uint8_t>(magic >> (24 - 8 * i));
      d[4 + i] = static_cast<std::uint8_t>(seqno >> (24 - 8 * i));
    }
    std::copy(channel.begin(), channel.end(), d.begin() + 8);
    d[8 + channel.size()] = 0;
    message.encode(d.data() + 9 + channel.size(), 0, size);
    if (++queued_ == kBatch) flush();
  }
  void flush() {
    std::array<iovec, kBatch> iov{};
    std::array<mmsghdr, kBatch> headers{};
    for (std::size_t i = 0; i < queued_; ++i) {
      iov[i] = {datagrams_[i].data(), datagrams_[i].size()};
      headers[i].msg_hdr.msg_name = &to_;
      headers[i].msg_hdr.msg_namelen = sizeof to_;
      headers[i].msg_hdr.msg_iov = &iov[i];
      headers[i].msg_hdr.msg_iovlen = 1;
    }
    for (std::size_t sent = 0; sent < queued_;) {
      const int n =
          ::sendmmsg(fd_, headers.data() + sent, static_cast<unsigned>(queued_ - sent), 0);
      if (n <= 0) break;  // a full send buffer: the rest of the batch is dropped, as a flood's are
      sent += static_cast<std::size_t>(n);
    }
    queued_ = 0;
  }

 private:
  static constexpr std::size_t kBatch = 64;
  int fd_ = -1;
  sockaddr_in to_{};
  std::uint32_t sequence_ = 0;
  std::array<std::vector<std::uint8_t>, kBatch> datagrams_;
  std::size_t queued_ = 0;
};

// Publishes wrongly signed starts at `rate` a second while not paused. The schedule is kept in
// 1 ms batches; a flooder more than 100 ms behind it restarts the schedule from now (counted), so
// it never bursts to catch up. Each batch is signed with the wrong key (command_auth::sign_command)
// once; its messages then differ in request id, nonce and signing time, so none repeats and none
// carries a tag that checks out under any key. With `sign_each`, every message is signed on its
// own (costlier for the flooder, the same work for the daemon).
class FloodThread {
 public:
  FloodThread(const std::string& url, double rate, bool sign_each, bool sendmmsg, int nice,
              std::uint64_t first_id)
      : lcm_(url), rate_(rate), sign_each_(sign_each), nice_(nice), first_id_(first_id) {
    if (sendmmsg) raw_.emplace(url);
    std::random_device entropy;
    for (auto& byte : wrong_key_) byte = static_cast<std::uint8_t>(entropy());
    nonce_.seed((std::uint64_t{entropy()} << 32) ^ entropy());
    if (lcm_.good()) thread_ = std::thread([this] { run(); });
  }
  ~FloodThread() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  FloodThread(const FloodThread&) = delete;
  FloodThread& operator=(const FloodThread&) = delete;

  bool good() { return lcm_.good() && (!raw_ || raw_->good()); }
  void set_paused(bool paused) { paused_.store(paused); }
  std::uint64_t sent() const { return sent_.load(); }
  // Seconds spent flooding so far, the current stretch included.
  double flooding_s() const {
    std::lock_guard lock(time_mutex_);
    SteadyClock::duration total = flooding_;
    if (active_since_) total += SteadyClock::now() - *active_since_;
    return std::chrono::duration<double>(total).count();
  }
  std::uint64_t schedule_resets() const { return schedule_resets_.load(); }

 private:
  void set_active(bool active) {
    std::lock_guard lock(time_mutex_);
    if (active) {
      active_since_ = SteadyClock::now();
    } else if (active_since_) {
      flooding_ += SteadyClock::now() - *active_since_;
      active_since_.reset();
    }
  }

  void run() {
    // Below the daemon, as another user's process is below a furutad the unit runs with Nice=-10.
    if (nice_ != 0) ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), nice_);
    furuta::rig_command_t command{};
    command.kind = furuta::rig_command_t::KIND_START_SESSION;
    command.profile = "bang_bang";
    command.amplitude_duty = 0.15;
    command.duration_s = 30;
    command.label = "flood";
    command.seed = 1;
    const std::string sender = "flood@estop_under_flood";
    std::uint64_t counter = first_id_;
    bool was_paused = true;
    double owed = 0;  // messages due but not sent, carried from batch to batch
    SteadyClock::time_point next{};
    furuta::rig_signed_command_t message;
    while (!stop_.load()) {
      if (paused_.load()) {
        if (!was_paused) set_active(false);
        was_paused = true;
        std::this_thread::sleep_for(1ms);
        continue;
      }
      if (was_paused) {
        was_paused = false;
        set_active(true);
        next = SteadyClock::now();
        owed = 0;
      }
      owed += rate_ / 1000.0;
      const auto batch = static_cast<std::uint64_t>(owed);
      owed -= static_cast<double>(batch);
      const std::int64_t signed_at = wall_ns();
      for (std::uint64_t i = 0; i < batch; ++i, ++counter) {
        command.request_id = kFloodIdBit | static_cast<std::int64_t>(counter);
        const auto nonce = static_cast<std::int64_t>(nonce_());
        const std::int64_t at = signed_at + static_cast<std::int64_t>(i);
        if (i == 0 || sign_each_) {
          message = furuta::command_auth::sign_command(command, wrong_key_, sender, at, nonce);
        } else {
          command.encode(message.command.data(), 0, message.command_size);
          message.signed_wall_ns = at;
          message.nonce = nonce;
        }
        if (raw_) {
          raw_->add(furuta::session_log::kChannelSignedCommand, message);
        } else {
          lcm_.publish(furuta::session_log::kChannelSignedCommand, &message);
        }
      }
      if (raw_) raw_->flush();
      sent_.fetch_add(batch);
      next += 1ms;
      const auto now = SteadyClock::now();
      if (now > next + 100ms) {
        schedule_resets_.fetch_add(1);
        next = now;
      } else if (next > now) {
        std::this_thread::sleep_until(next);
      }
    }
    set_active(false);
  }

  lcm::LCM lcm_;
  std::optional<RawMulticast> raw_;  // with --sendmmsg
  double rate_;
  bool sign_each_;
  int nice_;
  std::uint64_t first_id_;
  furuta::command_auth::CommandKey wrong_key_{};
  std::mt19937_64 nonce_;
  std::atomic<bool> paused_{true};
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<std::uint64_t> schedule_resets_{0};
  mutable std::mutex time_mutex_;
  SteadyClock::duration flooding_{};                     // past stretches
  std::optional<SteadyClock::time_point> active_since_;  // the current one
  std::thread thread_;
};

// The flood: `threads` flood threads sharing the rate, each with its own LCM instance and its own
// range of request ids.
class Flooder {
 public:
  Flooder(const std::string& url, double rate, bool sign_each, bool sendmmsg, int nice,
          int threads) {
    for (int i = 0; i < threads; ++i) {
      threads_.push_back(std::make_unique<FloodThread>(url, rate / threads, sign_each, sendmmsg,
                                                       nice, static_cast<std::uint64_t>(i) << 40));
    }
  }
  bool good() {
    return std::all_of(threads_.begin(), threads_.end(), [](auto& t) { return t->good(); });
  }
  void set_paused(bool paused) {
    for (auto& t : threads_) t->set_paused(paused);
  }
  std::uint64_t sent() const {
    std::uint64_t n = 0;
    for (const auto& t : threads_) n += t->sent();
    return n;
  }
  // The threads flood over the same stretches of time.
  double flooding_s() const { return threads_.front()->flooding_s(); }
  std::uint64_t schedule_resets() const {
    std::uint64_t n = 0;
    for (const auto& t : threads_) n += t->schedule_resets();
    return n;
  }
  double achieved_rate() const {
    const double s = flooding_s();
    return s > 0 ? static_cast<double>(sent()) / s : 0.0;
  }

 private:
  std::vector<std::unique_ptr<FloodThread>> threads_;
};

// What the observer saw of one e-stop, times in CLOCK_MONOTONIC ns.
struct EstopObservation {
  std::optional<std::int64_t> reply_ns;  // the first reply after the e-stop that is not the flood's
  bool reply_accepted = false;
  std::optional<std::int64_t> status_shows_end_ns;  // first status whose last_session_end is it
};

// Listens to RIG_STATUS on its own LCM instance and thread.
class Observer {
 public:
  explicit Observer(const std::string& url) : lcm_(url) {
    if (!lcm_.good()) return;
    subscription_ = lcm_.subscribe(furuta::session_log::kChannelStatus, &Observer::on_status, this);
    // The flood's replies come as fast as the daemon answers; room for them between dispatches.
    subscription_->setQueueCapacity(10000);
    thread_ = std::thread([this] {
      while (!stop_.load()) lcm_.handleTimeout(20);
    });
  }
  ~Observer() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
    if (subscription_) lcm_.unsubscribe(subscription_);
  }
  Observer(const Observer&) = delete;
  Observer& operator=(const Observer&) = delete;

  bool good() { return lcm_.good(); }

  // From now on, note what concerns the e-stop of `session`.
  void arm(const std::string& session) {
    std::lock_guard lock(mutex_);
    armed_session_ = session;
    observation_ = {};
  }
  void disarm() {
    std::lock_guard lock(mutex_);
    armed_session_.clear();
  }
  EstopObservation observation() const {
    std::lock_guard lock(mutex_);
    return observation_;
  }

  struct Latest {
    std::int8_t state = -1;
    std::int64_t refused_unauthenticated = 0;
    std::int64_t statuses = 0;       // every status received
    std::int64_t flood_replies = 0;  // replies to flood commands among them
  };
  Latest latest() const {
    std::lock_guard lock(mutex_);
    return latest_;
  }
  // The state in the first status received from now on, within `limit`.
  std::optional<std::int8_t> next_state(std::chrono::milliseconds limit) {
    std::unique_lock lock(mutex_);
    const std::int64_t after = latest_.statuses;
    if (!changed_.wait_for(lock, limit, [&] { return latest_.statuses > after; })) {
      return std::nullopt;
    }
    return latest_.state;
  }

 private:
  void on_status(const lcm::ReceiveBuffer*, const std::string&, const furuta::rig_status_t* s) {
    const std::int64_t now = monotonic_ns();
    {
      std::lock_guard lock(mutex_);
      ++latest_.statuses;
      const bool flood_reply = (s->reply_to_request_id & kFloodIdBit) != 0;
      if (flood_reply) ++latest_.flood_replies;
      latest_.state = s->state;
      latest_.refused_unauthenticated =
          std::max(latest_.refused_unauthenticated, s->refused_unauthenticated);
      if (!armed_session_.empty()) {
        // The CLI asks for status only once the e-stop is answered, so the first reply that is not
        // the flood's is the e-stop's.
        if (!observation_.reply_ns && s->reply_to_request_id != 0 && !flood_reply) {
          observation_.reply_ns = now;
          observation_.reply_accepted = s->request_accepted;
        }
        if (!observation_.status_shows_end_ns && s->last_session == armed_session_ &&
            starts_with(s->last_session_end, "estop_command")) {
          observation_.status_shows_end_ns = now;
        }
      }
    }
    changed_.notify_all();
  }

  lcm::LCM lcm_;
  lcm::Subscription* subscription_ = nullptr;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::string armed_session_;
  EstopObservation observation_;
  Latest latest_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// What the session's log says of its end: when the loop ended it and when it wrote the zero
// command to the 1065 (the first zero write at or after `from_ns`; a bang-bang never writes zero).
struct LoggedEnd {
  std::string end_reason;
  std::optional<std::int64_t> end_ns;
  std::optional<std::int64_t> zero_write_ns;
};

LoggedEnd read_logged_end(const std::filesystem::path& log_path, std::int64_t from_ns) {
  LoggedEnd result;
  furuta::session_log::SessionLog log;
  try {
    log = furuta::session_log::load_session_log(log_path);
  } catch (const std::exception& e) {
    result.end_reason = std::string("(log unreadable: ") + e.what() + ")";
    return result;
  }
  if (log.end) {
    result.end_reason = log.end->end_reason;
    result.end_ns = log.end->monotonic_ns;
  }
  const std::string board = furuta::config::RigConfig{}.motor_board.model;
  for (const auto& write : furuta::session_log::motor_command_writes(log, board)) {
    if (write.time_ns >= from_ns && write.duty == 0.0) {
      result.zero_write_ns = write.time_ns;
      break;
    }
  }
  return result;
}

struct Options {
  std::string lcm_url;
  std::string config;
  std::string command_key;
  int tries = 20;
  double rate = 100000;
  int flood_threads = 2;
  bool sign_each = false;
  bool sendmmsg = false;
  int flood_nice = 0;
  std::string json;
  double time_limit_s = 900;
  // The session runs this long, under the flood, before its e-stop, plus a random part of up to
  // 50 ms (three loop periods), so that the e-stop meets the loop at any phase of its cycle.
  double settle_s = 1.0;
};

struct Try {
  int number = 0;
  std::string start_mode;  // "flood on", "flood paused" or "no flood"
  int start_attempts = 0;
  std::string session;
  std::optional<double> reply_ms;  // observer: the daemon's reply to the e-stop arrived
  bool reply_accepted = false;
  std::optional<double> effect_ms;  // log: the zero command written to the 1065
  std::optional<double> end_ms;     // log: the loop's cycle that ended the session
  std::optional<double> status_ms;  // observer: the first status naming the e-stop's end
  double returned_ms = 0;           // run_remote_command(estop) returned
  int exit_code = -1;
  bool says_estop = false;        // the call's output says the session ended by e-stop
  std::string end_reason;         // from the log
  std::string cli_output;         // what the call wrote, when it did not exit 0
  std::uint64_t sent_during = 0;  // flood commands sent while the call ran
  bool within_target = false;
};

double ms_since(std::int64_t t0_ns, std::int64_t t_ns) {
  return static_cast<double>(t_ns - t0_ns) * 1e-6;
}

std::optional<double> ms_or_none(std::int64_t t0_ns, const std::optional<std::int64_t>& t_ns) {
  if (!t_ns) return std::nullopt;
  return ms_since(t0_ns, *t_ns);
}

struct Summary {
  std::size_t n = 0;
  double min = 0, median = 0, p95 = 0, max = 0;
};
// Nearest-rank quantiles of the values present.
Summary summarize(std::vector<double> values) {
  Summary s;
  s.n = values.size();
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const auto rank = [&](double q) {
    const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
    return values[std::clamp<std::size_t>(k, 1, values.size()) - 1];
  };
  s.min = values.front();
  s.median = rank(0.5);
  s.p95 = rank(0.95);
  s.max = values.back();
  return s;
}

nlohmann::json to_json(const Summary& s) {
  if (s.n == 0) return {{"n", 0}};
  return {{"n", s.n}, {"min", s.min}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
}

nlohmann::json optional_json(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

std::string cell(const std::optional<double>& v) {
  if (!v) return "-";
  std::ostringstream text;
  text << std::fixed << std::setprecision(1) << *v;
  return text.str();
}

std::string first_line(const std::string& text) {
  return text.substr(0, text.find('\n'));
}

// The session name in `furuta start`'s "furuta start: session NAME running".
std::optional<std::string> running_session(const std::string& out) {
  const std::string marker = "furuta start: session ";
  const auto at = out.find(marker);
  if (at == std::string::npos) return std::nullopt;
  const auto from = at + marker.size();
  const auto space = out.find(' ', from);
  if (space == std::string::npos || out.compare(space, 8, " running") != 0) return std::nullopt;
  return out.substr(from, space - from);
}

class Bench {
 public:
  Bench(const Options& options, std::filesystem::path logs_dir, Flooder& flooder,
        Observer& observer)
      : options_(options),
        logs_dir_(std::move(logs_dir)),
        flooder_(flooder),
        observer_(observer),
        deadline_(SteadyClock::now() + std::chrono::duration_cast<SteadyClock::duration>(
                                           std::chrono::duration<double>(options.time_limit_s))) {
    remote_.lcm_url = options.lcm_url;
    remote_.config_path = options.config;
    remote_.command_key = options.command_key;
    remote_.wait = true;
    start_.profile = "bang_bang";
    start_.amplitude_duty = 0.15;
    start_.duration_s = 30;
    start_.label = "flood";
  }

  bool out_of_time() const { return SteadyClock::now() >= deadline_; }

  // One try: a session running (started with the flood on, or with it paused when that start
  // failed), then the e-stop with the flood on. Nothing when no session could be started.
  std::optional<Try> run_try(int number) {
    Try t;
    t.number = number;
    const bool flooding = options_.rate > 0;
    for (int attempt = 1; attempt <= 6 && t.session.empty() && !out_of_time(); ++attempt) {
      const bool flood_on = flooding && attempt == 1;
      t.start_attempts = attempt;
      t.start_mode = !flooding ? "no flood" : flood_on ? "flood on" : "flood paused";
      flooder_.set_paused(!flood_on);
      if (!flood_on) std::this_thread::sleep_for(300ms);  // what the daemon holds drains
      make_idle();
      std::ostringstream out;
      std::ostringstream err;
      const int code =
          furuta::app::run_remote_command(RemoteKind::start, remote_, start_, out, err);
      const auto name = code == 0 ? running_session(out.str()) : std::nullopt;
      flooder_.set_paused(!flooding);
      if (!name) {
        std::cout << "  try " << number << ": start (" << t.start_mode << ") exit " << code << ": "
                  << first_line(err.str().empty() ? out.str() : err.str()) << "\n";
        continue;
      }
      // Under the flood for a while, then the e-stop; unless a safety rule ended it meanwhile.
      std::this_thread::sleep_for(
          std::chrono::duration<double>(options_.settle_s + phase_(random_)));
      if (std::filesystem::exists(log_path(*name))) {
        std::cout << "  try " << number << ": session " << *name
                  << " ended before the e-stop; starting another\n";
        continue;
      }
      t.session = *name;
    }
    if (t.session.empty()) return std::nullopt;

    observer_.arm(t.session);
    std::ostringstream out;
    std::ostringstream err;
    const std::uint64_t sent_before = flooder_.sent();
    const std::int64_t t0 = monotonic_ns();
    t.exit_code = furuta::app::run_remote_command(RemoteKind::estop, remote_, start_, out, err);
    const std::int64_t returned = monotonic_ns();
    t.sent_during = flooder_.sent() - sent_before;
    t.returned_ms = ms_since(t0, returned);
    t.says_estop = out.str().find(" ended: estop_command") != std::string::npos;
    if (t.exit_code != 0) t.cli_output = err.str() + out.str();

    // The log is finished a moment after the session ends; a status may still be on its way.
    const auto limit = SteadyClock::now() + 3s;
    EstopObservation seen = observer_.observation();
    while (SteadyClock::now() < limit && (!seen.reply_ns || !seen.status_shows_end_ns ||
                                          !std::filesystem::exists(log_path(t.session)))) {
      std::this_thread::sleep_for(10ms);
      seen = observer_.observation();
    }
    observer_.disarm();
    t.reply_ms = ms_or_none(t0, seen.reply_ns);
    t.reply_accepted = seen.reply_accepted;
    t.status_ms = ms_or_none(t0, seen.status_shows_end_ns);
    if (std::filesystem::exists(log_path(t.session))) {
      const LoggedEnd logged = read_logged_end(log_path(t.session), t0);
      t.end_reason = logged.end_reason;
      t.end_ms = ms_or_none(t0, logged.end_ns);
      t.effect_ms = ms_or_none(t0, logged.zero_write_ns);
    }
    const bool in_effect =
        t.effect_ms && *t.effect_ms <= kTargetMs && starts_with(t.end_reason, "estop_command");
    // Answered: the CLI got the reply (exit 0), in time as the observer saw it or, where the
    // observer missed it, no later than the call returned.
    const double answered_ms = t.reply_ms ? *t.reply_ms : t.returned_ms;
    t.within_target = t.exit_code == 0 && answered_ms <= kTargetMs && in_effect;
    return t;
  }

 private:
  std::filesystem::path log_path(const std::string& session) const {
    return logs_dir_ / (session + ".lcmlog");
  }

  // Until no session runs: an e-stop (unmeasured, the flood paused) when one does, e.g. one that a
  // start set going although its answer was lost.
  void make_idle() {
    for (int i = 0; i < 3; ++i) {
      const auto state = observer_.next_state(1500ms);
      if (state != furuta::rig_status_t::STATE_RUNNING) return;
      flooder_.set_paused(true);
      std::ostringstream sink;
      furuta::app::run_remote_command(RemoteKind::estop, remote_, start_, sink, sink);
      std::cout << "  (a session was running before the start: e-stopped it, flood paused)\n";
    }
  }

  const Options& options_;
  std::filesystem::path logs_dir_;
  Flooder& flooder_;
  Observer& observer_;
  SteadyClock::time_point deadline_;
  furuta::app::RemoteOptions remote_;
  furuta::app::StartOptions start_;
  std::mt19937_64 random_{std::random_device{}()};
  std::uniform_real_distribution<double> phase_{0.0, 0.05};
};

void print_table(const std::vector<Try>& tries) {
  std::cout << "\n"
            << std::setw(4) << "try" << std::setw(14) << "start" << std::setw(10) << "reply ms"
            << std::setw(11) << "effect ms" << std::setw(8) << "end ms" << std::setw(11)
            << "status ms" << std::setw(13) << "returned ms" << std::setw(6) << "exit"
            << std::setw(8) << "e-stop" << std::setw(9) << "in 100ms"
            << "\n";
  for (const Try& t : tries) {
    std::cout << std::setw(4) << t.number << std::setw(14) << t.start_mode << std::setw(10)
              << cell(t.reply_ms) << std::setw(11) << cell(t.effect_ms) << std::setw(8)
              << cell(t.end_ms) << std::setw(11) << cell(t.status_ms) << std::setw(13)
              << cell(t.returned_ms) << std::setw(6) << t.exit_code << std::setw(8)
              << (t.says_estop ? "yes" : "no") << std::setw(9) << (t.within_target ? "yes" : "no")
              << "\n";
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"estop_under_flood: `furuta estop` while wrongly signed starts flood the daemon"};
  Options options;
  app.add_option("--lcm-url", options.lcm_url, "The daemon's LCM URL (loopback, ttl=0)")
      ->required();
  app.add_option("--config", options.config, "The daemon's rig configuration")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--command-key", options.command_key, "The rig's command key (signs the starts)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--tries", options.tries, "E-stops to time")->check(CLI::Range(1, 1000));
  app.add_option("--rate", options.rate, "Wrongly signed commands a second (0: no flood)")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--flood-threads", options.flood_threads,
                 "Threads that share the flood, each with its own LCM instance")
      ->check(CLI::Range(1, 16));
  app.add_flag("--sendmmsg", options.sendmmsg,
               "Send the flood as LCM datagrams through one socket, 64 a sendmmsg call, instead "
               "of lcm_publish (far less of the machine spent making it)");
  app.add_option("--flood-nice", options.flood_nice,
                 "The flood threads' nice value (10: below a furutad run by its unit, Nice=-10, "
                 "by as much as another user's process is)")
      ->check(CLI::Range(0, 19));
  app.add_flag("--sign-each", options.sign_each,
               "Sign every flood message with the wrong key, not once per 1 ms batch");
  app.add_option("--settle-s", options.settle_s,
                 "Seconds a session runs under the flood before its e-stop")
      ->check(CLI::Range(0.0, 20.0));
  app.add_option("--time-limit-s", options.time_limit_s, "No try begins after this many seconds")
      ->check(CLI::Range(1.0, 7200.0));
  app.add_option("--json", options.json, "Also write the figures here");
  CLI11_PARSE(app, argc, argv);

  const std::filesystem::path logs_dir =
      furuta::config::load_rig_config(options.config).daemon.logs_dir;
  Observer observer(options.lcm_url);
  Flooder flooder(options.lcm_url, std::max(options.rate, 1.0), options.sign_each, options.sendmmsg,
                  options.flood_nice, options.flood_threads);
  if (!observer.good() || !flooder.good()) {
    std::cerr << "estop_under_flood: cannot open LCM at " << options.lcm_url << "\n";
    return 2;
  }
  {
    furuta::app::RemoteOptions probe;
    probe.lcm_url = options.lcm_url;
    probe.config_path = options.config;
    std::ostringstream out;
    std::ostringstream err;
    if (furuta::app::run_remote_command(RemoteKind::status, probe, {}, out, err) != 0) {
      std::cerr << "estop_under_flood: furutad does not answer: " << err.str();
      return 2;
    }
    std::cout << "furutad: " << out.str();
  }

  std::cout << "flood: " << options.rate << " wrongly signed starts a second on "
            << furuta::session_log::kChannelSignedCommand << " ("
            << (options.sign_each ? "each signed" : "signed once per 1 ms batch") << ", "
            << options.flood_threads << " thread(s)"
            << (options.sendmmsg ? ", sendmmsg" : ", lcm_publish") << ", nice "
            << options.flood_nice << "), " << options.lcm_url << "\n";
  Bench bench(options, logs_dir, flooder, observer);
  std::vector<Try> tries;
  const std::int64_t began = monotonic_ns();
  for (int i = 1; i <= options.tries && !bench.out_of_time(); ++i) {
    auto t = bench.run_try(i);
    if (!t) {
      std::cout << "  try " << i << ": no session could be started; skipped\n";
      continue;
    }
    std::cout << "  try " << i << ": session " << t->session << " (started with the "
              << t->start_mode << "), e-stop exit " << t->exit_code << ", reply "
              << cell(t->reply_ms) << " ms, effect " << cell(t->effect_ms) << " ms, returned "
              << cell(t->returned_ms) << " ms\n";
    if (!t->cli_output.empty()) std::cout << "    furuta estop said: " << t->cli_output;
    if (!starts_with(t->end_reason, "estop_command")) {
      std::cout << "    the e-stop did not act: "
                << (t->end_reason.empty() ? "the session still ran 3 s after the call returned"
                                          : "the session ended by " + t->end_reason)
                << "\n";
    }
    tries.push_back(std::move(*t));
  }
  flooder.set_paused(true);
  const double elapsed_s = ms_since(began, monotonic_ns()) * 1e-3;
  // A status after the flood stopped (periodic, 1 Hz) carries the daemon's final count.
  observer.next_state(1500ms);
  const Observer::Latest latest = observer.latest();

  print_table(tries);
  std::vector<double> reply, effect, end, status, returned;
  int within = 0;
  int started_paused = 0;
  int not_in_effect = 0;     // no end by e-stop within the try's window: the e-stop never acted
  int unanswered = 0;        // the call saw no answer (exit 2)
  int acted_unanswered = 0;  // ... although the e-stop acted (its answer was lost on the way)
  int missed_reply = 0;      // ... and the observer saw that answer
  for (const Try& t : tries) {
    if (t.reply_ms) reply.push_back(*t.reply_ms);
    if (t.effect_ms) effect.push_back(*t.effect_ms);
    if (t.end_ms) end.push_back(*t.end_ms);
    if (t.status_ms) status.push_back(*t.status_ms);
    returned.push_back(t.returned_ms);
    within += t.within_target ? 1 : 0;
    started_paused += t.start_mode == "flood paused" ? 1 : 0;
    const bool acted = starts_with(t.end_reason, "estop_command");
    not_in_effect += acted ? 0 : 1;
    unanswered += t.exit_code != 0 ? 1 : 0;
    acted_unanswered += t.exit_code != 0 && acted ? 1 : 0;
    missed_reply += t.exit_code != 0 && acted && t.reply_ms ? 1 : 0;
  }
  const std::vector<std::pair<std::string, Summary>> summaries = {
      {"reply (observer)", summarize(reply)},
      {"effect (zero written, log)", summarize(effect)},
      {"end (loop's cycle, log)", summarize(end)},
      {"status shows the end", summarize(status)},
      {"furuta estop returned", summarize(returned)}};
  std::cout << "\n"
            << std::left << std::setw(28) << "ms after the e-stop" << std::right << std::setw(4)
            << "n" << std::setw(9) << "min" << std::setw(9) << "median" << std::setw(9) << "p95"
            << std::setw(9) << "max"
            << "\n";
  for (const auto& [what, s] : summaries) {
    std::cout << std::left << std::setw(28) << what << std::right << std::setw(4) << s.n
              << std::fixed << std::setprecision(1) << std::setw(9) << s.min << std::setw(9)
              << s.median << std::setw(9) << s.p95 << std::setw(9) << s.max << "\n";
    std::cout.unsetf(std::ios::floatfield);
  }
  std::cout << "\n"
            << within << " of " << options.tries << " tries answered and in effect within "
            << kTargetMs << " ms (" << tries.size() << " ran, " << started_paused
            << " of their sessions started with the flood paused)\n"
            << "e-stops that never acted (the session ran on): " << not_in_effect
            << "; calls that saw no answer (exit 2): " << unanswered << ", in " << acted_unanswered
            << " of them the e-stop acted (the observer saw the daemon's answer in " << missed_reply
            << ")\n";
  const double sent = static_cast<double>(flooder.sent());
  const double refused_pct =
      sent > 0 ? 100.0 * static_cast<double>(latest.refused_unauthenticated) / sent : 0.0;
  std::cout << std::fixed << std::setprecision(0) << "flood: asked " << options.rate
            << "/s, achieved " << flooder.achieved_rate() << "/s (" << flooder.sent() << " sent in "
            << std::setprecision(1) << flooder.flooding_s() << " s of flooding, "
            << flooder.schedule_resets() << " times more than 100 ms behind schedule)\n"
            << "daemon: refused_unauthenticated " << latest.refused_unauthenticated << " ("
            << refused_pct << " % of those sent); observer: " << latest.statuses
            << " statuses received, " << latest.flood_replies << " of them replies to the flood; "
            << elapsed_s << " s in all\n";
  std::cout.unsetf(std::ios::floatfield);

  if (!options.json.empty()) {
    nlohmann::json doc;
    doc["target_ms"] = kTargetMs;
    doc["tries_asked"] = options.tries;
    doc["tries_run"] = tries.size();
    doc["within_target"] = within;
    doc["not_in_effect"] = not_in_effect;
    doc["unanswered"] = unanswered;
    doc["unanswered_although_acted"] = acted_unanswered;
    doc["unanswered_although_acted_answer_observed"] = missed_reply;
    doc["started_with_flood_paused"] = started_paused;
    doc["flood"] = {{"rate_asked", options.rate},
                    {"rate_achieved", flooder.achieved_rate()},
                    {"sign_each", options.sign_each},
                    {"sendmmsg", options.sendmmsg},
                    {"nice", options.flood_nice},
                    {"threads", options.flood_threads},
                    {"sent", flooder.sent()},
                    {"flooding_s", flooder.flooding_s()},
                    {"schedule_resets", flooder.schedule_resets()}};
    doc["daemon"] = {{"refused_unauthenticated", latest.refused_unauthenticated}};
    doc["observer"] = {{"statuses", latest.statuses}, {"flood_replies", latest.flood_replies}};
    doc["elapsed_s"] = elapsed_s;
    for (const auto& [what, s] : summaries) doc["summary_ms"][what] = to_json(s);
    doc["tries"] = nlohmann::json::array();
    for (const Try& t : tries) {
      doc["tries"].push_back({{"try", t.number},
                              {"start_mode", t.start_mode},
                              {"start_attempts", t.start_attempts},
                              {"session", t.session},
                              {"reply_ms", optional_json(t.reply_ms)},
                              {"reply_accepted", t.reply_accepted},
                              {"effect_ms", optional_json(t.effect_ms)},
                              {"end_ms", optional_json(t.end_ms)},
                              {"status_ms", optional_json(t.status_ms)},
                              {"returned_ms", t.returned_ms},
                              {"exit_code", t.exit_code},
                              {"says_estop", t.says_estop},
                              {"end_reason", t.end_reason},
                              {"flood_sent_during_call", t.sent_during},
                              {"within_target", t.within_target},
                              {"cli_output", t.cli_output}});
    }
    std::ofstream file(options.json);
    file << doc.dump(2) << "\n";
    if (!file) {
      std::cerr << "estop_under_flood: cannot write " << options.json << "\n";
      return 2;
    }
  }
  return 0;
}
