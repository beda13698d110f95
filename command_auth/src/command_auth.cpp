#include "furuta/command_auth/command_auth.hpp"

#include <fcntl.h>
#include <glib.h>
#include <grp.h>
#include <pwd.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <memory>
#include <random>
#include <sstream>
#include <vector>

namespace furuta::command_auth {

namespace {

// Bumped if the signed layout ever changes, so an old tag can never verify under a new layout.
constexpr char kDomain[] = "furuta rig_signed_command_t v1";

struct FdCloser {
  int fd = -1;
  ~FdCloser() {
    if (fd >= 0) ::close(fd);
  }
};

struct HmacFree {
  void operator()(GHmac* hmac) const { g_hmac_unref(hmac); }
};

void put_u64(GHmac* hmac, std::uint64_t value) {
  std::uint8_t bytes[8];
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<std::uint8_t>(value >> (8 * i));
  g_hmac_update(hmac, bytes, sizeof bytes);
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string octal_mode(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", static_cast<unsigned>(mode & 07777));
  return text;
}

// Compares in time that does not depend on where the first difference is.
bool same_tag(const CommandTag& a, const std::uint8_t (&b)[32]) {
  unsigned difference = 0;
  for (std::size_t i = 0; i < a.size(); ++i) difference |= a[i] ^ b[i];
  return difference == 0;
}

std::string seconds_text(std::int64_t ns) {
  std::ostringstream out;
  out.precision(3);
  out << static_cast<double>(ns) * 1e-9 << " s";
  return out.str();
}

}  // namespace

bool moves_motor(const furuta::rig_command_t& command) {
  // Unknown kinds are refused by the validator; here they count as moving, to be safe.
  return command.kind != furuta::rig_command_t::KIND_STOP &&
         command.kind != furuta::rig_command_t::KIND_ESTOP &&
         command.kind != furuta::rig_command_t::KIND_STATUS_REQUEST;
}

KeyFile read_command_key(const std::filesystem::path& path) {
  KeyFile result;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    const int error = errno;
    result.permission_denied = error == EACCES || error == EPERM;
    result.problem = "cannot read the command key " + path.string() + ": " + std::strerror(error);
    return result;
  }
  FdCloser closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    result.problem = "the command key " + path.string() + " is not a regular file";
    return result;
  }
  if ((st.st_mode & (S_IROTH | S_IWOTH)) != 0) {
    result.problem = "the command key " + path.string() + " has mode " + octal_mode(st.st_mode) +
                     ": every user can read it, so it proves nothing (chmod 0640, group furuta)";
    return result;
  }
  char buffer[256];
  const ssize_t n = ::read(fd, buffer, sizeof buffer);
  if (n < 0) {
    result.problem = "cannot read the command key " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  std::string text(buffer, static_cast<std::size_t>(n));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) {
    text.pop_back();
  }
  const std::string where = path.string() + ": line 1: ";
  if (text.find('\n') != std::string::npos) {
    result.problem = where + "the key is one line of 64 hexadecimal digits, found more lines";
    return result;
  }
  if (text.size() != 2 * kKeyBytes) {
    result.problem = where + "expected 64 hexadecimal digits (a 32-byte key), found " +
                     std::to_string(text.size()) + " characters";
    return result;
  }
  CommandKey key{};
  for (std::size_t i = 0; i < kKeyBytes; ++i) {
    const int high = hex_digit(text[2 * i]);
    const int low = hex_digit(text[2 * i + 1]);
    if (high < 0 || low < 0) {
      const std::size_t column = (high < 0 ? 2 * i : 2 * i + 1) + 1;
      result.problem = where + "column " + std::to_string(column) + ": '" + text[column - 1] +
                       "' is not a hexadecimal digit";
      return result;
    }
    key[i] = static_cast<std::uint8_t>(high * 16 + low);
  }
  result.key = key;
  return result;
}

KeyCreation ensure_command_key(const std::filesystem::path& path, const std::string& group) {
  KeyCreation result;
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) return result;  // there already: never replaced here
  if (errno != ENOENT) {
    result.problem = "cannot look at " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  CommandKey key{};
  if (::getrandom(key.data(), key.size(), 0) != static_cast<ssize_t>(key.size())) {
    result.problem = std::string("no random bytes for a command key: ") + std::strerror(errno);
    return result;
  }
  std::string text;
  static constexpr char kHex[] = "0123456789abcdef";
  for (std::uint8_t b : key) {
    text += kHex[b >> 4];
    text += kHex[b & 15];
  }
  text += '\n';
  // Written beside it and linked into place, so the key appears whole or not at all, and a key
  // another process created meanwhile is kept (link refuses to replace).
  std::string temp = path.string() + ".newXXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) {
    result.problem = "cannot create the command key " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  bool linked = false;
  {
    FdCloser closer{fd};
    std::string why;
    if (::fchmod(fd, 0640) != 0) why = std::string("chmod: ") + std::strerror(errno);
    if (why.empty() && ::geteuid() == 0 && !group.empty()) {
      struct group entry {};
      struct group* found = nullptr;
      std::vector<char> buffer(4096);
      if (::getgrnam_r(group.c_str(), &entry, buffer.data(), buffer.size(), &found) == 0 && found &&
          ::fchown(fd, 0, found->gr_gid) != 0) {
        why = std::string("chown root:") + group + ": " + std::strerror(errno);
      }
    }
    if (why.empty() && ::write(fd, text.data(), text.size()) != static_cast<ssize_t>(text.size())) {
      why = std::string("write: ") + std::strerror(errno);
    }
    if (why.empty() && ::fsync(fd) != 0) why = std::string("fsync: ") + std::strerror(errno);
    if (why.empty()) {
      if (::link(temp.c_str(), path.c_str()) == 0) {
        linked = true;
      } else if (errno != EEXIST) {
        why = std::string("link: ") + std::strerror(errno);
      }
    }
    if (!why.empty())
      result.problem = "cannot create the command key " + path.string() + ": " + why;
  }
  ::unlink(temp.c_str());
  result.created = linked;
  return result;
}

CommandTag command_tag(const CommandKey& key, const furuta::rig_signed_command_t& message) {
  std::unique_ptr<GHmac, HmacFree> hmac(g_hmac_new(G_CHECKSUM_SHA256, key.data(), key.size()));
  g_hmac_update(hmac.get(), reinterpret_cast<const guchar*>(kDomain), sizeof kDomain);
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

CommandVerifier::CommandVerifier(std::optional<CommandKey> key, std::string key_problem,
                                 VerifierSettings settings, std::int64_t started_wall_ns)
    : key_(key),
      key_problem_(std::move(key_problem)),
      settings_(settings),
      started_wall_ns_(started_wall_ns) {}

void CommandVerifier::forget_before(std::int64_t wall_ns) {
  while (!taken_.empty() && taken_.front().first < wall_ns) {
    taken_tags_.erase(taken_.front().second);
    taken_.pop_front();
  }
}

Verdict CommandVerifier::verify(const furuta::rig_signed_command_t& message,
                                std::int64_t now_wall_ns) {
  Verdict verdict;
  if (!key_) {
    verdict.reason = "this daemon has no command key, so it takes no start: " + key_problem_;
    return verdict;
  }
  const CommandTag expected = command_tag(*key_, message);
  if (!same_tag(expected, message.tag)) {
    verdict.reason = "bad signature from \"" + message.sender +
                     "\": not signed with this rig's command key, or changed on the way";
    return verdict;
  }
  const std::int64_t window = settings_.window.count();
  if (message.signed_wall_ns < started_wall_ns_) {
    verdict.reason = "signed before this daemon started (" +
                     seconds_text(started_wall_ns_ - message.signed_wall_ns) +
                     "): refused as a possible replay; sign it again";
    return verdict;
  }
  if (message.signed_wall_ns < now_wall_ns - window ||
      message.signed_wall_ns > now_wall_ns + window) {
    const std::int64_t off = message.signed_wall_ns - now_wall_ns;
    verdict.reason = "signed " + seconds_text(off < 0 ? -off : off) +
                     (off < 0 ? " ago" : " ahead of the daemon's clock") + ", outside the +- " +
                     seconds_text(window) +
                     " a signed command is taken in (replayed, or the clocks are out of step)";
    return verdict;
  }
  forget_before(now_wall_ns - window);
  if (taken_tags_.count(expected) != 0) {
    verdict.reason = "replayed: this signed command was taken already";
    return verdict;
  }
  if (taken_.size() >= settings_.max_remembered) {
    verdict.reason = "more than " + std::to_string(settings_.max_remembered) +
                     " signed commands within the replay window; try again shortly";
    return verdict;
  }
  if (message.command.empty() ||
      verdict.command.decode(message.command.data(), 0, static_cast<int>(message.command.size())) !=
          static_cast<int>(message.command.size())) {
    verdict.reason = "the signed bytes are not one rig_command_t";
    return verdict;
  }
  taken_.emplace_back(message.signed_wall_ns, expected);
  taken_tags_.insert(expected);
  verdict.accepted = true;
  return verdict;
}

}  // namespace furuta::command_auth
