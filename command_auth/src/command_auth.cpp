#include "furuta/command_auth/command_auth.hpp"

#include <fcntl.h>
#include <glib.h>
#include <pwd.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <vector>

#include "furuta/common/wire_text.hpp"

namespace furuta::command_auth {

namespace {

// Bumped if the signed layout ever changes, so an old tag can never verify under a new layout.
constexpr char kCommandDomain[] = "furuta rig_signed_command_t v1";

struct HmacFree {
  void operator()(GHmac* hmac) const { g_hmac_unref(hmac); }
};

void put_u64(GHmac* hmac, std::uint64_t value) {
  std::uint8_t bytes[8];
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<std::uint8_t>(value >> (8 * i));
  g_hmac_update(hmac, bytes, sizeof bytes);
}

// Compares in time that does not depend on where the first difference is.
bool same_tag(const CommandTag& a, const std::uint8_t (&b)[32]) {
  unsigned difference = 0;
  for (std::size_t i = 0; i < a.size(); ++i) difference |= a[i] ^ b[i];
  return difference == 0;
}

}  // namespace

bool moves_motor(const furuta::rig_command_t& command) {
  // Unknown kinds are refused by the validator; here they count as moving, to be safe.
  return command.kind != furuta::rig_command_t::KIND_STOP &&
         command.kind != furuta::rig_command_t::KIND_ESTOP &&
         command.kind != furuta::rig_command_t::KIND_STATUS_REQUEST;
}

CommandTag command_tag(const CommandKey& key, const furuta::rig_signed_command_t& message) {
  std::unique_ptr<GHmac, HmacFree> hmac(g_hmac_new(G_CHECKSUM_SHA256, key.data(), key.size()));
  g_hmac_update(hmac.get(), reinterpret_cast<const guchar*>(kCommandDomain), sizeof kCommandDomain);
  put_u64(hmac.get(), static_cast<std::uint64_t>(message.signed_wall_ns));
  put_u64(hmac.get(), static_cast<std::uint64_t>(message.nonce));
  put_u64(hmac.get(), message.sender.size());
  g_hmac_update(hmac.get(), reinterpret_cast<const guchar*>(message.sender.data()),
                static_cast<gssize>(message.sender.size()));
  put_u64(hmac.get(), message.command.size());
  if (!message.command.empty()) {
    g_hmac_update(hmac.get(), message.command.data(), static_cast<gssize>(message.command.size()));
  }
  CommandTag tag{};
  gsize length = tag.size();
  g_hmac_get_digest(hmac.get(), tag.data(), &length);
  return tag;
}

furuta::rig_signed_command_t sign_command(const furuta::rig_command_t& command,
                                          const CommandKey& key, const std::string& sender,
                                          std::int64_t signed_wall_ns, std::int64_t nonce) {
  furuta::rig_signed_command_t m{};
  m.sender = sender;
  m.signed_wall_ns = signed_wall_ns;
  m.nonce = nonce;
  m.command.resize(static_cast<std::size_t>(command.getEncodedSize()));
  command.encode(m.command.data(), 0, static_cast<int>(m.command.size()));
  m.command_size = static_cast<std::int32_t>(m.command.size());
  const CommandTag tag = command_tag(key, m);
  std::copy(tag.begin(), tag.end(), m.tag);
  return m;
}

furuta::rig_signed_command_t sign_command_now(const furuta::rig_command_t& command,
                                              const CommandKey& key, const std::string& sender) {
  std::random_device entropy;
  const auto nonce = static_cast<std::int64_t>((std::uint64_t{entropy()} << 32) ^ entropy());
  const std::int64_t now_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                  std::chrono::system_clock::now().time_since_epoch())
                                  .count();
  return sign_command(command, key, sender, now_ns, nonce);
}

std::string this_sender() {
  std::string user = std::to_string(::geteuid());
  struct passwd entry {};
  struct passwd* found = nullptr;
  std::vector<char> buffer(4096);
  if (::getpwuid_r(::geteuid(), &entry, buffer.data(), buffer.size(), &found) == 0 && found) {
    user = found->pw_name;
  }
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) std::strcpy(host, "unknown-host");
  return user + "@" + host;
}

namespace {

constexpr char kStateHeader[] = "furuta command replay state v1";
constexpr char kStateKey[] = "highest_signed_wall_ns";

// a - b without overflow, saturated to the int64 range: signing times come from the wire.
std::int64_t saturating_difference(std::int64_t a, std::int64_t b) {
  std::int64_t out = 0;
  if (__builtin_sub_overflow(a, b, &out)) {
    return a > b ? std::numeric_limits<std::int64_t>::max()
                 : std::numeric_limits<std::int64_t>::min();
  }
  return out;
}

std::int64_t saturating_sum(std::int64_t a, std::int64_t b) {
  std::int64_t out = 0;
  if (__builtin_add_overflow(a, b, &out)) {
    return b > 0 ? std::numeric_limits<std::int64_t>::max()
                 : std::numeric_limits<std::int64_t>::min();
  }
  return out;
}

// |difference| in seconds, for messages; any pair of int64 times formats without overflow.
std::string distance_text(std::int64_t a, std::int64_t b) {
  const long double seconds = (static_cast<long double>(a) - static_cast<long double>(b)) * 1e-9L;
  std::ostringstream out;
  out.precision(3);
  out << static_cast<double>(seconds < 0 ? -seconds : seconds) << " s";
  return out.str();
}

Verdict refused(Refusal refusal, std::string reason) {
  Verdict verdict;
  verdict.refusal = refusal;
  verdict.reason = std::move(reason);
  return verdict;
}

}  // namespace

ReplayState read_replay_state(const std::filesystem::path& path) {
  ReplayState state;
  std::ifstream in(path);
  if (!in) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec) && !ec) return state;
    state.problem = "cannot read the replay state " + path.string() + ": " + std::strerror(errno);
    return state;
  }
  std::string header, key;
  std::getline(in, header);
  if (header != kStateHeader) {
    state.problem = path.string() + ": line 1: expected \"" + kStateHeader + "\"";
    return state;
  }
  long long value = 0;
  if (!(in >> key >> value) || key != kStateKey) {
    state.problem = path.string() + ": line 2: expected \"" + kStateKey + " <ns>\"";
    return state;
  }
  state.highest_signed_wall_ns = value;
  return state;
}

std::string write_replay_state(const std::filesystem::path& path,
                               std::int64_t highest_signed_wall_ns) {
  const std::string text = std::string(kStateHeader) + "\n" + kStateKey + " " +
                           std::to_string(highest_signed_wall_ns) + "\n";
  const std::string temp = path.string() + ".new";
  const auto fail = [&](const char* what) {
    const std::string why = std::string(what) + " " + temp + ": " + std::strerror(errno);
    ::unlink(temp.c_str());
    return why;
  };
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0640);
  if (fd < 0) return fail("cannot create");
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  const bool synced = written && ::fsync(fd) == 0;
  ::close(fd);
  if (!written) return fail("cannot write");
  if (!synced) return fail("cannot sync");
  if (::rename(temp.c_str(), path.c_str()) != 0) return fail("cannot rename into place");
  // The rename itself reaches the disk with its directory.
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return {};
}

CommandVerifier::CommandVerifier(std::optional<CommandKey> key, std::string key_problem,
                                 VerifierSettings settings, std::int64_t now_wall_ns,
                                 std::int64_t now_monotonic_ns)
    : key_(key),
      key_problem_(std::move(key_problem)),
      settings_(std::move(settings)),
      started_wall_ns_(now_wall_ns),
      started_monotonic_ns_(now_monotonic_ns),
      highest_taken_ns_(std::numeric_limits<std::int64_t>::min()) {
  start_floor_wall_ns_ = now_wall_ns;
  if (settings_.state_file.empty()) return;
  const ReplayState state = read_replay_state(settings_.state_file);
  if (state.highest_signed_wall_ns) {
    highest_taken_ns_ = *state.highest_signed_wall_ns;
    start_floor_wall_ns_ = std::max(start_floor_wall_ns_, saturating_sum(highest_taken_ns_, 1));
    return;
  }
  if (state.problem.empty()) return;  // no file yet: nothing was ever taken with it
  // Unreadable: anything an earlier daemon took was signed at most max_ahead past its clock,
  // which was before now unless the clock was stepped back.
  start_floor_wall_ns_ = saturating_sum(now_wall_ns, settings_.max_ahead.count());
  state_problem_ = state.problem + "; starts signed before " +
                   distance_text(start_floor_wall_ns_, now_wall_ns) +
                   " from now are refused as possible replays";
}

std::int64_t CommandVerifier::floor_wall_ns(std::int64_t now_monotonic_ns) const {
  const std::int64_t elapsed = saturating_difference(now_monotonic_ns, started_monotonic_ns_);
  const std::int64_t trailing =
      saturating_difference(saturating_sum(started_wall_ns_, std::max<std::int64_t>(0, elapsed)),
                            settings_.window.count());
  return std::max(start_floor_wall_ns_, trailing);
}

std::string CommandVerifier::record_taken(std::int64_t signed_wall_ns) {
  if (settings_.state_file.empty() || signed_wall_ns <= highest_taken_ns_) return {};
  if (std::string why = write_replay_state(settings_.state_file, signed_wall_ns); !why.empty()) {
    return why;
  }
  highest_taken_ns_ = signed_wall_ns;
  return {};
}

Verdict CommandVerifier::verify(const furuta::rig_signed_command_t& message,
                                std::int64_t now_wall_ns, std::int64_t now_monotonic_ns) {
  if (!key_) {
    return refused(Refusal::no_key,
                   "this daemon has no command key, so it takes no start: " + key_problem_);
  }
  // Sizes first: nothing of an oversized message is hashed, stored or echoed.
  if (message.sender.size() > settings_.max_sender_bytes) {
    return refused(Refusal::malformed, "sender: " + std::to_string(message.sender.size()) +
                                           " bytes, above the limit of " +
                                           std::to_string(settings_.max_sender_bytes));
  }
  if (message.command.size() > settings_.max_command_bytes) {
    return refused(Refusal::malformed, "command: " + std::to_string(message.command.size()) +
                                           " bytes, above the limit of " +
                                           std::to_string(settings_.max_command_bytes));
  }
  const CommandTag expected = command_tag(*key_, message);
  if (!same_tag(expected, message.tag)) {
    return refused(Refusal::bad_signature,
                   "bad signature from " + text::wire_quoted(message.sender, 64) +
                       ": not signed with this rig's command key, or changed on the way");
  }
  Verdict verdict;
  if (message.command.empty() ||
      verdict.command.decode(message.command.data(), 0, static_cast<int>(message.command.size())) !=
          static_cast<int>(message.command.size())) {
    return refused(Refusal::malformed, "the signed bytes are not one rig_command_t");
  }
  if (!moves_motor(verdict.command)) {
    // Its tag says who sent it; replaying a stop or a status request moves nothing.
    verdict.accepted = true;
    return verdict;
  }
  const std::int64_t signed_ns = message.signed_wall_ns;
  const std::int64_t window = settings_.window.count();
  if (signed_ns < saturating_difference(now_wall_ns, window)) {
    return refused(Refusal::out_of_time,
                   "signed " + distance_text(now_wall_ns, signed_ns) + " ago, outside the " +
                       distance_text(window, 0) +
                       " a signed command is taken in (replayed, or the clocks are out of step)");
  }
  if (signed_ns > saturating_sum(now_wall_ns, settings_.max_ahead.count())) {
    return refused(Refusal::out_of_time, "signed " + distance_text(signed_ns, now_wall_ns) +
                                             " ahead of the daemon's clock, more than the " +
                                             distance_text(settings_.max_ahead.count(), 0) +
                                             " allowed (the clocks are out of step: NTP on both)");
  }
  const std::int64_t floor = floor_wall_ns(now_monotonic_ns);
  if (signed_ns < floor) {
    return refused(Refusal::out_of_time,
                   "signed " + distance_text(floor, signed_ns) +
                       " before the replay floor (this daemon's start, the latest command it "
                       "took before a restart, or its window since): refused as a possible "
                       "replay; sign it again");
  }
  while (!taken_.empty() && taken_.begin()->first < floor) {
    taken_tags_.erase(taken_.begin()->second);
    taken_.erase(taken_.begin());
  }
  if (taken_tags_.count(expected) != 0) {
    return refused(Refusal::replayed, "replayed: this signed command was taken already");
  }
  if (taken_.size() >= settings_.max_remembered) {
    return refused(Refusal::memory_full, "more than " + std::to_string(settings_.max_remembered) +
                                             " signed commands within the replay window; try "
                                             "again shortly");
  }
  if (std::string why = record_taken(signed_ns); !why.empty()) {
    return refused(Refusal::not_recorded,
                   "cannot record the replay floor (" + why +
                       "): refused, since a restart could then take it again");
  }
  taken_.emplace(signed_ns, expected);
  taken_tags_.insert(expected);
  verdict.accepted = true;
  return verdict;
}

}  // namespace furuta::command_auth
