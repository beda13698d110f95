#pragma once
// What the daemon says, authenticated: every rig_status_t furutad publishes carries an Ed25519
// signature under the daemon's key, whose public half every user can read and check
// (docs/security.md). The private half is a seed in a key file like the command key's; the public
// half is a world-readable file beside it. A status is also bounded in size, so no message from a
// stranger can make the daemon's answers too large to receive.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "furuta/command_auth/key_file.hpp"
#include "furuta/rig_status_t.hpp"

namespace furuta::command_auth {

// The most a status the daemon publishes encodes to; a tool drops anything larger unread.
inline constexpr std::size_t kMaxStatusBytes = 4096;

using DaemonPublicKey = std::array<std::uint8_t, 32>;

// Every text field cut to its share of kMaxStatusBytes and escaped (text::wire_text), so the
// encoded status fits whatever the texts were.
void bound_status_text(furuta::rig_status_t& status);

// Signs statuses with the Ed25519 pair derived from a 32-byte seed (the daemon key file's bytes).
class StatusSigner {
 public:
  explicit StatusSigner(const CommandKey& seed);
  ~StatusSigner();  // the secret is wiped
  StatusSigner(const StatusSigner&) = delete;
  StatusSigner& operator=(const StatusSigner&) = delete;

  // Fills `status.signature` over the rest of the message.
  void sign(furuta::rig_status_t& status) const;
  const DaemonPublicKey& public_key() const { return public_key_; }

 private:
  std::array<std::uint8_t, 64> secret_key_{};
  DaemonPublicKey public_key_{};
};

enum class StatusAuthenticity {
  signed_by_daemon,  // the signature checks out under the trusted public key
  unsigned_status,   // no signature (all zero): a daemon without a key, or anyone
  wrongly_signed,    // a signature that does not check out: forged, changed, or another daemon
};
std::string_view to_string(StatusAuthenticity authenticity);
StatusAuthenticity check_status(const furuta::rig_status_t& status, const DaemonPublicKey& key);

// The public key file: 64 hexadecimal digits and an optional newline. Anyone may read it; it is
// refused when anyone but root or the caller could change it (the mode's group or other write
// bits). `problem` names the file and what is wrong.
struct PublicKeyFile {
  std::optional<DaemonPublicKey> key;
  std::string problem;
};
PublicKeyFile read_daemon_public_key(const std::filesystem::path& path);
DaemonPublicKey daemon_public_key(const CommandKey& seed);
// Writes `key` at `path` (mode 0644) unless the file there already holds it: written beside it,
// synced and renamed into place. "" or why not.
std::string write_daemon_public_key(const std::filesystem::path& path, const DaemonPublicKey& key);

}  // namespace furuta::command_auth
