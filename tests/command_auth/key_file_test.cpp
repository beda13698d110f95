// The rig's key files: their format, who may read them, and how a missing one is made
// (docs/security.md).
#include "furuta/command_auth/key_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/xattr.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "temp_dir.hpp"

namespace furuta::command_auth {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

void write_file(const fs::path& path, const std::string& text, mode_t mode) {
  std::ofstream(path) << text;
  ASSERT_EQ(::chmod(path.c_str(), mode), 0);
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A directory with exactly `mode` (mkdir's is cut by the umask).
void make_dir(const fs::path& path, mode_t mode) {
  ASSERT_EQ(::mkdir(path.c_str(), 0700), 0) << path << ": " << std::strerror(errno);
  ASSERT_EQ(::chmod(path.c_str(), mode), 0) << path << ": " << std::strerror(errno);
}

const std::string kGoodKey = std::string(64, 'a') + "\n";
constexpr uid_t kNobody = 65534;
constexpr gid_t kNogroup = 65534;

// One POSIX ACL entry: its tag, its permissions (r 4, w 2, x 1) and the user or group it names.
struct AclEntry {
  std::uint16_t tag;
  std::uint16_t perm;
  std::uint32_t id = 0xffffffff;  // ACL_UNDEFINED_ID: for every entry but named users and groups
};
constexpr std::uint16_t kUserObj = 0x01, kUser = 0x02, kGroupObj = 0x04, kGroup = 0x08,
                        kMask = 0x10, kOther = 0x20;

// An ACL as the kernel stores it in system.posix_acl_access or system.posix_acl_default: a
// version, then the entries in the kernel's order (by tag, then id), little-endian.
std::string acl_blob(const std::vector<AclEntry>& entries) {
  std::string blob;
  const auto put = [&blob](std::uint32_t value, int bytes) {
    for (int i = 0; i < bytes; ++i) blob += static_cast<char>((value >> (8 * i)) & 0xff);
  };
  put(0x0002, 4);
  for (const AclEntry& e : entries) {
    put(e.tag, 2);
    put(e.perm, 2);
    put(e.id, 4);
  }
  return blob;
}

// Sets the access ACL of `path` by writing its extended attribute; 0, or the errno.
int set_acl(const fs::path& path, const std::vector<AclEntry>& entries) {
  const std::string blob = acl_blob(entries);
  return ::setxattr(path.c_str(), "system.posix_acl_access", blob.data(), blob.size(), 0) == 0
             ? 0
             : errno;
}

bool acls_unsupported(int error) {
  return error == ENOTSUP || error == EOPNOTSUPP;
}

bool root() {
  return ::geteuid() == 0;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CommandKeyFile, ACreatedKeyHasMode0640AndReadsBackAndIsNeverReplaced) {
  TempDir dir;
  const fs::path path = dir.path() / "command.key";
  const KeyCreation made = ensure_command_key(path, "");
  ASSERT_EQ(made.problem, "");
  EXPECT_TRUE(made.created);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  EXPECT_EQ(fs::file_size(path), 65u);  // 64 hex digits and a newline
  const KeyFile first = read_command_key(path);
  ASSERT_TRUE(first.key) << first.problem;
  // A second call keeps it; a second key elsewhere differs (random).
  const KeyCreation again = ensure_command_key(path, "");
  EXPECT_FALSE(again.created);
  EXPECT_EQ(again.problem, "");
  EXPECT_EQ(read_command_key(path).key, first.key);
  ASSERT_EQ(ensure_command_key(dir.path() / "other.key", "").problem, "");
  EXPECT_NE(read_command_key(dir.path() / "other.key").key, first.key);
  // No temporary file is left behind.
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++entries;
  EXPECT_EQ(entries, 2);
}

TEST(CommandKeyFile, BadKeyFilesSayWhatIsWrongAndWhere) {
  TempDir dir;
  const fs::path path = dir.path() / "command.key";
  const std::string good(64, 'a');
  struct Case {
    std::string text;
    mode_t mode;
    std::string expected;
  };
  for (const Case& c : std::vector<Case>{
           {"abc\n", 0640, "line 1: expected 64 hexadecimal digits (a 32-byte key), found 3"},
           {good.substr(0, 10) + "g" + good.substr(11) + "\n", 0640, "column 11: 'g' is not"},
           {good + "\n" + good + "\n", 0640, "found more lines"},
           {good + "\n", 0644, "mode 0644: every user can read it"},
       }) {
    SCOPED_TRACE(c.text);
    write_file(path, c.text, c.mode);
    const KeyFile key = read_command_key(path);
    EXPECT_FALSE(key.key);
    EXPECT_NE(key.problem.find(path.string()), std::string::npos) << key.problem;
    EXPECT_NE(key.problem.find(c.expected), std::string::npos) << key.problem;
  }
  write_file(path, good + "\r\n", 0600);
  const KeyFile ok = read_command_key(path);
  ASSERT_TRUE(ok.key) << ok.problem;
  EXPECT_EQ((*ok.key)[0], 0xaa);
  const KeyFile missing = read_command_key(dir.path() / "none.key");
  EXPECT_FALSE(missing.key);
  EXPECT_FALSE(missing.permission_denied);
  EXPECT_NE(missing.problem.find("No such file"), std::string::npos) << missing.problem;
}

TEST(CommandKeyFile, AnAclEntryForAnotherUserOrGroupIsRefusedWhateverTheMask) {
  if (!root()) GTEST_SKIP() << "needs root: a 0640 key must belong to group root here";
  TempDir dir;
  const fs::path path = dir.path() / "command.key";
  write_file(path, kGoodKey, 0640);
  const int error =
      set_acl(path, {{kUserObj, 6}, {kUser, 4, kNobody}, {kGroupObj, 4}, {kMask, 4}, {kOther, 0}});
  if (acls_unsupported(error))
    GTEST_SKIP() << "the file system refuses ACLs: " << std::strerror(error);
  ASSERT_EQ(error, 0) << std::strerror(error);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  ASSERT_EQ(st.st_mode & 07777, 0640u);  // the mode alone looks right
  KeyFile key = read_command_key(path);
  EXPECT_FALSE(key.key);
  EXPECT_TRUE(contains(key.problem, path.string())) << key.problem;
  EXPECT_TRUE(contains(key.problem, "ACL entry user:65534:r-- lets another user read it"))
      << key.problem;
  EXPECT_TRUE(contains(key.problem, "setfacl -b")) << key.problem;

  // A mask that withholds the entry's read does not make it acceptable.
  ASSERT_EQ(
      set_acl(path, {{kUserObj, 6}, {kUser, 4, kNobody}, {kGroupObj, 0}, {kMask, 0}, {kOther, 0}}),
      0);
  key = read_command_key(path);
  EXPECT_FALSE(key.key);
  EXPECT_TRUE(contains(key.problem, "ACL entry user:65534:r--")) << key.problem;

  // A named group, read and write.
  ASSERT_EQ(
      set_acl(path,
              {{kUserObj, 6}, {kGroupObj, 4}, {kGroup, 6, kNogroup}, {kMask, 6}, {kOther, 0}}),
      0);
  key = read_command_key(path);
  EXPECT_FALSE(key.key);
  EXPECT_TRUE(contains(key.problem, "ACL entry group:65534:rw- lets another group read it"))
      << key.problem;

  // Named entries for root and group root are fine.
  ASSERT_EQ(
      set_acl(
          path,
          {{kUserObj, 6}, {kUser, 6, 0}, {kGroupObj, 4}, {kGroup, 4, 0}, {kMask, 6}, {kOther, 0}}),
      0);
  ASSERT_GT(::getxattr(path.c_str(), "system.posix_acl_access", nullptr, 0), 4);
  key = read_command_key(path);
  EXPECT_TRUE(key.key) << key.problem;

  // Only the base entries: fine.
  ASSERT_EQ(set_acl(path, {{kUserObj, 6}, {kGroupObj, 4}, {kOther, 0}}), 0);
  key = read_command_key(path);
  EXPECT_TRUE(key.key) << key.problem;
}

TEST(CommandKeyFile, AKeyOwnedByAnotherUserIsRefused) {
  if (!root()) GTEST_SKIP() << "needs root to give a file to user nobody";
  TempDir dir;
  const fs::path path = dir.path() / "command.key";
  write_file(path, kGoodKey, 0640);
  ASSERT_EQ(::chown(path.c_str(), kNobody, 0), 0) << std::strerror(errno);
  const KeyFile key = read_command_key(path);
  EXPECT_FALSE(key.key);
  EXPECT_TRUE(contains(key.problem, path.string())) << key.problem;
  EXPECT_TRUE(contains(key.problem, "is owned by user")) << key.problem;
  EXPECT_TRUE(contains(key.problem, "65534")) << key.problem;
  EXPECT_TRUE(contains(key.problem, "chown root")) << key.problem;
  // ensure_command_key neither keeps it nor replaces it.
  const KeyCreation made = ensure_command_key(path, "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, "is owned by user")) << made.problem;
  EXPECT_TRUE(contains(made.problem, "left as it is")) << made.problem;
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_uid, kNobody);
}

TEST(CommandKeyFile, AKeyReadableByAGroupOtherThanRootOrFurutaIsRefused) {
  if (!root()) GTEST_SKIP() << "needs root to give a file to group nogroup";
  TempDir dir;
  const fs::path path = dir.path() / "command.key";
  write_file(path, kGoodKey, 0640);
  ASSERT_EQ(::chown(path.c_str(), 0, kNogroup), 0) << std::strerror(errno);
  KeyFile key = read_command_key(path);
  EXPECT_FALSE(key.key);
  EXPECT_TRUE(contains(key.problem, "mode 0640 and group")) << key.problem;
  EXPECT_TRUE(contains(key.problem, "its members can read it")) << key.problem;
  // Without group bits the group does not matter.
  ASSERT_EQ(::chmod(path.c_str(), 0600), 0);
  key = read_command_key(path);
  EXPECT_TRUE(key.key) << key.problem;
}

TEST(CommandKeyFile, AKeyDirectoryOtherUsersCanWriteIsRefusedAndNothingIsWrittenOrKept) {
  TempDir dir;
  const fs::path open = dir.path() / "open";
  make_dir(open, 0777);
  const fs::path path = open / "command.key";
  const KeyCreation made = ensure_command_key(path, "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, "the key directory " + open.string())) << made.problem;
  EXPECT_TRUE(contains(made.problem, "every user can create, remove or rename files in it"))
      << made.problem;
  EXPECT_TRUE(contains(made.problem, "chmod o-w")) << made.problem;
  EXPECT_TRUE(fs::is_empty(open));
  EXPECT_EQ(key_directory_problem(path), made.problem);

  // A key another user planted there is not kept, though the file itself reads well.
  const std::string planted = std::string(64, 'b') + "\n";
  write_file(path, planted, 0640);
  ASSERT_TRUE(read_command_key(path).key);
  const KeyCreation again = ensure_command_key(path, "");
  EXPECT_FALSE(again.created);
  EXPECT_TRUE(contains(again.problem, open.string())) << again.problem;
  EXPECT_EQ(read_text(path), planted);

  // A world-writable directory further up, without the sticky bit, is refused too.
  make_dir(open / "sub", 0755);
  const std::string deeper = key_directory_problem(open / "sub" / "command.key");
  EXPECT_TRUE(contains(deeper, "the directory " + open.string() + " (on the way to")) << deeper;
  EXPECT_TRUE(contains(deeper, "every user")) << deeper;
}

TEST(CommandKeyFile, AKeyDirectoryAGroupCanWriteIsRefusedUnlessTheGroupIsRoot) {
  TempDir dir;
  const fs::path shared = dir.path() / "shared";
  make_dir(shared, 0770);
  if (!root()) GTEST_SKIP() << "needs root to give a directory to group root or nogroup";
  // Group root may write: fine.
  EXPECT_EQ(key_directory_problem(shared / "command.key"), "");
  ASSERT_EQ(::chown(shared.c_str(), 0, kNogroup), 0) << std::strerror(errno);
  const fs::path path = shared / "command.key";
  KeyCreation made = ensure_command_key(path, "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, "the key directory " + shared.string())) << made.problem;
  EXPECT_TRUE(contains(made.problem, "group")) << made.problem;
  EXPECT_TRUE(contains(made.problem, "65534) can create, remove or rename files in it"))
      << made.problem;
  EXPECT_TRUE(contains(made.problem, "chmod g-w")) << made.problem;
  EXPECT_TRUE(fs::is_empty(shared));
  // A planted key: not kept.
  write_file(path, kGoodKey, 0640);
  made = ensure_command_key(path, "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, shared.string())) << made.problem;
  EXPECT_EQ(read_text(path), kGoodKey);
}

TEST(CommandKeyFile, AKeyDirectoryWithAnAclEntryGrantingWriteIsRefused) {
  TempDir dir;
  const fs::path sub = dir.path() / "acl";
  make_dir(sub, 0755);
  // Write for nobody, withheld by the mask (so the mode stays 0755): refused all the same.
  const int error =
      set_acl(sub, {{kUserObj, 7}, {kUser, 7, kNobody}, {kGroupObj, 5}, {kMask, 5}, {kOther, 5}});
  if (acls_unsupported(error))
    GTEST_SKIP() << "the file system refuses ACLs: " << std::strerror(error);
  ASSERT_EQ(error, 0) << std::strerror(error);
  const KeyCreation made = ensure_command_key(sub / "command.key", "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, sub.string())) << made.problem;
  EXPECT_TRUE(
      contains(made.problem, "ACL entry user:65534:rwx lets another user create, remove or rename"))
      << made.problem;
  EXPECT_TRUE(contains(made.problem, "setfacl -b")) << made.problem;
  EXPECT_TRUE(fs::is_empty(sub));
  // Read-only entries for others are fine in a directory.
  ASSERT_EQ(
      set_acl(sub, {{kUserObj, 7}, {kUser, 5, kNobody}, {kGroupObj, 5}, {kMask, 5}, {kOther, 5}}),
      0);
  EXPECT_EQ(key_directory_problem(sub / "command.key"), "");
}

TEST(CommandKeyFile, ANewKeyThatWouldInheritAnAclEntryForAnotherUserIsNotMade) {
  if (!root()) GTEST_SKIP() << "needs root: a 0640 key must belong to group root here";
  TempDir dir;
  const fs::path sub = dir.path() / "inherits";
  make_dir(sub, 0755);
  const std::string blob =
      acl_blob({{kUserObj, 6}, {kUser, 4, kNobody}, {kGroupObj, 4}, {kMask, 4}, {kOther, 0}});
  if (::setxattr(sub.c_str(), "system.posix_acl_default", blob.data(), blob.size(), 0) != 0) {
    const int error = errno;
    if (acls_unsupported(error))
      GTEST_SKIP() << "the file system refuses ACLs: " << std::strerror(error);
    FAIL() << std::strerror(error);
  }
  EXPECT_EQ(key_directory_problem(sub / "command.key"), "");  // nobody may not write there
  const KeyCreation made = ensure_command_key(sub / "command.key", "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, "the new key would be refused")) << made.problem;
  EXPECT_TRUE(contains(made.problem, "ACL entry user:65534:r--")) << made.problem;
  EXPECT_TRUE(fs::is_empty(sub));
}

TEST(CommandKeyFile, AStickyWorldWritableDirectoryIsAcceptedAboveTheKeyButNotAsItsDirectory) {
  TempDir dir;
  const fs::path sticky = dir.path() / "sticky";
  make_dir(sticky, 01777);
  make_dir(sticky / "sub", 0755);
  EXPECT_EQ(key_directory_problem(sticky / "sub" / "command.key"), "");
  const KeyCreation below = ensure_command_key(sticky / "sub" / "command.key", "");
  EXPECT_EQ(below.problem, "");
  EXPECT_TRUE(below.created);

  const KeyCreation in = ensure_command_key(sticky / "command.key", "");
  EXPECT_FALSE(in.created);
  EXPECT_TRUE(contains(in.problem, "the key directory " + sticky.string())) << in.problem;
  EXPECT_TRUE(contains(in.problem, "mode 1777: every user")) << in.problem;
  EXPECT_TRUE(contains(in.problem, "the sticky bit is not enough")) << in.problem;
  EXPECT_FALSE(fs::exists(fs::symlink_status(sticky / "command.key")));
}

TEST(CommandKeyFile, SymbolicLinksOnTheWayAreFollowedAndEveryDirectoryOnTheirWayIsChecked) {
  TempDir dir;
  make_dir(dir.path() / "real", 0755);
  make_dir(dir.path() / "open", 0777);
  fs::create_symlink("real", dir.path() / "alias");
  fs::create_symlink(dir.path() / "open", dir.path() / "to-open");
  EXPECT_EQ(key_directory_problem(dir.path() / "alias" / "command.key"), "");
  EXPECT_EQ(key_directory_problem(dir.path() / "open" / ".." / "real" / "command.key"), "");
  const std::string via = key_directory_problem(dir.path() / "to-open" / "command.key");
  EXPECT_TRUE(contains(via, "the key directory " + (dir.path() / "open").string())) << via;
  const std::string missing = key_directory_problem(dir.path() / "none" / "command.key");
  EXPECT_TRUE(contains(missing, "No such file")) << missing;
  if (!root()) return;
  // A link another user owns may have been planted.
  ASSERT_EQ(::lchown((dir.path() / "alias").c_str(), kNobody, kNogroup), 0);
  const std::string planted = key_directory_problem(dir.path() / "alias" / "command.key");
  EXPECT_TRUE(contains(planted, "the symbolic link " + (dir.path() / "alias").string())) << planted;
  EXPECT_TRUE(contains(planted, "is owned by user")) << planted;
}

TEST(CommandKeyFile, ASymbolicLinkAtTheKeyPathIsRefusedAndLeftAlone) {
  TempDir dir;
  const fs::path path = dir.path() / "command.key";
  fs::create_symlink(dir.path() / "nowhere", path);  // dangling
  const KeyCreation made = ensure_command_key(path, "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, path.string() + " is a symbolic link: refused (remove it"))
      << made.problem;
  EXPECT_TRUE(fs::is_symlink(path));
  EXPECT_FALSE(fs::exists(dir.path() / "nowhere"));
  const KeyFile key = read_command_key(path);
  EXPECT_FALSE(key.key);
  EXPECT_TRUE(contains(key.problem, path.string())) << key.problem;
  EXPECT_TRUE(contains(key.problem, "is a symbolic link")) << key.problem;

  // A link to a good key is refused too.
  write_file(dir.path() / "nowhere", kGoodKey, 0640);
  EXPECT_TRUE(contains(ensure_command_key(path, "").problem, "is a symbolic link")) << path;
  EXPECT_FALSE(read_command_key(path).key);
}

TEST(CommandKeyFile, AnExistingKeyThatIsRefusedIsNeitherKeptNorReplaced) {
  TempDir dir;
  const fs::path path = dir.path() / "command.key";
  write_file(path, kGoodKey, 0644);
  KeyCreation made = ensure_command_key(path, "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, path.string())) << made.problem;
  EXPECT_TRUE(contains(made.problem, "mode 0644: every user can read it")) << made.problem;
  EXPECT_TRUE(contains(made.problem, "left as it is")) << made.problem;
  EXPECT_EQ(read_text(path), kGoodKey);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0644u);

  // Not a key at all: the same.
  write_file(path, "not a key\n", 0640);
  made = ensure_command_key(path, "");
  EXPECT_FALSE(made.created);
  EXPECT_TRUE(contains(made.problem, "line 1:")) << made.problem;
  EXPECT_EQ(read_text(path), "not a key\n");
}

TEST(CommandKeyFile, TheNewKeysOwnerAndModeCanBeChosen) {
  TempDir dir;
  const fs::path path = dir.path() / "seed";
  const KeyCreation made = ensure_command_key(path, "", "", 0600);
  ASSERT_EQ(made.problem, "");
  EXPECT_TRUE(made.created);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  EXPECT_EQ(st.st_uid, ::geteuid());
  const KeyFile key = read_command_key(path);
  EXPECT_TRUE(key.key) << key.problem;
  // A mode that lets others in is not made.
  const KeyCreation loose = ensure_command_key(dir.path() / "loose", "", "", 0644);
  EXPECT_FALSE(loose.created);
  EXPECT_TRUE(contains(loose.problem, "mode 0644")) << loose.problem;
  EXPECT_FALSE(fs::exists(dir.path() / "loose"));

  if (!root()) return;
  // As root, for another user (the service user, here nobody): made theirs, and kept when asked
  // for again with the same owner.
  const fs::path theirs = dir.path() / "theirs";
  const KeyCreation given = ensure_command_key(theirs, "", "nobody", 0600);
  ASSERT_EQ(given.problem, "");
  EXPECT_TRUE(given.created);
  ASSERT_EQ(::stat(theirs.c_str(), &st), 0);
  EXPECT_EQ(st.st_uid, kNobody);
  EXPECT_EQ(st.st_gid, 0u);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  const std::string before = read_text(theirs);
  const KeyCreation again = ensure_command_key(theirs, "", "nobody", 0600);
  EXPECT_EQ(again.problem, "");
  EXPECT_FALSE(again.created);
  EXPECT_EQ(read_text(theirs), before);
  EXPECT_TRUE(read_command_key(theirs, "nobody").key);
  // Without naming that owner, root's reader refuses a key another user owns.
  EXPECT_TRUE(contains(read_command_key(theirs).problem, "is owned by user"));
  EXPECT_TRUE(contains(ensure_command_key(theirs, "").problem, "is owned by user"));
}

}  // namespace
}  // namespace furuta::command_auth
