// Signing and checking the commands that move the motor: the key file, the tag, the time window
// and the replay memory (docs/security.md).
#include "furuta/command_auth/command_auth.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <limits>
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
  return CommandVerifier(key, "no key here", VerifierSettings{}, kNow - 60 * kSecond,
                         kNow - 60 * kSecond);
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
  const Verdict first = v.verify(signed_start, kNow + 2 * kSecond, kNow + 2 * kSecond);
  ASSERT_TRUE(first.accepted) << first.reason;
  EXPECT_EQ(first.command.amplitude_duty, 0.3);
  EXPECT_EQ(first.command.request_id, 42);
  EXPECT_EQ(first.command.label, "signed");
  // The same bytes again: a replay.
  const Verdict again = v.verify(signed_start, kNow + 3 * kSecond, kNow + 3 * kSecond);
  EXPECT_FALSE(again.accepted);
  EXPECT_NE(again.reason.find("replayed"), std::string::npos) << again.reason;
  // Signed anew (another nonce), the same command is a new one.
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "ana@rig", kNow, 8), kNow, kNow).accepted);
}

TEST(CommandAuth, AWrongKeyATamperedFieldOrSenderIsABadSignature) {
  CommandVerifier v = verifier();
  const Verdict wrong_key =
      v.verify(sign_command(start_command(), key_of(2), "eve@lab", kNow, 1), kNow, kNow);
  EXPECT_FALSE(wrong_key.accepted);
  EXPECT_NE(wrong_key.reason.find("bad signature from \"eve@lab\""), std::string::npos)
      << wrong_key.reason;

  // The amplitude raised on the way, the tag kept.
  auto tampered = sign_command(start_command(0.1), key_of(1), "ana@rig", kNow, 2);
  const auto louder = sign_command(start_command(0.6), key_of(1), "ana@rig", kNow, 2);
  tampered.command = louder.command;
  EXPECT_FALSE(v.verify(tampered, kNow, kNow).accepted);

  auto other_sender = sign_command(start_command(), key_of(1), "ana@rig", kNow, 3);
  other_sender.sender = "bob@rig";
  EXPECT_FALSE(v.verify(other_sender, kNow, kNow).accepted);
  auto other_time = sign_command(start_command(), key_of(1), "ana@rig", kNow, 4);
  other_time.signed_wall_ns += kSecond;
  EXPECT_FALSE(v.verify(other_time, kNow, kNow).accepted);
  auto one_bit = sign_command(start_command(), key_of(1), "ana@rig", kNow, 5);
  one_bit.tag[31] ^= 1;
  EXPECT_FALSE(v.verify(one_bit, kNow, kNow).accepted);
  // None of them used up the genuine one.
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "ana@rig", kNow, 5), kNow, kNow).accepted);
}

TEST(CommandAuth, OutsideTheWindowOrBeforeTheVerifierStartedIsRefused) {
  CommandVerifier v = verifier();
  const Verdict old =
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow - 31 * kSecond, 1), kNow, kNow);
  EXPECT_FALSE(old.accepted);
  EXPECT_NE(old.reason.find("ago"), std::string::npos) << old.reason;
  const Verdict ahead =
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow + 31 * kSecond, 1), kNow, kNow);
  EXPECT_FALSE(ahead.accepted);
  EXPECT_NE(ahead.reason.find("ahead"), std::string::npos) << ahead.reason;
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow - 29 * kSecond, 1), kNow, kNow)
          .accepted);

  // A daemon restarted 10 s ago has forgotten what it took before: older signatures are refused
  // even within the window.
  CommandVerifier restarted(key_of(1), "", VerifierSettings{}, kNow - 10 * kSecond,
                            kNow - 10 * kSecond);
  const Verdict before = restarted.verify(
      sign_command(start_command(), key_of(1), "a@b", kNow - 20 * kSecond, 1), kNow, kNow);
  EXPECT_FALSE(before.accepted);
  EXPECT_NE(before.reason.find("before the replay floor"), std::string::npos) << before.reason;
  EXPECT_EQ(before.refusal, Refusal::out_of_time);
}

TEST(CommandAuth, TheReplayMemoryIsBoundedAndForgetsOnlyWhatTheWindowRefuses) {
  VerifierSettings settings;
  settings.max_remembered = 3;
  CommandVerifier v(key_of(1), "", settings, 0, 0);
  for (int n = 0; n < 3; ++n) {
    EXPECT_TRUE(
        v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, n), kNow, kNow).accepted);
  }
  const Verdict full =
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, 3), kNow, kNow);
  EXPECT_FALSE(full.accepted);
  EXPECT_NE(full.reason.find("more than 3"), std::string::npos) << full.reason;
  // Once the window has passed them they are forgotten, and room is made.
  const std::int64_t later = kNow + 40 * kSecond;
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "a@b", later, 3), later, later).accepted);
  // ...and the old ones are still refused, by the window now.
  EXPECT_FALSE(
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, 0), later, later).accepted);
}

TEST(CommandAuth, WithoutAKeyEverySignedCommandIsRefusedWithWhy) {
  CommandVerifier v = verifier(std::nullopt);
  const Verdict verdict =
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, 1), kNow, kNow);
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
  const Verdict verdict = v.verify(m, kNow, kNow);
  EXPECT_FALSE(verdict.accepted);
  EXPECT_NE(verdict.reason.find("not one rig_command_t"), std::string::npos) << verdict.reason;
}

// Ahead-dated signatures: a clock a little fast is fine; one far ahead would let a captured
// command outlive the daemon that took it.
TEST(CommandAuth, ASignatureDatedAheadBeyondTheSkewIsRefused) {
  CommandVerifier v = verifier();
  const Verdict far =
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow + 20 * kSecond, 1), kNow, kNow);
  EXPECT_FALSE(far.accepted);
  EXPECT_EQ(far.refusal, Refusal::out_of_time);
  EXPECT_NE(far.reason.find("20 s ahead of the daemon's clock, more than the 2 s allowed"),
            std::string::npos)
      << far.reason;
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow + kSecond, 2), kNow, kNow)
          .accepted);
}

// A start taken, the daemon restarted, the same bytes again: refused, whether the state file
// says what was taken or is damaged (then the floor is the skew past the start).
TEST(CommandAuth, AStartTakenBeforeARestartIsRefusedAfterIt) {
  TempDir dir;
  VerifierSettings settings;
  settings.state_file = dir.path() / "replay.state";
  const auto ahead = sign_command(start_command(), key_of(1), "a@b", kNow + 1500'000'000, 1);
  {
    CommandVerifier before(key_of(1), "", settings, kNow - kSecond, 0);
    ASSERT_TRUE(before.verify(ahead, kNow, kSecond).accepted);
    EXPECT_EQ(before.state_problem(), "");
  }
  const ReplayState state = read_replay_state(settings.state_file);
  ASSERT_TRUE(state.highest_signed_wall_ns) << state.problem;
  EXPECT_EQ(*state.highest_signed_wall_ns, kNow + 1500'000'000);

  // Restarted half a second later, on a new monotonic clock.
  CommandVerifier after(key_of(1), "", settings, kNow + 500'000'000, 7);
  const Verdict replay = after.verify(ahead, kNow + 600'000'000, 7 + 100'000'000);
  EXPECT_FALSE(replay.accepted);
  EXPECT_EQ(replay.refusal, Refusal::out_of_time);
  EXPECT_NE(replay.reason.find("replay floor"), std::string::npos) << replay.reason;
  // A command signed after what was taken goes through.
  EXPECT_TRUE(after
                  .verify(sign_command(start_command(), key_of(1), "a@b", kNow + 1600'000'000, 2),
                          kNow + 1600'000'000, 7 + kSecond)
                  .accepted);

  // Damaged: said so, with the file and line, and the floor is the skew past the start.
  std::ofstream(settings.state_file) << "furuta command replay state v1\nhighest x\n";
  CommandVerifier damaged(key_of(1), "", settings, kNow + 500'000'000, 7);
  EXPECT_NE(damaged.state_problem().find(settings.state_file.string() + ": line 2"),
            std::string::npos)
      << damaged.state_problem();
  EXPECT_FALSE(damaged.verify(ahead, kNow + 600'000'000, 7 + 100'000'000).accepted);
}

// The wall clock stepped forward (one valid command taken then) and back: the captured start is
// still refused, since the memory is kept by the monotonic clock's floor, not the wall clock's.
TEST(CommandAuth, ClockStepsForwardAndBackNeverLetASignatureInTwice) {
  CommandVerifier v(key_of(1), "", VerifierSettings{}, kNow, 0);
  const auto captured = sign_command(start_command(), key_of(1), "a@b", kNow, 1);
  ASSERT_TRUE(v.verify(captured, kNow, 0).accepted);
  const std::int64_t stepped = kNow + 61 * kSecond;
  ASSERT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "a@b", stepped, 2), stepped, kSecond)
          .accepted);
  const Verdict again = v.verify(captured, kNow + 2 * kSecond, 2 * kSecond);
  EXPECT_FALSE(again.accepted);
  EXPECT_EQ(again.refusal, Refusal::replayed) << again.reason;
  // Stepped back 100 s and the window passed on the monotonic clock: refused by the floor.
  const Verdict late = v.verify(captured, kNow + 5 * kSecond, 40 * kSecond);
  EXPECT_FALSE(late.accepted);
  EXPECT_EQ(late.refusal, Refusal::out_of_time) << late.reason;
  EXPECT_GE(v.floor_wall_ns(40 * kSecond), kNow + 10 * kSecond);
}

// Stops, e-stops and status requests need a good tag but are not remembered: a key holder's flood
// of them cannot fill the memory that starts need.
TEST(CommandAuth, SignedCommandsThatDoNotMoveTheMotorUseNoMemory) {
  VerifierSettings settings;
  settings.max_remembered = 3;
  CommandVerifier v(key_of(1), "", settings, kNow, kNow);
  furuta::rig_command_t status{};
  status.kind = furuta::rig_command_t::KIND_STATUS_REQUEST;
  for (int n = 0; n < 100; ++n) {
    const Verdict verdict =
        v.verify(sign_command(status, key_of(1), "a@b", kNow + kSecond, n), kNow, kNow);
    ASSERT_TRUE(verdict.accepted) << verdict.reason;
    EXPECT_EQ(verdict.command.kind, +furuta::rig_command_t::KIND_STATUS_REQUEST);
  }
  EXPECT_TRUE(
      v.verify(sign_command(start_command(), key_of(1), "a@b", kNow, 1), kNow, kNow).accepted);
}

// A megabyte of sender is refused by its size, never hashed or echoed; a hostile sender within
// the size is echoed bounded and escaped.
TEST(CommandAuth, AnOversizedOrHostileSenderIsNeverEchoedWhole) {
  CommandVerifier v = verifier();
  auto huge = sign_command(start_command(), key_of(2), std::string(1'000'000, 'A'), kNow, 1);
  const Verdict big = v.verify(huge, kNow, kNow);
  EXPECT_FALSE(big.accepted);
  EXPECT_EQ(big.refusal, Refusal::malformed);
  EXPECT_NE(big.reason.find("sender: 1000000 bytes, above the limit of 128"), std::string::npos)
      << big.reason.substr(0, 200);
  EXPECT_LT(big.reason.size(), 200u);

  const auto hostile = sign_command(start_command(), key_of(2), "\x1b]0;owned\a\x1b[2J", kNow, 1);
  const Verdict escaped = v.verify(hostile, kNow, kNow);
  EXPECT_EQ(escaped.refusal, Refusal::bad_signature);
  EXPECT_EQ(escaped.reason.find('\x1b'), std::string::npos) << escaped.reason;
  EXPECT_NE(escaped.reason.find("\\x1b]0;owned\\x07"), std::string::npos) << escaped.reason;
}

// Signing times at the ends of int64 format without overflow (UBSan runs this).
TEST(CommandAuth, ExtremeSigningTimesAreRefusedWithAFiniteText) {
  CommandVerifier v = verifier();
  for (std::int64_t t :
       {std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max()}) {
    const Verdict verdict =
        v.verify(sign_command(start_command(), key_of(1), "a@b", t, 1), kNow, kNow);
    EXPECT_FALSE(verdict.accepted);
    EXPECT_EQ(verdict.refusal, Refusal::out_of_time);
    EXPECT_NE(verdict.reason.find("e+"), std::string::npos) << verdict.reason;
    EXPECT_EQ(verdict.reason.find("nan"), std::string::npos) << verdict.reason;
    EXPECT_EQ(verdict.reason.find("inf"), std::string::npos) << verdict.reason;
    EXPECT_EQ(verdict.reason.find("-"), std::string::npos) << verdict.reason;
  }
}

// The floor is written before a start is taken; when it cannot be, the start is refused.
TEST(CommandAuth, AStartWhoseFloorCannotBeWrittenIsRefused) {
  TempDir dir;
  VerifierSettings settings;
  settings.state_file = dir.path() / "missing-dir" / "replay.state";
  CommandVerifier v(key_of(1), "", settings, kNow, kNow);
  const std::int64_t later = kNow + 3 * kSecond;
  const Verdict verdict =
      v.verify(sign_command(start_command(), key_of(1), "a@b", later, 1), later, later);
  EXPECT_FALSE(verdict.accepted);
  EXPECT_EQ(verdict.refusal, Refusal::not_recorded);
  EXPECT_NE(verdict.reason.find("missing-dir"), std::string::npos) << verdict.reason;
}

TEST(CommandAuth, TheSenderIsUserAtHost) {
  const std::string sender = this_sender();
  EXPECT_NE(sender.find('@'), std::string::npos) << sender;
  EXPECT_GT(sender.find('@'), 0u);
}

}  // namespace
}  // namespace furuta::command_auth
