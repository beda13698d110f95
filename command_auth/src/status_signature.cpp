#include "furuta/command_auth/status_signature.hpp"

#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <vector>

#include "furuta/common/wire_text.hpp"

namespace furuta::command_auth {

namespace {

// Bumped if the signed layout ever changes, so an old signature never checks under a new layout.
constexpr char kStatusDomain[] = "furuta rig_status_t v1";

void ensure_sodium() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (::sodium_init() < 0) throw std::runtime_error("libsodium could not be initialised");
  });
}

// The bytes a signature covers: the domain, then the status encoded with its signature zeroed.
std::vector<std::uint8_t> signed_bytes(furuta::rig_status_t status) {
  std::fill(std::begin(status.signature), std::end(status.signature), 0);
  const int size = status.getEncodedSize();
  std::vector<std::uint8_t> bytes(sizeof kStatusDomain + static_cast<std::size_t>(size));
  std::memcpy(bytes.data(), kStatusDomain, sizeof kStatusDomain);
  status.encode(bytes.data() + sizeof kStatusDomain, 0, size);
  return bytes;
}

std::string hex_text(const DaemonPublicKey& key) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string text;
  for (std::uint8_t b : key) {
    text += kHex[b >> 4];
    text += kHex[b & 15];
  }
  return text + "\n";
}

struct ClosesFd {
  int fd = -1;
  ~ClosesFd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

void bound_status_text(furuta::rig_status_t& s) {
  // Shares of kMaxStatusBytes: the fixed fields and the signature take under 400 bytes.
  constexpr std::size_t kName = 128, kEnd = 256, kReason = 512;
  s.session = text::printable_text(s.session, kName);
  s.request_reason = text::printable_text(s.request_reason, kReason);
  s.last_fault = text::printable_text(s.last_fault, kReason);
  s.last_fault_session = text::printable_text(s.last_fault_session, kName);
  s.last_session = text::printable_text(s.last_session, kName);
  s.last_session_end = text::printable_text(s.last_session_end, kEnd);
  s.refused_reason = text::printable_text(s.refused_reason, kReason);
  s.logs_problem = text::printable_text(s.logs_problem, kReason);
  s.unauthenticated_reason = text::printable_text(s.unauthenticated_reason, kReason);
}

StatusSigner::StatusSigner(const CommandKey& seed) {
  ensure_sodium();
  static_assert(crypto_sign_SEEDBYTES == kKeyBytes);
  static_assert(crypto_sign_SECRETKEYBYTES == 64 && crypto_sign_PUBLICKEYBYTES == 32);
  ::crypto_sign_seed_keypair(public_key_.data(), secret_key_.data(), seed.data());
}

StatusSigner::~StatusSigner() {
  ::sodium_memzero(secret_key_.data(), secret_key_.size());
}

void StatusSigner::sign(furuta::rig_status_t& status) const {
  const std::vector<std::uint8_t> bytes = signed_bytes(status);
  static_assert(sizeof status.signature == crypto_sign_BYTES);
  ::crypto_sign_detached(status.signature, nullptr, bytes.data(), bytes.size(), secret_key_.data());
}

std::string_view to_string(StatusAuthenticity authenticity) {
  switch (authenticity) {
    case StatusAuthenticity::signed_by_daemon:
      return "signed by the daemon";
    case StatusAuthenticity::unsigned_status:
      return "unsigned";
    case StatusAuthenticity::wrongly_signed:
      return "wrongly signed";
  }
  return "?";
}

StatusAuthenticity check_status(const furuta::rig_status_t& status, const DaemonPublicKey& key) {
  ensure_sodium();
  if (std::all_of(std::begin(status.signature), std::end(status.signature),
                  [](std::uint8_t b) { return b == 0; })) {
    return StatusAuthenticity::unsigned_status;
  }
  const std::vector<std::uint8_t> bytes = signed_bytes(status);
  return ::crypto_sign_verify_detached(status.signature, bytes.data(), bytes.size(), key.data()) ==
                 0
             ? StatusAuthenticity::signed_by_daemon
             : StatusAuthenticity::wrongly_signed;
}

DaemonPublicKey daemon_public_key(const CommandKey& seed) {
  return StatusSigner(seed).public_key();
}

PublicKeyFile read_daemon_public_key(const std::filesystem::path& path) {
  PublicKeyFile result;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    result.problem =
        "cannot read the daemon's public key " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  ClosesFd closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    result.problem = "the daemon's public key " + path.string() + " is not a regular file";
    return result;
  }
  if (st.st_uid != 0 && st.st_uid != ::geteuid()) {
    result.problem = "the daemon's public key " + path.string() + " is owned by user " +
                     std::to_string(st.st_uid) +
                     ", who could replace it: it must be root's (furutad --create-command-key)";
    return result;
  }
  if ((st.st_mode & S_IWOTH) != 0 || ((st.st_mode & S_IWGRP) != 0 && st.st_gid != 0)) {
    result.problem = "the daemon's public key " + path.string() +
                     " may be changed by users other than its owner: chmod 0644";
    return result;
  }
  char buffer[256];
  const ssize_t n = ::read(fd, buffer, sizeof buffer);
  if (n < 0) {
    result.problem =
        "cannot read the daemon's public key " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  std::string text(buffer, static_cast<std::size_t>(n));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) {
    text.pop_back();
  }
  const std::optional<CommandKey> key = key_from_hex(text);
  if (!key) {
    result.problem = path.string() + ": line 1: expected 64 hexadecimal digits (a 32-byte key)";
    return result;
  }
  result.key = *key;
  return result;
}

std::string write_daemon_public_key(const std::filesystem::path& path, const DaemonPublicKey& key) {
  const PublicKeyFile existing = read_daemon_public_key(path);
  if (existing.key == key) return {};
  const std::string text = hex_text(key);
  const std::string temp = path.string() + ".new";
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0) return "cannot create " + temp + ": " + std::strerror(errno);
  std::string why;
  {
    ClosesFd closer{fd};
    if (::fchmod(fd, 0644) != 0) why = std::string("chmod: ") + std::strerror(errno);
    if (why.empty() && ::write(fd, text.data(), text.size()) != static_cast<ssize_t>(text.size())) {
      why = std::string("write: ") + std::strerror(errno);
    }
    if (why.empty() && ::fsync(fd) != 0) why = std::string("fsync: ") + std::strerror(errno);
  }
  if (why.empty() && ::rename(temp.c_str(), path.c_str()) != 0) {
    why = std::string("rename: ") + std::strerror(errno);
  }
  if (!why.empty()) {
    ::unlink(temp.c_str());
    return "cannot write the daemon's public key " + path.string() + ": " + why;
  }
  return {};
}

}  // namespace furuta::command_auth
