#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>

#include "furuta/daemon/excitation.hpp"
#include "furuta/daemon/safety.hpp"

namespace furuta::daemon::command_validator_test {
namespace {

using furuta::rig_command_t;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kStart = 1'000 * kSecond;  // an arbitrary monotonic clock reading

// lcm-gen leaves the numeric fields uninitialised: every test command starts from this one.
rig_command_t command_of(std::int8_t kind) {
  rig_command_t command;
  command.request_id = 1;
  command.kind = kind;
  command.profile = "bang_bang";
  command.amplitude_duty = 0.3;
  command.duration_s = 10.0;
  command.label = "run-1";
  command.seed = 1;
  return command;
}

rig_command_t start() {
  return command_of(rig_command_t::KIND_START_SESSION);
}

// A validator with plenty of tokens, so field tests never meet the rate limit.
CommandValidator unlimited() {
  CommandLimits limits;
  limits.max_commands_per_s = 1'000'000;
  return CommandValidator(limits);
}

CommandDecision check_once(const rig_command_t& command) {
  return unlimited().validate(command, kStart);
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CommandValidator, KnownKindsAreAcceptedWithoutAReason) {
  for (int kind : {+rig_command_t::KIND_START_SESSION, +rig_command_t::KIND_STOP,
                   +rig_command_t::KIND_ESTOP, +rig_command_t::KIND_STATUS_REQUEST}) {
    const auto decision = check_once(command_of(static_cast<std::int8_t>(kind)));
    EXPECT_TRUE(decision.accepted) << kind << ": " << decision.reason;
    EXPECT_EQ(decision.reason, "");
  }
}

TEST(CommandValidator, UnknownKindsAreRejected) {
  for (int kind : {0, 5, 7, -1, 127, -128}) {
    const auto decision = check_once(command_of(static_cast<std::int8_t>(kind)));
    EXPECT_FALSE(decision.accepted);
    EXPECT_EQ(decision.reason, "kind: " + std::to_string(kind) + " is not a known command");
  }
}

TEST(CommandValidator, StopAndStatusIgnoreTheSessionFields) {
  for (int kind : {+rig_command_t::KIND_STOP, +rig_command_t::KIND_STATUS_REQUEST,
                   +rig_command_t::KIND_ESTOP}) {
    rig_command_t command = command_of(static_cast<std::int8_t>(kind));
    command.profile = "nonsense";
    command.amplitude_duty = kNan;
    command.duration_s = -1.0;
    command.label = "../../etc/passwd";
    command.seed = -5;
    EXPECT_TRUE(check_once(command).accepted) << kind;
  }
}

// --- rate limiting ---

TEST(CommandValidator, TheBucketStartsFullAndRefillsAtTheConfiguredRate) {
  CommandValidator validator{CommandLimits{}};  // 5 per second
  const auto request = start();                 // 5 starts per second
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(validator.validate(request, kStart).accepted) << i;
  const auto refused = validator.validate(request, kStart);
  EXPECT_FALSE(refused.accepted);
  EXPECT_EQ(refused.reason, "rate limit: more than 5 starts per second");
  // One token every 200 ms.
  EXPECT_FALSE(validator.validate(request, kStart + 199'999'999).accepted);
  EXPECT_TRUE(validator.validate(request, kStart + 200'000'000).accepted);
  EXPECT_FALSE(validator.validate(request, kStart + 200'000'001).accepted);
  // A long quiet spell refills to the burst size, not beyond.
  const std::int64_t later = kStart + 3600 * kSecond;
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(validator.validate(request, later).accepted) << i;
  EXPECT_FALSE(validator.validate(request, later).accepted);
}

TEST(CommandValidator, ASteadyStreamGetsTheConfiguredRate) {
  CommandValidator validator{CommandLimits{}};
  const auto status = start();
  int accepted = 0;
  for (std::int64_t t = 0; t <= 10 * kSecond; t += 100'000'000) {  // 10 per second for 10 s
    accepted += validator.validate(status, kStart + t).accepted ? 1 : 0;
  }
  EXPECT_EQ(accepted, 5 + 10 * 5);  // the burst, then the refill rate
  int steady = 0;
  CommandValidator at_rate{CommandLimits{}};
  for (std::int64_t t = 0; t < 100 * kSecond; t += 200'000'000) {  // exactly 5 per second
    steady += at_rate.validate(status, kStart + t).accepted ? 1 : 0;
  }
  EXPECT_EQ(steady, 500);
}

TEST(CommandValidator, StatusRequestsHaveTheirOwnBucketAndCannotLockOutAStop) {
  CommandValidator validator{CommandLimits{}};
  const auto status = command_of(rig_command_t::KIND_STATUS_REQUEST);
  const auto stop = command_of(rig_command_t::KIND_STOP);
  int accepted = 0;
  for (int i = 0; i < 30; ++i) accepted += validator.validate(status, kStart).accepted ? 1 : 0;
  EXPECT_EQ(accepted, 20);  // the status bucket's burst
  const CommandDecision refused = validator.validate(status, kStart);
  EXPECT_EQ(refused.reason, "rate limit: more than 20 status requests per second");
  EXPECT_TRUE(validator.validate(stop, kStart).accepted);  // untouched by the polling
}

TEST(CommandValidator, EstopIsNeverRateLimitedAndSpendsNoToken) {
  CommandValidator validator{CommandLimits{}};
  const auto estop = command_of(rig_command_t::KIND_ESTOP);
  const auto request = start();
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(validator.validate(estop, kStart).accepted) << i;
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(validator.validate(request, kStart).accepted) << i;
  EXPECT_FALSE(validator.validate(request, kStart).accepted);
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(validator.validate(estop, kStart).accepted) << i;

  CommandLimits none;
  none.max_commands_per_s = 0;
  CommandValidator closed(none);
  EXPECT_TRUE(closed.validate(estop, kStart).accepted);
  EXPECT_FALSE(closed.validate(request, kStart).accepted);
  EXPECT_EQ(closed.validate(request, kStart + 100 * kSecond).reason,
            "rate limit: more than 0 starts per second");
}

TEST(CommandValidator, RejectedCommandsSpendTokensToo) {
  // A flood of garbage must not keep the daemon busy: it is throttled like anything else.
  CommandValidator validator{CommandLimits{}};
  rig_command_t bad = start();
  bad.amplitude_duty = 5.0;
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(validator.validate(bad, kStart).accepted);
  for (int i = 0; i < 2; ++i) EXPECT_FALSE(validator.validate(command_of(9), kStart).accepted);
  const auto decision = validator.validate(start(), kStart);
  EXPECT_FALSE(decision.accepted);
  EXPECT_EQ(decision.reason, "rate limit: more than 5 starts per second");
  EXPECT_EQ(decision.refusal, CommandRefusal::start_budget);
  // Stops have a budget of their own, untouched by the starts.
  EXPECT_TRUE(validator.validate(command_of(rig_command_t::KIND_STOP), kStart).accepted);
}

TEST(CommandValidator, AClockThatJumpsAroundNeitherRefillsNorOverflows) {
  CommandValidator validator{CommandLimits{}};
  const auto request = start();
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(validator.validate(request, kStart).accepted);
  EXPECT_FALSE(validator.validate(request, kStart - 10 * kSecond).accepted);  // backwards: nothing
  EXPECT_FALSE(validator.validate(request, std::numeric_limits<std::int64_t>::min()).accepted);
  // Forward again from the newest reading, across the whole range without overflow.
  for (int i = 0; i < 5; ++i) {
    EXPECT_TRUE(validator.validate(request, std::numeric_limits<std::int64_t>::max()).accepted)
        << i;
  }
  EXPECT_FALSE(validator.validate(request, std::numeric_limits<std::int64_t>::max()).accepted);

  CommandValidator from_negative{CommandLimits{}};  // the first reading may be anything
  EXPECT_TRUE(from_negative.validate(request, std::numeric_limits<std::int64_t>::min()).accepted);
}

// --- START_SESSION fields ---

TEST(CommandValidator, EveryKnownProfileIsAccepted) {
  for (const char* name : {"bang_bang", "free_decay", "step", "prbs", "chirp", "multisine"}) {
    rig_command_t command = start();
    command.profile = name;
    EXPECT_TRUE(check_once(command).accepted) << name;
  }
}

TEST(CommandValidator, AnUnknownProfileIsRejectedListingTheKnownOnes) {
  for (const std::string& name :
       {std::string(), std::string("sine"), std::string("BANG_BANG"), std::string("bang_bang "),
        std::string("bang-bang"), std::string("prbs\0", 5)}) {
    rig_command_t command = start();
    command.profile = name;
    const auto decision = check_once(command);
    EXPECT_FALSE(decision.accepted) << name;
    EXPECT_EQ(decision.reason.rfind("profile: ", 0), 0U) << decision.reason;
    EXPECT_TRUE(contains(decision.reason,
                         "is not one of bang_bang, free_decay, step, prbs, chirp, multisine"))
        << decision.reason;
  }
  rig_command_t command = start();
  command.profile = "sine";
  EXPECT_EQ(check_once(command).reason,
            "profile: \"sine\" is not one of bang_bang, free_decay, step, prbs, chirp, multisine, "
            "balance");
}

TEST(CommandValidator, EchoedStringsAreEscapedAndBounded) {
  rig_command_t command = start();
  command.profile = std::string("x\n\x01\x7f\"\\", 6) + std::string(500, 'y');
  const auto reason = check_once(command).reason;
  EXPECT_TRUE(contains(reason, "\"x\\x0a\\x01\\x7f\\x22\\x5cyyy")) << reason;
  EXPECT_TRUE(contains(reason, "...\"")) << reason;
  EXPECT_LT(reason.size(), 200U);
  for (char c : reason) EXPECT_TRUE(c >= 0x20 && c < 0x7f) << static_cast<int>(c);
}

TEST(CommandValidator, AmplitudeMustBeFiniteAboveZeroAndWithinTheLimit) {
  for (double amplitude : {0.5, 1e-9, 0.3}) {
    rig_command_t command = start();
    command.amplitude_duty = amplitude;
    EXPECT_TRUE(check_once(command).accepted) << amplitude;
  }
  const std::pair<double, std::string> rejected[] = {
      {0.0, "amplitude_duty: 0 is not above 0"},
      {-0.0, "amplitude_duty: -0 is not above 0"},
      {-0.1, "amplitude_duty: -0.1 is not above 0"},
      {0.9, "amplitude_duty: 0.9 above the limit 0.5"},
      {std::nextafter(0.5, 1.0), "amplitude_duty: 0.5000000000000001 above the limit 0.5"},
      {1e308, "amplitude_duty: 1e+308 above the limit 0.5"},
      {kNan, "amplitude_duty: nan is not a finite number"},
      {kInf, "amplitude_duty: inf is not a finite number"},
      {-kInf, "amplitude_duty: -inf is not a finite number"},
  };
  for (const auto& [amplitude, reason] : rejected) {
    rig_command_t command = start();
    command.amplitude_duty = amplitude;
    const auto decision = check_once(command);
    EXPECT_FALSE(decision.accepted) << amplitude;
    EXPECT_EQ(decision.reason, reason);
  }
}

TEST(CommandValidator, AmplitudeNeverPassesFullDutyWhateverTheConfiguredLimit) {
  CommandLimits limits;
  limits.max_amplitude_duty = 2.0;
  CommandValidator validator(limits);
  rig_command_t command = start();
  command.amplitude_duty = 1.0;
  EXPECT_TRUE(validator.validate(command, kStart).accepted);
  command.amplitude_duty = 1.5;
  EXPECT_EQ(validator.validate(command, kStart).reason, "amplitude_duty: 1.5 above the limit 1");
}

TEST(CommandValidator, DurationMustBeFiniteAboveZeroAndWithinTheLimit) {
  for (double duration : {600.0, 0.016, 1e-6}) {
    rig_command_t command = start();
    command.duration_s = duration;
    EXPECT_TRUE(check_once(command).accepted) << duration;
  }
  const std::pair<double, std::string> rejected[] = {
      {0.0, "duration_s: 0 is not above 0"},
      {-10.0, "duration_s: -10 is not above 0"},
      {700.0, "duration_s: 700 above the limit 600"},
      {std::nextafter(600.0, 1e9), "duration_s: 600.0000000000001 above the limit 600"},
      {1e300, "duration_s: 1e+300 above the limit 600"},
      {kNan, "duration_s: nan is not a finite number"},
      {kInf, "duration_s: inf is not a finite number"},
  };
  for (const auto& [duration, reason] : rejected) {
    rig_command_t command = start();
    command.duration_s = duration;
    const auto decision = check_once(command);
    EXPECT_FALSE(decision.accepted) << duration;
    EXPECT_EQ(decision.reason, reason);
  }
}

TEST(CommandValidator, LabelIsBoundedAndSafeInAFileName) {
  for (const std::string& label : {std::string(), std::string("run-1_a.b c"), std::string(64, 'x'),
                                   std::string("ABCxyz0123456789")}) {
    rig_command_t command = start();
    command.label = label;
    EXPECT_TRUE(check_once(command).accepted) << label;
  }
  rig_command_t command = start();
  command.label = std::string(65, 'x');
  EXPECT_EQ(check_once(command).reason, "label: 65 characters, above the limit 64");
  command.label = std::string(100000, 'x');
  EXPECT_EQ(check_once(command).reason, "label: 100000 characters, above the limit 64");

  for (const std::string& label :
       {std::string("a/b"), std::string("../etc"), std::string("line\nbreak"), std::string("tab\t"),
        std::string("nul\0x", 5), std::string("del\x7f"), std::string("caf\xc3\xa9"),
        std::string("star*"), std::string("semi;colon"), std::string("back\\slash"),
        std::string("quote\"")}) {
    command.label = label;
    const auto decision = check_once(command);
    EXPECT_FALSE(decision.accepted) << label;
    EXPECT_EQ(decision.reason.rfind("label: ", 0), 0U) << decision.reason;
    EXPECT_TRUE(contains(decision.reason, "file name")) << decision.reason;
  }
  command.label = "a/b";
  EXPECT_EQ(check_once(command).reason,
            "label: \"a/b\" has 0x2f at position 1; only letters, digits, '-', '_', '.' and ' ' "
            "are allowed (the label becomes part of a file name)");

  CommandLimits short_labels;
  short_labels.max_label_chars = 3;
  short_labels.max_commands_per_s = 100;
  CommandValidator validator(short_labels);
  command.label = "abc";
  EXPECT_TRUE(validator.validate(command, kStart).accepted);
  command.label = "abcd";
  EXPECT_EQ(validator.validate(command, kStart).reason, "label: 4 characters, above the limit 3");
}

TEST(CommandValidator, SeedMustNotBeNegative) {
  rig_command_t command = start();
  for (std::int64_t seed :
       {std::int64_t{0}, std::int64_t{1}, std::numeric_limits<std::int64_t>::max()}) {
    command.seed = seed;
    EXPECT_TRUE(check_once(command).accepted) << seed;
  }
  command.seed = -1;
  EXPECT_EQ(check_once(command).reason, "seed: -1 is negative; it must be >= 0");
  command.seed = std::numeric_limits<std::int64_t>::min();
  EXPECT_EQ(check_once(command).reason, "seed: -9223372036854775808 is negative; it must be >= 0");
}

TEST(CommandValidator, TheFirstBadFieldIsReportedInOrder) {
  rig_command_t command = start();
  command.profile = "sine";
  command.amplitude_duty = kNan;
  command.duration_s = -1.0;
  command.label = "/";
  command.seed = -1;
  EXPECT_EQ(check_once(command).reason.rfind("profile: ", 0), 0U);
  command.profile = "step";
  EXPECT_EQ(check_once(command).reason.rfind("amplitude_duty: ", 0), 0U);
  command.amplitude_duty = 0.2;
  EXPECT_EQ(check_once(command).reason.rfind("duration_s: ", 0), 0U);
  command.duration_s = 5.0;
  EXPECT_EQ(check_once(command).reason.rfind("label: ", 0), 0U);
  command.label = "ok";
  EXPECT_EQ(check_once(command).reason.rfind("seed: ", 0), 0U);
  command.seed = 0;
  EXPECT_TRUE(check_once(command).accepted);
}

// --- from an accepted command to the session's excitation ---

TEST(SpecFromCommand, CopiesTheCommandsFieldsOverTheDefaults) {
  ExcitationSpec defaults;
  defaults.kind = ProfileKind::bang_bang;
  defaults.switch_period_s = 0.7;
  defaults.switch_period_jitter = 0.2;
  defaults.arm_switch_rad = 1.1;
  defaults.prbs_order = 11;
  defaults.multisine_components = 5;
  rig_command_t command = start();
  command.profile = "prbs";
  command.amplitude_duty = 0.25;
  command.duration_s = 42.0;
  command.seed = std::numeric_limits<std::int64_t>::max();
  const ExcitationSpec spec = spec_from_command(command, defaults);
  EXPECT_EQ(spec.kind, ProfileKind::prbs);
  EXPECT_EQ(spec.amplitude_duty, 0.25);
  EXPECT_EQ(spec.duration_s, 42.0);
  EXPECT_EQ(spec.seed, 9223372036854775807ULL);
  EXPECT_EQ(spec.switch_period_s, 0.7);
  EXPECT_EQ(spec.switch_period_jitter, 0.2);
  EXPECT_EQ(spec.arm_switch_rad, 1.1);
  EXPECT_EQ(spec.prbs_order, 11);
  EXPECT_EQ(spec.multisine_components, 5);
  EXPECT_EQ(spec.prbs_bit_period_s, defaults.prbs_bit_period_s);
  EXPECT_EQ(spec.chirp_f1_hz, defaults.chirp_f1_hz);
}

TEST(SpecFromCommand, EveryAcceptedProfileMakesAnExcitation) {
  for (const char* name : {"bang_bang", "free_decay", "step", "prbs", "chirp", "multisine"}) {
    rig_command_t command = start();
    command.profile = name;
    command.amplitude_duty = 0.5;
    command.duration_s = 600.0;
    command.seed = 0;
    ASSERT_TRUE(check_once(command).accepted) << name;
    const ExcitationSpec spec = spec_from_command(command, ExcitationSpec{});
    EXPECT_EQ(to_string(spec.kind), name);
    EXPECT_NO_THROW(Excitation{spec}) << name;
    EXPECT_EQ(check_spec_limits(spec, CommandLimits{}), "") << name;
  }
}

TEST(SpecFromCommand, RefusesWhatValidationRefuses) {
  rig_command_t command = start();
  command.profile = "sine";
  EXPECT_THROW(spec_from_command(command, ExcitationSpec{}), std::invalid_argument);
  command.profile = "step";
  command.seed = -3;
  EXPECT_THROW(spec_from_command(command, ExcitationSpec{}), std::invalid_argument);
}

TEST(CheckSpecLimits, NamesTheFieldBeyondTheCommandLimits) {
  const CommandLimits limits;
  ExcitationSpec spec;
  spec.amplitude_duty = 0.5;
  spec.duration_s = 600.0;
  spec.arm_switch_rad = 2.4;
  EXPECT_EQ(check_spec_limits(spec, limits), "");
  spec.arm_switch_rad = 2.5;
  EXPECT_EQ(check_spec_limits(spec, limits), "arm_switch_rad: 2.5 above the limit 2.4");
  spec.arm_switch_rad = kNan;
  EXPECT_EQ(check_spec_limits(spec, limits), "arm_switch_rad: nan above the limit 2.4");
  spec.kind = ProfileKind::chirp;  // thresholds only matter to bang-bang
  EXPECT_EQ(check_spec_limits(spec, limits), "");
  spec.amplitude_duty = 0.6;
  EXPECT_EQ(check_spec_limits(spec, limits), "amplitude_duty: 0.6 above the limit 0.5");
  spec.amplitude_duty = 0.5;
  spec.duration_s = kInf;
  EXPECT_EQ(check_spec_limits(spec, limits), "duration_s: inf is not a finite number");
}

}  // namespace
}  // namespace furuta::daemon::command_validator_test
