#include "furuta/command_auth/key_file.hpp"

#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <sys/xattr.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <deque>
#include <functional>
#include <vector>

namespace furuta::command_auth {

namespace {

namespace fs = std::filesystem;

struct FdCloser {
  int fd = -1;
  ~FdCloser() {
    if (fd >= 0) ::close(fd);
  }
};

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

// ---- users and groups ------------------------------------------------------------------------

// Calls a getpwnam_r-style function with a growing buffer; true when it found an entry.
bool lookup(const std::function<int(char*, std::size_t, bool*)>& call) {
  std::vector<char> buffer(4096);
  for (int attempt = 0; attempt < 8; ++attempt) {
    bool found = false;
    const int error = call(buffer.data(), buffer.size(), &found);
    if (error == ERANGE) {
      buffer.resize(buffer.size() * 4);
      continue;
    }
    return error == 0 && found;
  }
  return false;
}

// The "no such user" and "no such group" values (chown's "leave it as it is").
constexpr uid_t kNoUser = static_cast<uid_t>(-1);
constexpr gid_t kNoGroup = static_cast<gid_t>(-1);

// The user's id, or kNoUser.
uid_t user_id(const std::string& name) {
  if (name.empty()) return kNoUser;
  uid_t uid = kNoUser;
  const bool found = lookup([&](char* buffer, std::size_t size, bool* hit) {
    struct passwd entry {};
    struct passwd* result = nullptr;
    const int error = ::getpwnam_r(name.c_str(), &entry, buffer, size, &result);
    if (error == 0 && result != nullptr) {
      *hit = true;
      uid = result->pw_uid;
    }
    return error;
  });
  return found ? uid : kNoUser;
}

// The group's id, or kNoGroup.
gid_t group_id(const std::string& name) {
  if (name.empty()) return kNoGroup;
  gid_t gid = kNoGroup;
  const bool found = lookup([&](char* buffer, std::size_t size, bool* hit) {
    struct group entry {};
    struct group* result = nullptr;
    const int error = ::getgrnam_r(name.c_str(), &entry, buffer, size, &result);
    if (error == 0 && result != nullptr) {
      *hit = true;
      gid = result->gr_gid;
    }
    return error;
  });
  return found ? gid : kNoGroup;
}

// "user nobody (65534)", or "user 65534" when it has no name.
std::string describe_user(uid_t uid) {
  std::string name;
  lookup([&](char* buffer, std::size_t size, bool* hit) {
    struct passwd entry {};
    struct passwd* result = nullptr;
    const int error = ::getpwuid_r(uid, &entry, buffer, size, &result);
    if (error == 0 && result != nullptr) {
      *hit = true;
      name = result->pw_name;
    }
    return error;
  });
  const std::string id = std::to_string(uid);
  return name.empty() ? "user " + id : "user " + name + " (" + id + ")";
}

// "group users (100)", or "group 100" when it has no name.
std::string describe_group(gid_t gid) {
  std::string name;
  lookup([&](char* buffer, std::size_t size, bool* hit) {
    struct group entry {};
    struct group* result = nullptr;
    const int error = ::getgrgid_r(gid, &entry, buffer, size, &result);
    if (error == 0 && result != nullptr) {
      *hit = true;
      name = result->gr_name;
    }
    return error;
  });
  const std::string id = std::to_string(gid);
  return name.empty() ? "group " + id : "group " + name + " (" + id + ")";
}

// ---- POSIX access ACLs (the system.posix_acl_access extended attribute) -----------------------

constexpr const char* kAclName = "system.posix_acl_access";
constexpr std::uint32_t kAclVersion = 0x0002;
constexpr std::uint16_t kAclUserObj = 0x01;
constexpr std::uint16_t kAclUser = 0x02;
constexpr std::uint16_t kAclGroupObj = 0x04;
constexpr std::uint16_t kAclGroup = 0x08;
constexpr std::uint16_t kAclMask = 0x10;
constexpr std::uint16_t kAclOther = 0x20;
constexpr std::uint16_t kAclRead = 4;
constexpr std::uint16_t kAclWrite = 2;
constexpr std::uint16_t kAclExecute = 1;

struct AclEntry {
  std::uint16_t tag = 0;
  std::uint16_t perm = 0;
  std::uint32_t id = 0;
};

struct Acl {
  std::vector<AclEntry> entries;  // empty: no ACL beyond the mode bits
  std::string error;              // not empty: the ACL could not be read or understood
};

std::uint32_t little_endian(const unsigned char* bytes, int size) {
  std::uint32_t value = 0;
  for (int i = size - 1; i >= 0; --i) value = (value << 8) | bytes[i];
  return value;
}

// `get(buffer, size)` is fgetxattr or lgetxattr of kAclName.
Acl read_acl(const std::function<ssize_t(void*, std::size_t)>& get) {
  Acl acl;
  std::vector<unsigned char> blob;
  for (int attempt = 0;; ++attempt) {
    const ssize_t size = get(nullptr, 0);
    if (size < 0) {
      if (errno == ENODATA || errno == ENOTSUP || errno == EOPNOTSUPP) return acl;
      acl.error = std::strerror(errno);
      return acl;
    }
    blob.resize(static_cast<std::size_t>(size));
    const ssize_t n = get(blob.data(), blob.size());
    if (n >= 0) {
      blob.resize(static_cast<std::size_t>(n));
      break;
    }
    if (errno == ENODATA) return acl;  // removed meanwhile
    if (errno != ERANGE || attempt >= 4) {
      acl.error = std::strerror(errno);
      return acl;
    }
  }
  if (blob.size() < 4 || (blob.size() - 4) % 8 != 0 ||
      little_endian(blob.data(), 4) != kAclVersion) {
    acl.error = "an ACL of " + std::to_string(blob.size()) + " bytes in an unknown format";
    return acl;
  }
  for (std::size_t at = 4; at < blob.size(); at += 8) {
    AclEntry entry;
    entry.tag = static_cast<std::uint16_t>(little_endian(blob.data() + at, 2));
    entry.perm = static_cast<std::uint16_t>(little_endian(blob.data() + at + 2, 2));
    entry.id = little_endian(blob.data() + at + 4, 4);
    acl.entries.push_back(entry);
  }
  return acl;
}

// "user:65534:r--", as getfacl writes it.
std::string acl_entry_text(const AclEntry& entry) {
  std::string text;
  switch (entry.tag) {
    case kAclUserObj:
      text = "user::";
      break;
    case kAclUser:
      text = "user:" + std::to_string(entry.id) + ":";
      break;
    case kAclGroupObj:
      text = "group::";
      break;
    case kAclGroup:
      text = "group:" + std::to_string(entry.id) + ":";
      break;
    case kAclMask:
      text = "mask::";
      break;
    case kAclOther:
      text = "other::";
      break;
    default:
      text = "tag " + std::to_string(entry.tag) + ":" + std::to_string(entry.id) + ":";
  }
  text += (entry.perm & kAclRead) ? 'r' : '-';
  text += (entry.perm & kAclWrite) ? 'w' : '-';
  text += (entry.perm & kAclExecute) ? 'x' : '-';
  return text;
}

// Who, besides the owner, may hold access: the users and groups an ACL entry may name.
struct Trusted {
  std::vector<uid_t> users;
  std::vector<gid_t> groups;
  bool user(uid_t uid) const {
    for (uid_t u : users)
      if (u == uid) return true;
    return false;
  }
  bool group(gid_t gid) const {
    for (gid_t g : groups)
      if (g == gid) return true;
    return false;
  }
};

// The first entry granting any of `perm` to a user or group outside `trusted`, whatever the mask
// says: named users and groups, and the owning group's entry when `owning_group` is not trusted.
// Unknown tags count as foreign.
std::optional<AclEntry> foreign_acl_entry(const Acl& acl, std::uint16_t perm,
                                          const Trusted& trusted, gid_t owning_group) {
  for (const AclEntry& entry : acl.entries) {
    if ((entry.perm & perm) == 0) continue;
    switch (entry.tag) {
      case kAclUserObj:
      case kAclMask:
      case kAclOther:  // the mode's owner and other bits, checked from the mode
        break;
      case kAclUser:
        if (!trusted.user(entry.id)) return entry;
        break;
      case kAclGroup:
        if (!trusted.group(entry.id)) return entry;
        break;
      case kAclGroupObj:
        if (!trusted.group(owning_group)) return entry;
        break;
      default:
        return entry;
    }
  }
  return std::nullopt;
}

// ---- the key file ------------------------------------------------------------------------------

constexpr const char* kKeyFix = "chmod 0640, group furuta; or 0600 for a key only its owner reads";

// read_command_key, with `also_owner` (unless kNoUser) accepted as the file's owner too.
KeyFile read_key(const fs::path& path, uid_t also_owner) {
  KeyFile result;
  const std::string name = "the key file " + path.string();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    const int error = errno;
    result.permission_denied = error == EACCES || error == EPERM;
    if (error == ELOOP) {
      result.problem = name + " is a symbolic link: refused (put the key file itself there)";
    } else {
      result.problem = "cannot read " + name + ": " + std::strerror(error);
    }
    return result;
  }
  FdCloser closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    result.problem = name + " is not a regular file";
    return result;
  }
  const uid_t euid = ::geteuid();
  if (st.st_uid != 0 && st.st_uid != euid && (also_owner == kNoUser || st.st_uid != also_owner)) {
    result.problem = name + " is owned by " + describe_user(st.st_uid) +
                     ", who can read and change it, so it proves nothing (chown root " +
                     path.string() + ", or to the user that reads it; " + kKeyFix + ")";
    return result;
  }
  const std::string mode = octal_mode(st.st_mode);
  if ((st.st_mode & S_IROTH) != 0) {
    result.problem = name + " has mode " + mode +
                     ": every user can read it, so it proves nothing (" + kKeyFix + ")";
    return result;
  }
  if ((st.st_mode & S_IWOTH) != 0) {
    result.problem = name + " has mode " + mode +
                     ": every user can change it, so it proves nothing (" + kKeyFix + ")";
    return result;
  }
  Trusted trusted{{0, euid}, {0}};
  if (const gid_t furuta = group_id("furuta"); furuta != kNoGroup) trusted.groups.push_back(furuta);
  if ((st.st_mode & (S_IRGRP | S_IWGRP)) != 0 && !trusted.group(st.st_gid)) {
    result.problem = name + " has mode " + mode + " and " + describe_group(st.st_gid) +
                     ": its members can " + ((st.st_mode & S_IRGRP) ? "read" : "change") +
                     " it, so it proves nothing (chgrp furuta " + path.string() +
                     ", or chmod 0600)";
    return result;
  }
  const Acl acl = read_acl(
      [fd](void* buffer, std::size_t size) { return ::fgetxattr(fd, kAclName, buffer, size); });
  if (!acl.error.empty()) {
    result.problem = "cannot check who may read " + name + ": its ACL: " + acl.error +
                     " (setfacl -b " + path.string() + " removes it)";
    return result;
  }
  if (const std::optional<AclEntry> entry =
          foreign_acl_entry(acl, kAclRead | kAclWrite, trusted, st.st_gid)) {
    const bool user = entry->tag == kAclUser;
    result.problem = name + ": ACL entry " + acl_entry_text(*entry) + " lets " +
                     (user ? "another user" : "another group") + " " +
                     ((entry->perm & kAclRead) ? "read" : "change") +
                     " it, so it proves nothing (setfacl -b " + path.string() +
                     " removes every ACL entry; then " + kKeyFix + ")";
    return result;
  }
  char buffer[256];
  const ssize_t n = ::read(fd, buffer, sizeof buffer);
  if (n < 0) {
    result.problem = "cannot read " + name + ": " + std::strerror(errno);
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

// ---- the key's directory -----------------------------------------------------------------------

// Why other users could create, remove or rename entries in directory `dir`, or "". `own`: the
// key's own directory (where a sticky bit is no excuse).
std::string directory_problem(const std::string& dir, bool own, const std::string& key_dir) {
  const std::string name = own ? "the key directory " + dir
                               : "the directory " + dir + " (on the way to " + key_dir + ")";
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) return "cannot examine " + name + ": " + std::strerror(errno);
  const uid_t euid = ::geteuid();
  if (st.st_uid != 0 && st.st_uid != euid) {
    return name + " is owned by " + describe_user(st.st_uid) +
           ", who can replace a key in it (chown root " + dir + ", or keep the key elsewhere)";
  }
  const bool sticky_excuses = !own && (st.st_mode & S_ISVTX) != 0;
  if (sticky_excuses) return "";
  const std::string mode = octal_mode(st.st_mode);
  const std::string what = " create, remove or rename files in it";
  const std::string sticky_note =
      (st.st_mode & S_ISVTX) != 0
          ? "; the sticky bit is not enough for the key's own directory: keep the key in a "
            "directory only root can write, such as /etc/furuta"
          : "";
  if ((st.st_mode & S_IWOTH) != 0) {
    return name + " has mode " + mode + ": every user can" + what + " (chmod o-w " + dir +
           sticky_note + ")";
  }
  if ((st.st_mode & S_IWGRP) != 0 && st.st_gid != 0) {
    return name + " has mode " + mode + ": " + describe_group(st.st_gid) + " can" + what +
           " (chmod g-w " + dir + ", or chgrp root " + dir + sticky_note + ")";
  }
  const Acl acl = read_acl([&dir](void* buffer, std::size_t size) {
    return ::lgetxattr(dir.c_str(), kAclName, buffer, size);
  });
  if (!acl.error.empty()) {
    return "cannot check who may write to " + name + ": its ACL: " + acl.error + " (setfacl -b " +
           dir + " removes it)";
  }
  const Trusted trusted{{0, euid}, {0}};
  if (const std::optional<AclEntry> entry = foreign_acl_entry(acl, kAclWrite, trusted, st.st_gid)) {
    return name + ": ACL entry " + acl_entry_text(*entry) + " lets " +
           (entry->tag == kAclUser ? "another user" : "another group") + what + " (setfacl -b " +
           dir + " removes every ACL entry" + sticky_note + ")";
  }
  return "";
}

std::string join(const std::string& dir, const std::string& name) {
  return dir == "/" ? "/" + name : dir + "/" + name;
}

std::string parent_of(const std::string& dir) {
  const std::size_t slash = dir.rfind('/');
  return slash == 0 || slash == std::string::npos ? "/" : dir.substr(0, slash);
}

// The existing file at `path`: kept when it is a key read_key accepts, else why not.
KeyCreation judge_existing(const fs::path& path, uid_t also_owner) {
  KeyCreation result;
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    result.problem = "cannot look at " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  if (S_ISLNK(st.st_mode)) {
    result.problem = path.string() +
                     " is a symbolic link: refused (remove it, and run this again to make a new "
                     "key there; a key is a regular file, never a link)";
    return result;
  }
  const KeyFile existing = read_key(path, also_owner);
  if (!existing.key) {
    result.problem = existing.problem +
                     "; it is left as it is (fix it, or remove it and run this again to make a "
                     "new key)";
  }
  return result;
}

}  // namespace

std::optional<CommandKey> key_from_hex(std::string_view text) {
  CommandKey key{};
  if (text.size() != 2 * key.size()) return std::nullopt;
  for (std::size_t i = 0; i < key.size(); ++i) {
    const int high = hex_digit(text[2 * i]);
    const int low = hex_digit(text[2 * i + 1]);
    if (high < 0 || low < 0) return std::nullopt;
    key[i] = static_cast<std::uint8_t>(high * 16 + low);
  }
  return key;
}

KeyFile read_command_key(const std::filesystem::path& path, const std::string& owner_user) {
  return read_key(path, user_id(owner_user));
}

std::string key_directory_problem(const std::filesystem::path& key_path) {
  fs::path dir = key_path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code error;
  const fs::path absolute = fs::absolute(dir, error);
  if (error) return "cannot find the directory of " + key_path.string() + ": " + error.message();

  // Walk the path as the kernel does, one name at a time, following symbolic links, and note
  // every directory a name is looked up in (".." needs no note: nobody can replace it).
  std::deque<std::string> pending;
  for (const fs::path& part : absolute.relative_path()) pending.push_back(part.string());
  std::string current = "/";
  std::vector<std::string> visited;
  int links = 0;
  while (!pending.empty()) {
    const std::string part = pending.front();
    pending.pop_front();
    if (part.empty() || part == ".") continue;
    if (part == "..") {
      current = parent_of(current);
      continue;
    }
    if (visited.empty() || visited.back() != current) visited.push_back(current);
    const std::string next = join(current, part);
    struct stat st {};
    if (::lstat(next.c_str(), &st) != 0) {
      return "cannot examine the directory " + next + " (for the key " + key_path.string() +
             "): " + std::strerror(errno);
    }
    if (S_ISLNK(st.st_mode)) {
      if (st.st_uid != 0 && st.st_uid != ::geteuid()) {
        return "the symbolic link " + next + " (on the way to the key " + key_path.string() +
               ") is owned by " + describe_user(st.st_uid) +
               ", who may have planted it (remove it, or name the real directory)";
      }
      if (++links > 40) {
        return "cannot examine the directory of " + key_path.string() + ": " + std::strerror(ELOOP);
      }
      std::vector<char> target(static_cast<std::size_t>(st.st_size > 0 ? st.st_size : 255) + 1);
      const ssize_t n = ::readlink(next.c_str(), target.data(), target.size());
      if (n < 0 || static_cast<std::size_t>(n) >= target.size()) {
        return "cannot read the symbolic link " + next + ": " +
               std::strerror(n < 0 ? errno : ENAMETOOLONG);
      }
      const fs::path to(std::string(target.data(), static_cast<std::size_t>(n)));
      if (to.is_absolute()) current = "/";
      std::vector<std::string> parts;
      for (const fs::path& p : to.relative_path()) parts.push_back(p.string());
      pending.insert(pending.begin(), parts.begin(), parts.end());
      continue;
    }
    if (!S_ISDIR(st.st_mode)) {
      return "cannot use " + next + " as a directory for the key " + key_path.string() +
             ": not a directory";
    }
    current = next;
  }
  for (const std::string& d : visited) {
    if (d == current) continue;
    if (std::string why = directory_problem(d, false, current); !why.empty()) return why;
  }
  return directory_problem(current, true, current);
}

KeyCreation ensure_command_key(const std::filesystem::path& path, const std::string& group,
                               const std::string& owner_user, mode_t mode) {
  KeyCreation result;
  if ((mode & ~static_cast<mode_t>(0660)) != 0) {
    result.problem = "will not create the key " + path.string() + " with mode " + octal_mode(mode) +
                     ": a key is 0640 or stricter (0660 at most)";
    return result;
  }
  if (std::string why = key_directory_problem(path); !why.empty()) {
    result.problem = why;
    return result;
  }
  const uid_t owner = user_id(owner_user);
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0) return judge_existing(path, owner);
  if (errno != ENOENT) {
    result.problem = "cannot look at " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  CommandKey key{};
  if (::getrandom(key.data(), key.size(), 0) != static_cast<ssize_t>(key.size())) {
    result.problem = std::string("no random bytes for a key: ") + std::strerror(errno);
    return result;
  }
  std::string text;
  static constexpr char kHex[] = "0123456789abcdef";
  for (std::uint8_t b : key) {
    text += kHex[b >> 4];
    text += kHex[b & 15];
  }
  text += '\n';
  // Written beside it and linked into place, so the key appears whole or not at all, and a file
  // another process put there meanwhile is never replaced (link refuses to).
  std::string temp = path.string() + ".newXXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) {
    result.problem = "cannot create the key " + path.string() + ": " + std::strerror(errno);
    return result;
  }
  bool linked = false;
  bool there_already = false;
  {
    FdCloser closer{fd};
    std::string why;
    if (::fchmod(fd, mode) != 0) why = std::string("chmod: ") + std::strerror(errno);
    if (why.empty() && ::geteuid() == 0) {
      const gid_t gid = group_id(group);
      if ((owner != kNoUser || gid != kNoGroup) && ::fchown(fd, owner, gid) != 0) {
        why = "chown " + (owner != kNoUser ? owner_user : std::string()) +
              (gid != kNoGroup ? ":" + group : "") + ": " + std::strerror(errno);
      }
    }
    if (why.empty() && ::write(fd, text.data(), text.size()) != static_cast<ssize_t>(text.size())) {
      why = std::string("write: ") + std::strerror(errno);
    }
    if (why.empty() && ::fsync(fd) != 0) why = std::string("fsync: ") + std::strerror(errno);
    // Judged as an existing key would be (a default ACL of the directory, say, is inherited).
    if (why.empty()) {
      if (const KeyFile check = read_key(temp, owner); !check.key) {
        why = "the new key would be refused: " + check.problem;
      }
    }
    if (why.empty()) {
      if (::link(temp.c_str(), path.c_str()) == 0) {
        linked = true;
      } else if (errno == EEXIST) {
        there_already = true;
      } else {
        why = std::string("link: ") + std::strerror(errno);
      }
    }
    if (!why.empty()) result.problem = "cannot create the key " + path.string() + ": " + why;
  }
  ::unlink(temp.c_str());
  if (there_already) return judge_existing(path, owner);
  result.created = linked;
  return result;
}

}  // namespace furuta::command_auth
