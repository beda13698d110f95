// Signing and checking the commands that move the motor: the key file, the tag, the time window
// and the replay memory (docs/security.md).
#include "furuta/command_auth/command_auth.hpp"

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

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kNow = 1'800'000'000 * kSecond;  // 2027-01-15, a wall clock in ns

CommandKey key_of(std::uint8_t fill) {
  CommandKey key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(fill + i);
  return key;
}

furuta::rig_command_t start_command(double amplitude = 0.3) {
  furuta::rig_command_t c{};
  c.request_id = 42;
  c.kind = furuta::rig_command_t::KIND_START_SESSION;
  c.profile = "bang_bang";
  c.amplitude_duty = amplitude;
  c.duration_s = 10;
  c.label = "signed";
  c.seed = 1;
  return c;
}

CommandVerifier verifier(std::optional<CommandKey> key = key_of(1)) {
  return CommandVerifier(key, "no key here", VerifierSettings{}, kNow - 60 * kSecond);
}

void write_file(const fs::path& path, const std::string& text, mode_t mode) {
  std::ofstream(path) << text;
  ASSERT_EQ(::chmod(path.c_str(), mode), 0);
}

TEST(CommandAuth, OnlyCommandsThatMoveTheMotorNeedATag) {
  furuta::rig_command_t c{};
  c.kind = furuta::rig_command_t::KIND_START_SESSION;
  EXPECT_TRUE(moves_motor(c));
  for (auto kind : {furuta::rig_command_t::KIND_STOP, furuta::rig_command_t::KIND_ESTOP,
                    furuta::rig_command_t::KIND_STATUS_REQUEST}) {
    c.kind = kind;
    EXPECT_FALSE(moves_motor(c)) << int(kind);
  }
  c.kind = 99;  // unknown: treated as moving
  EXPECT_TRUE(moves_motor(c));
}

TEST(CommandAuth, ASignedCommandIsTakenOnceWithinTheWindow) {
  CommandVerifier v = verifier();
  const auto signed_start = sign_command(start_command(), key_of(1), "ana@rig", kNow, 7);
  const Verdict first = v.verify(signed_start, kNow + 2 * kSecond);
  ASSERT_TRUE(first.accepted) << first.reason;
  EXPECT_EQ(first.command.amplitude_duty, 0.3);
  EXPECT_EQ(first.command.request_id, 42);
  EXPECT_EQ(first.command.label, "signed");
  // The same bytes again: a replay.
  const Verdict again = v.verify(signed_start, kNow + 3 * kSecond);
  EXPECT_FALSE(again.accepted);
  EXPECT_NE(again.reason.find("replayed"), std::string::npos) << again.reason;
  // Signed anew (another nonce), the same command is a new one.
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "ana@rig", kNow, 8), kNow).accepted);
}

TEST(CommandAuth, AWrongKeyATamperedFieldOrSenderIsABadSignature) {
  CommandVerifier v = verifier();
  const Verdict wrong_key =
      v.verify(sign_command(start_command(), key_of(2), "eve@lab", kNow, 1), kNow);
  EXPECT_FALSE(wrong_key.accepted);
  EXPECT_NE(wrong_key.reason.find("bad signature from \"eve@lab\""), std::string::npos)
      << wrong_key.reason;

  // The amplitude raised on the way, the tag kept.
  auto tampered = sign_command(start_command(0.1), key_of(1), "ana@rig", kNow, 2);
  const auto louder = sign_command(start_command(0.6), key_of(1), "ana@rig", kNow, 2);
  tampered.command = louder.command;
  EXPECT_FALSE(v.verify(tampered, kNow).accepted);

  auto other_sender = sign_command(start_command(), key_of(1), "ana@rig", kNow, 3);
  other_sender.sender = "bob@rig";
  EXPECT_FALSE(v.verify(other_sender, kNow).accepted);
  auto other_time = sign_command(start_command(), key_of(1), "ana@rig", kNow, 4);
  other_time.signed_wall_ns += kSecond;
  EXPECT_FALSE(v.verify(other_time, kNow).accepted);
  auto one_bit = sign_command(start_command(), key_of(1), "ana@rig", kNow, 5);
  one_bit.tag[31] ^= 1;
  EXPECT_FALSE(v.verify(one_bit, kNow).accepted);
  // None of them used up the genuine one.
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "ana@rig", kNow, 5), kNow).accepted);
}

TEST(CommandAuth, OutsideTheWindowOrBeforeTheVerifierStartedIsRefused) {
  CommandVerifier v = verifier();
  const Verdict old =
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow - 31 * kSecond, 1), kNow);
  EXPECT_FALSE(old.accepted);
  EXPECT_NE(old.reason.find("ago"), std::string::npos) << old.reason;
  const Verdict ahead =
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow + 31 * kSecond, 1), kNow);
  EXPECT_FALSE(ahead.accepted);
  EXPECT_NE(ahead.reason.find("ahead"), std::string::npos) << ahead.reason;
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow - 29 * kSecond, 1), kNow)
          .accepted);

  // A daemon restarted 10 s ago has forgotten what it took before: older signatures are refused
  // even within the window.
  CommandVerifier restarted(key_of(1), "", VerifierSettings{}, kNow - 10 * kSecond);
  const Verdict before = restarted.verify(
      sign_command(start_command(), key_of(1), "a@b", kNow - 20 * kSecond, 1), kNow);
  EXPECT_FALSE(before.accepted);
  EXPECT_NE(before.reason.find("before this daemon started"), std::string::npos) << before.reason;
}

TEST(CommandAuth, TheReplayMemoryIsBoundedAndForgetsOnlyWhatTheWindowRefuses) {
  VerifierSettings settings;
  settings.max_remembered = 3;
  CommandVerifier v(key_of(1), "", settings, 0);
  for (int n = 0; n < 3; ++n) {
    EXPECT_TRUE(v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, n), kNow).accepted);
  }
  const Verdict full = v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, 3), kNow);
  EXPECT_FALSE(full.accepted);
  EXPECT_NE(full.reason.find("more than 3"), std::string::npos) << full.reason;
  // Once the window has passed them they are forgotten, and room is made.
  const std::int64_t later = kNow + 40 * kSecond;
  EXPECT_TRUE(v.verify(sign_command(start_command(), key_of(1), "a@b", later, 3), later).accepted);
  // ...and the old ones are still refused, by the window now.
  EXPECT_FALSE(v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, 0), later).accepted);
}

TEST(CommandAuth, WithoutAKeyEverySignedCommandIsRefusedWithWhy) {
  CommandVerifier v = verifier(std::nullopt);
  const Verdict verdict = v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, 1), kNow);
  EXPECT_FALSE(verdict.accepted);
  EXPECT_NE(verdict.reason.find("no key here"), std::string::npos) << verdict.reason;
}

TEST(CommandAuth, SignedBytesThatAreNoCommandAreRefused) {
  CommandVerifier v = verifier();
  auto m = sign_command(start_command(), key_of(1), "a@b", kNow, 1);
  m.command.resize(10);
  m.command_size = 10;
  const CommandTag tag = command_tag(key_of(1), m);
  std::copy(tag.begin(), tag.end(), m.tag);
  const Verdict verdict = v.verify(m, kNow);
  EXPECT_FALSE(verdict.accepted);
  EXPECT_NE(verdict.reason.find("not one rig_command_t"), std::string::npos) << verdict.reason;
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

TEST(CommandAuth, TheSenderIsUserAtHost) {
  const std::string sender = this_sender();
  EXPECT_NE(sender.find('@'), std::string::npos) << sender;
  EXPECT_GT(sender.find('@'), 0u);
}

}  // namespace
}  // namespace furuta::command_auth
