// The daemon's answers: signed with its key, checked with the public half, bounded in size
// (docs/security.md).
#include "furuta/command_auth/status_signature.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "temp_dir.hpp"

namespace furuta::command_auth {
namespace {

namespace fs = std::filesystem;
using furuta::testing::TempDir;

CommandKey seed_of(std::uint8_t fill) {
  CommandKey key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(fill * 7 + i);
  return key;
}

furuta::rig_status_t refusal() {
  furuta::rig_status_t s{};
  s.state = furuta::rig_status_t::STATE_RUNNING;
  s.session = "2026-11-28T12-00-00Z_run1";
  s.reply_to_request_id = 1234;
  s.request_accepted = false;
  s.request_reason = "refused: the command key was revoked; no session started";
  s.cycles = 500;
  return s;
}

TEST(StatusSignature, ASignedStatusChecksOutAndAnyChangeOrAnotherKeyDoesNot) {
  const StatusSigner daemon(seed_of(1));
  furuta::rig_status_t status = refusal();
  EXPECT_EQ(check_status(status, daemon.public_key()), StatusAuthenticity::unsigned_status);
  daemon.sign(status);
  EXPECT_EQ(check_status(status, daemon.public_key()), StatusAuthenticity::signed_by_daemon);

  furuta::rig_status_t changed = status;
  changed.request_accepted = true;
  EXPECT_EQ(check_status(changed, daemon.public_key()), StatusAuthenticity::wrongly_signed);
  changed = status;
  changed.reply_to_request_id += 1;
  EXPECT_EQ(check_status(changed, daemon.public_key()), StatusAuthenticity::wrongly_signed);
  changed = status;
  changed.signature[0] ^= 1;
  EXPECT_EQ(check_status(changed, daemon.public_key()), StatusAuthenticity::wrongly_signed);

  // A forger with a key of their own.
  furuta::rig_status_t forged = refusal();
  StatusSigner(seed_of(2)).sign(forged);
  EXPECT_EQ(check_status(forged, daemon.public_key()), StatusAuthenticity::wrongly_signed);
  EXPECT_EQ(daemon_public_key(seed_of(1)), daemon.public_key());
  EXPECT_NE(daemon_public_key(seed_of(2)), daemon.public_key());
}

// However long the texts a status would quote, it encodes within the stated maximum, and what it
// says is printable.
TEST(StatusSignature, EveryStatusFitsTheStatedMaximum) {
  furuta::rig_status_t status = refusal();
  const std::string huge(1'000'000, '\x1b');
  for (std::string* field :
       {&status.session, &status.request_reason, &status.last_fault, &status.last_fault_session,
        &status.last_session, &status.last_session_end, &status.refused_reason,
        &status.logs_problem, &status.unauthenticated_reason}) {
    *field = huge;
  }
  bound_status_text(status);
  StatusSigner(seed_of(1)).sign(status);
  EXPECT_LE(static_cast<std::size_t>(status.getEncodedSize()), kMaxStatusBytes);
  EXPECT_EQ(status.request_reason.find('\x1b'), std::string::npos);
  EXPECT_EQ(status.request_reason.substr(0, 8), "\\x1b\\x1b");
  // Ordinary texts are left as they are.
  furuta::rig_status_t plain = refusal();
  bound_status_text(plain);
  EXPECT_EQ(plain.request_reason, refusal().request_reason);
  EXPECT_EQ(plain.session, refusal().session);
}

TEST(StatusSignature, ThePublicKeyFileReadsBackAndIsRefusedWhenOthersMayChangeIt) {
  TempDir dir;
  const fs::path path = dir.path() / "daemon.pub";
  const DaemonPublicKey key = daemon_public_key(seed_of(3));
  ASSERT_EQ(write_daemon_public_key(path, key), "");
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0644u);
  const PublicKeyFile read = read_daemon_public_key(path);
  ASSERT_TRUE(read.key) << read.problem;
  EXPECT_EQ(*read.key, key);
  // Written again with the same key: unchanged; with another: replaced.
  ASSERT_EQ(write_daemon_public_key(path, key), "");
  ASSERT_EQ(write_daemon_public_key(path, daemon_public_key(seed_of(4))), "");
  EXPECT_EQ(read_daemon_public_key(path).key, daemon_public_key(seed_of(4)));

  ASSERT_EQ(::chmod(path.c_str(), 0666), 0);
  const PublicKeyFile writable = read_daemon_public_key(path);
  EXPECT_FALSE(writable.key);
  EXPECT_NE(writable.problem.find("may be changed by users other than its owner"),
            std::string::npos)
      << writable.problem;
  ASSERT_EQ(::chmod(path.c_str(), 0644), 0);
  std::ofstream(path) << "not a key\n";
  const PublicKeyFile bad = read_daemon_public_key(path);
  EXPECT_FALSE(bad.key);
  EXPECT_NE(bad.problem.find(path.string() + ": line 1: expected 64 hexadecimal digits"),
            std::string::npos)
      << bad.problem;
  const PublicKeyFile missing = read_daemon_public_key(dir.path() / "none.pub");
  EXPECT_NE(missing.problem.find("No such file"), std::string::npos) << missing.problem;
}

}  // namespace
}  // namespace furuta::command_auth
