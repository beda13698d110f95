#pragma once
// Who may move the motor: commands that do carry an HMAC-SHA256 tag under the rig's command key,
// a secret in a file that only root and group `furuta` can read (docs/security.md). The signer
// (`furuta start`) and the verifier (furutad) share these few functions.

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <set>
#include <string>

#include "furuta/command_auth/key_file.hpp"
#include "furuta/rig_command_t.hpp"
#include "furuta/rig_signed_command_t.hpp"

namespace furuta::command_auth {

using CommandTag = std::array<std::uint8_t, 32>;

// Stopping is always safe and a status request changes nothing: only these need a tag.
bool moves_motor(const furuta::rig_command_t& command);

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

// Why a signed command was refused; each is counted apart in the daemon's status.
enum class Refusal {
  none,
  unsigned_command,  // a command that moves the motor sent without a tag (the daemon's check)
  no_key,            // the verifier has no command key
  malformed,         // a sender or command over its size limit, or signed bytes that are no command
  bad_signature,     // the tag does not check out
  out_of_time,       // signed too long ago, too far ahead, or below the replay floor
  replayed,          // taken already
  memory_full,       // more signatures within the window than the memory holds
  not_recorded,      // the replay floor could not be written to disk
};

struct Verdict {
  bool accepted = false;
  Refusal refusal = Refusal::none;
  std::string reason;             // why not, for RIG_STATUS: bounded, stranger's bytes escaped
  furuta::rig_command_t command;  // when accepted
};

struct VerifierSettings {
  // A signed command is taken if signed at most `window` before the daemon's wall clock and at
  // most `max_ahead` after it, and only once.
  std::chrono::nanoseconds window{std::chrono::seconds(30)};
  std::chrono::nanoseconds max_ahead{std::chrono::seconds(2)};
  std::size_t max_remembered = 65536;  // signatures within the window; beyond it, refused
  // Refused as malformed before any other work: a sender or command longer than this.
  std::size_t max_sender_bytes = 128;
  std::size_t max_command_bytes = 1024;
  // Where the replay floor survives a restart (the latest signing time taken, written before the
  // command is acted on). Empty: kept in memory only (a verifier that lives as long as its user).
  std::filesystem::path state_file;
};

// Checks signed commands: the tag, then the time, then that it was not taken before. Not
// thread-safe: one caller at a time.
//
// Replays are refused by a floor that never moves down: a command signed before the floor is
// refused whatever the clocks say. The floor starts at the verifier's start (and above every
// signing time taken by an earlier verifier with the same state file, or `max_ahead` past the
// start when that file is unreadable or damaged) and rises with the monotonic clock, staying
// `window` behind it, so stepping the wall clock forward or back never lets a signature in twice.
// Signatures at or above the floor are remembered; those below it are forgotten, since the floor
// refuses them anyway.
class CommandVerifier {
 public:
  // Without a key every signed command is refused with `key_problem`.
  CommandVerifier(std::optional<CommandKey> key, std::string key_problem, VerifierSettings settings,
                  std::int64_t now_wall_ns, std::int64_t now_monotonic_ns);

  // A command that moves the motor is taken at most once; one that does not (stop, e-stop,
  // status) only needs a good tag and is not remembered, so it uses up nothing a start needs.
  Verdict verify(const furuta::rig_signed_command_t& message, std::int64_t now_wall_ns,
                 std::int64_t now_monotonic_ns);
  bool has_key() const { return key_.has_value(); }
  // What the state file said at start ("" when all was well): for furutad to print.
  const std::string& state_problem() const { return state_problem_; }
  // Commands signed before this wall time are refused.
  std::int64_t floor_wall_ns(std::int64_t now_monotonic_ns) const;

 private:
  std::string record_taken(std::int64_t signed_wall_ns);

  std::optional<CommandKey> key_;
  std::string key_problem_;
  VerifierSettings settings_;
  std::int64_t start_floor_wall_ns_ = 0;
  std::int64_t started_wall_ns_ = 0;
  std::int64_t started_monotonic_ns_ = 0;
  std::int64_t highest_taken_ns_;  // as written to the state file
  std::string state_problem_;
  std::set<std::pair<std::int64_t, CommandTag>> taken_;  // by signing time
  std::set<CommandTag> taken_tags_;
};

// The replay state file: "furuta command replay state v1\nhighest_signed_wall_ns N\n". Missing:
// nullopt with no problem; unreadable or damaged: nullopt and the problem, naming file and line.
struct ReplayState {
  std::optional<std::int64_t> highest_signed_wall_ns;
  std::string problem;
};
ReplayState read_replay_state(const std::filesystem::path& path);
// Written beside it, synced and renamed into place (a crash leaves the old or the new whole). ""
// or why not.
std::string write_replay_state(const std::filesystem::path& path,
                               std::int64_t highest_signed_wall_ns);

}  // namespace furuta::command_auth
