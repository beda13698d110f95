#pragma once
// Who may move the motor: commands that do carry an HMAC-SHA256 tag under the rig's command key,
// a secret in a file that only root and group `furuta` can read (docs/security.md). The signer
// (`furuta start`) and the verifier (furutad) share these few functions.

#include <array>
#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <optional>
#include <set>
#include <string>

#include "furuta/rig_command_t.hpp"
#include "furuta/rig_signed_command_t.hpp"

namespace furuta::command_auth {

inline constexpr std::size_t kKeyBytes = 32;
using CommandKey = std::array<std::uint8_t, kKeyBytes>;
using CommandTag = std::array<std::uint8_t, 32>;

// Stopping is always safe and a status request changes nothing: only these need a tag.
bool moves_motor(const furuta::rig_command_t& command);

// The key file: 64 hexadecimal digits (32 bytes) and an optional newline, mode 0640 or stricter.
struct KeyFile {
  std::optional<CommandKey> key;
  std::string problem;             // why there is no key: names the file and what is wrong
  bool permission_denied = false;  // the caller may not read it (not in group furuta)
};
KeyFile read_command_key(const std::filesystem::path& path);

// Writes a new random key at `path` if there is none: mode 0640, group `group` when that group
// exists and this process may give the file to it. An existing file is left as it is.
struct KeyCreation {
  bool created = false;
  std::string problem;  // empty: the key is there (old or new)
};
KeyCreation ensure_command_key(const std::filesystem::path& path, const std::string& group);

// The tag over sender, time, nonce and the command's bytes (all of the message but the tag).
CommandTag command_tag(const CommandKey& key, const furuta::rig_signed_command_t& message);

furuta::rig_signed_command_t sign_command(const furuta::rig_command_t& command,
                                          const CommandKey& key, const std::string& sender,
                                          std::int64_t signed_wall_ns, std::int64_t nonce);

// Signed now (the system's UTC clock) with a random nonce, as `sender`.
furuta::rig_signed_command_t sign_command_now(const furuta::rig_command_t& command,
                                              const CommandKey& key, const std::string& sender);

// "user@host" of this process, for the sender field.
std::string this_sender();

struct Verdict {
  bool accepted = false;
  std::string reason;             // why not, for RIG_STATUS
  furuta::rig_command_t command;  // when accepted
};

struct VerifierSettings {
  // A signed command is taken within this much of the daemon's wall clock, either way, and only
  // once: the tags taken within the window are remembered.
  std::chrono::nanoseconds window{std::chrono::seconds(30)};
  std::size_t max_remembered = 65536;  // about 6 MB at most; beyond it, refused until room
};

class CommandVerifier {
 public:
  // Without a key every signed command is refused with `key_problem`. Commands signed before
  // `started_wall_ns` are refused too: a restarted verifier no longer knows which it took.
  CommandVerifier(std::optional<CommandKey> key, std::string key_problem, VerifierSettings settings,
                  std::int64_t started_wall_ns);

  Verdict verify(const furuta::rig_signed_command_t& message, std::int64_t now_wall_ns);
  bool has_key() const { return key_.has_value(); }

 private:
  void forget_before(std::int64_t wall_ns);

  std::optional<CommandKey> key_;
  std::string key_problem_;
  VerifierSettings settings_;
  std::int64_t started_wall_ns_;
  std::deque<std::pair<std::int64_t, CommandTag>> taken_;  // by signing time, as taken
  std::set<CommandTag> taken_tags_;
};

}  // namespace furuta::command_auth
