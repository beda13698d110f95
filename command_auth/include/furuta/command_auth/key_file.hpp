#pragma once
// The rig's secret key files (the command key, the daemon's signing seed): 64 hexadecimal digits
// (32 random bytes) that only root, the process's own user and group `furuta` may read
// (docs/security.md).

#include <sys/types.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace furuta::command_auth {

inline constexpr std::size_t kKeyBytes = 32;
using CommandKey = std::array<std::uint8_t, kKeyBytes>;

// What read_command_key found: a key, or why there is none.
struct KeyFile {
  std::optional<CommandKey> key;
  std::string problem;             // why there is no key: names the file, what is wrong, the fix
  bool permission_denied = false;  // the caller may not open it (not in group furuta)
};

// Reads the key at `path`: a regular file (not a symbolic link) holding 64 hexadecimal digits on
// one line and an optional line end. It is refused, with the reason and the fix, unless nobody but
// root, this process's effective user and the groups root and `furuta` (when that group exists)
// can read or write it:
// - its owner is root or the effective user (or `owner_user`, when not empty and that user exists);
// - its group bits are clear unless its group is root or `furuta`;
// - its "other" bits are clear;
// - its POSIX access ACL has no named user entry with read or write for a user other than root or
//   the effective user, no named group entry with read or write for a group other than root or
//   `furuta`, and no read or write in the owning-group entry unless that group is root or `furuta`,
//   whatever the mask says.
// Format problems name the line and column. Only the file is checked, not its directory.
KeyFile read_command_key(const std::filesystem::path& path, const std::string& owner_user = "");

// Why the directory holding `key_path` is not a safe place for a key, or "" when it is. The path
// is followed as the kernel would (symbolic links included) and every directory a name is looked up
// in is checked, up to /, as well as the key's own directory. Safe: each is owned by root or the
// effective user, and nobody else can create, remove or rename entries in it: no group write unless
// the group is root, no write for other users, no ACL entry granting write to a user other than
// root or the effective user or to a group other than root (whatever the mask says). A directory
// above the key's own one that others may write is accepted when its sticky bit is set (as /tmp);
// the key's own directory never is. A symbolic link on the way must be owned by root or the
// effective user. A directory that does not exist or cannot be examined is a problem. The message
// names the directory, who can write to it (a group, every user, or the ACL entry) and the fix.
std::string key_directory_problem(const std::filesystem::path& key_path);

// 64 hexadecimal digits, either case, as the key they spell; nothing for any other text.
std::optional<CommandKey> key_from_hex(std::string_view text);

// What ensure_command_key did.
struct KeyCreation {
  bool created = false;  // a new key was written at the path
  std::string problem;   // empty: a key that passes the checks below is there (old or new)
};

// Makes sure a key is at `path`, making a new random one if nothing is there.
// - If key_directory_problem(path) reports a problem, that problem is returned and nothing is
//   written.
// - If something is at `path`, nothing is written: a symbolic link is refused; anything else is
//   kept (created false, no problem) only if read_command_key(path, owner_user) accepts it;
//   otherwise read_command_key's problem is returned and the file is left as it is.
// - Otherwise a new key (getrandom) is written to a temporary file beside `path` with mode `mode`,
//   owned by `owner_user` (when it is not empty, this process runs as root and that user exists;
//   otherwise by this process's user), group `group` (when it is not empty, this process runs as
//   root and that group exists), judged as an existing file would be (a problem leaves nothing
//   behind), and linked into place, so the key appears whole and never replaces a file another
//   process put there meanwhile (which is then judged as above).
// - A `mode` granting more than 0660 is a problem; nothing is written.
KeyCreation ensure_command_key(const std::filesystem::path& path, const std::string& group,
                               const std::string& owner_user = "", mode_t mode = 0640);

}  // namespace furuta::command_auth
