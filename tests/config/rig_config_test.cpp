#include "furuta/config/rig_config.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace furuta::config {
namespace {

ConfigError error_of(const std::string& text) {
  try {
    parse_rig_config(text, "rig.toml");
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no ConfigError for:\n" << text;
  return ConfigError("", 0, "", "");
}

TEST(RigConfig, TheShippedFileLoadsWithThePapersValues) {
  const RigConfig c = load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  EXPECT_EQ(c.name, "furuta-lab-1");
  EXPECT_EQ(c.backend, UsbBackend::simulated);
  EXPECT_DOUBLE_EQ(c.arm_encoder.counts_per_rev, 1024.0);
  EXPECT_DOUBLE_EQ(c.arm_encoder.gear_ratio, 26.0);  // 5.2 * 5
  EXPECT_DOUBLE_EQ(c.simulation.parameters.fv1, 8.13e-2);
  EXPECT_DOUBLE_EQ(c.simulation.parameters.mu4, 1.31781e-3);
  ASSERT_TRUE(c.nominal.has_value());
  EXPECT_DOUBLE_EQ(c.nominal->mu1, 1.18152e-3);
  EXPECT_DOUBLE_EQ(c.simulation.motor_encoder_counts_per_rev, 1024.0);
  EXPECT_FALSE(c.motor_board.serial.has_value());
}

TEST(RigConfig, AnEmptyFileGivesTheDefaults) {
  const RigConfig c = parse_rig_config("", "empty.toml");
  EXPECT_DOUBLE_EQ(c.pendulum_encoder.counts_per_rev, 4096.0);
  EXPECT_DOUBLE_EQ(c.motor.no_load_speed_rpm, 11700.0);
  EXPECT_DOUBLE_EQ(c.simulation.parameters.mug, model::paper_run1().mug);
  EXPECT_FALSE(c.nominal.has_value());
}

TEST(RigConfig, EncoderGeometryReachesTheSimulationAndConvertsDegrees) {
  const RigConfig c = parse_rig_config(
      "[encoders.pendulum]\ncounts_per_rev = 2000\nsign = -1\nzero_offset_deg = 180\n"
      "[boards.encoder]\nserial = \"123456\"\npendulum_channel = 2\n",
      "rig.toml");
  EXPECT_EQ(c.pendulum_encoder.sign, -1);
  EXPECT_NEAR(c.pendulum_encoder.zero_offset_rad, std::numbers::pi, 1e-15);
  EXPECT_DOUBLE_EQ(c.simulation.pendulum_encoder_counts_per_rev, 2000.0);
  EXPECT_EQ(c.simulation.pendulum_channel, 2);
  EXPECT_EQ(c.simulation.serial_1047, "123456");
  ASSERT_TRUE(c.encoder_board.serial.has_value());
}

TEST(RigConfig, ErrorsNameFileLineAndField) {
  const ConfigError e = error_of("[rig]\nname = \"x\"\n\n[encoders.arm]\ncounts_per_rev = -5\n");
  EXPECT_EQ(e.file(), "rig.toml");
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.field(), "encoders.arm.counts_per_rev");
  EXPECT_NE(std::string(e.what()).find("rig.toml:5: encoders.arm.counts_per_rev: must be > 0"),
            std::string::npos)
      << e.what();
}

// The torque is formed from the input input_lag_ms earlier: a negative lag would have the angles
// lead the input.
TEST(RigConfig, ANegativeInputLagIsRefused) {
  const ConfigError e = error_of("[identification]\ninput_lag_ms = -3\n");
  EXPECT_EQ(e.line(), 2);
  EXPECT_NE(std::string(e.what()).find("identification.input_lag_ms: must be in [0, 100]"),
            std::string::npos)
      << e.what();
  EXPECT_EQ(*parse_rig_config("[identification]\ninput_lag_ms = 0\n", "rig.toml")
                 .identification.input_lag_ms,
            0.0);
}

// [guaranteed]: the physical inputs no recording gives; each refusal names its key and line.
TEST(RigConfig, GuaranteedInputsAreReadAndChecked) {
  const RigConfig shipped = load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  EXPECT_EQ(shipped.guaranteed.prior_percent, 50.0);
  EXPECT_EQ(shipped.guaranteed.lag_ms, (std::array<double, 2>{0.0, 2.0}));
  const RigConfig c = parse_rig_config(
      "[guaranteed]\nprior_percent = 30\nfriction_prior = [0.0, 0.5]\nlag_ms = [0.5, 3]\n"
      "motor_tolerance_pct = [2, 3, 0.5, 0]\n",
      "rig.toml");
  EXPECT_EQ(c.guaranteed.prior_percent, 30.0);
  EXPECT_EQ(c.guaranteed.friction_prior, (std::array<double, 2>{0.0, 0.5}));
  EXPECT_EQ(c.guaranteed.lag_ms, (std::array<double, 2>{0.5, 3.0}));
  EXPECT_EQ(c.guaranteed.motor_tolerance_pct, (std::array<double, 4>{2, 3, 0.5, 0}));
  EXPECT_STREQ(error_of("[guaranteed]\n\nlag_ms = [2, 1]\n").what(),
               "rig.toml:3: guaranteed.lag_ms: must be [low, high] with 0 <= low < high (an "
               "angle cannot lead its state)");
  EXPECT_EQ(error_of("[guaranteed]\nfriction_prior = [-0.1, 1]\n").field(),
            "guaranteed.friction_prior");
  EXPECT_EQ(error_of("[guaranteed]\nprior_percent = 100\n").field(), "guaranteed.prior_percent");
  EXPECT_EQ(error_of("[guaranteed]\nmotor_tolerance_pct = [1, 1, 1]\n").field(),
            "guaranteed.motor_tolerance_pct");
  EXPECT_EQ(error_of("[guaranteed]\nlag = [0, 1]\n").field(), "guaranteed.lag");
}

TEST(RigConfig, CountsPerRevolutionMustBeAWholeNumber) {
  const ConfigError e = error_of("[encoders.pendulum]\ncounts_per_rev = 1024.5\n");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.field(), "encoders.pendulum.counts_per_rev");
  EXPECT_NE(std::string(e.what()).find(
                "rig.toml:2: encoders.pendulum.counts_per_rev: must be a whole number of counts"),
            std::string::npos)
      << e.what();
  // A whole number written as a float is the same count.
  EXPECT_DOUBLE_EQ(parse_rig_config("[encoders.arm]\ncounts_per_rev = 2048.0\n", "rig.toml")
                       .arm_encoder.counts_per_rev,
                   2048.0);
}

TEST(RigConfig, UnknownKeysAreRejectedNotIgnored) {
  const ConfigError e = error_of("[motor]\nmotor_ration = 5.2\n");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.field(), "motor.motor_ration");
  EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos);
  EXPECT_EQ(error_of("[simulaton]\nseed = 3\n").field(), "simulaton");
}

TEST(RigConfig, WrongTypesRangesAndChoicesAreErrors) {
  EXPECT_EQ(error_of("[simulation]\nseed = \"one\"\n").field(), "simulation.seed");
  EXPECT_EQ(error_of("[encoders.arm]\nsign = 2\n").field(), "encoders.arm.sign");
  EXPECT_EQ(error_of("[motor]\nmotor_efficiency = 1.5\n").field(), "motor.motor_efficiency");
  EXPECT_EQ(error_of("[boards.encoder]\npendulum_channel = 4\n").field(),
            "boards.encoder.pendulum_channel");
  EXPECT_EQ(error_of("[motor]\nno_load_speed_rpm = nan\n").field(), "motor.no_load_speed_rpm");
  const ConfigError backend = error_of("[rig]\nbackend = \"serial\"\n");
  EXPECT_EQ(backend.field(), "rig.backend");
  EXPECT_NE(std::string(backend.what()).find("simulated, hidapi, libusb"), std::string::npos);
  EXPECT_EQ(error_of("rig = 3\n").field(), "rig");  // a table expected
}

TEST(RigConfig, SyntaxErrorsCarryTheirLine) {
  const ConfigError e = error_of("[rig]\nname = \"unterminated\n");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.file(), "rig.toml");
}

TEST(RigConfig, AMissingFileIsAnErrorNamingIt) {
  try {
    load_rig_config("/nonexistent/rig.toml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/rig.toml");
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
  }
}

}  // namespace
}  // namespace furuta::config

namespace furuta::config {
namespace {

TEST(RigConfig, IdentificationSectionIsCheckedAgainstTheSamplePeriod) {
  const RigConfig shipped = load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  EXPECT_EQ(shipped.identification.cutoff_hz, 15.0);
  ASSERT_TRUE(shipped.identification.input_lag_ms.has_value());
  EXPECT_FALSE(parse_rig_config("", "empty").identification.input_lag_ms.has_value());
  // 16 ms: Nyquist 31.25 Hz, so the cut-off must stay below 15.625 Hz.
  const ConfigError high = error_of("[identification]\ncutoff_hz = 16\n");
  EXPECT_EQ(high.field(), "identification.cutoff_hz");
  EXPECT_EQ(high.line(), 2);
  // A faster loop allows a higher cut-off.
  EXPECT_EQ(parse_rig_config("[daemon]\nperiod_ms = 8\n[identification]\ncutoff_hz = 20\n", "x")
                .identification.cutoff_hz,
            20.0);
  EXPECT_EQ(error_of("[identification]\ndifferentiator_taps = 30\n").field(),
            "identification.differentiator_taps");
}

}  // namespace
}  // namespace furuta::config

namespace furuta::config {
namespace {

TEST(RigConfig, AutomationSectionSaysWhichSessionsFormAnIdentification) {
  const RigConfig shipped = load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  EXPECT_EQ(shipped.automation.fit_labels, std::vector<std::string>{"bang-bang"});
  EXPECT_EQ(shipped.automation.fit_sessions, 2);
  EXPECT_EQ(shipped.automation.validation_label, "validation");
  EXPECT_EQ(shipped.automation.identifications_dir, "/var/lib/furuta/identifications");

  const RigConfig c = parse_rig_config(
      "[automation]\nfit_labels = [\"a\", \"b\"]\nfit_sessions = 3\nvalidation_label = \"\"\n"
      "sivia = false\nsimulate = false\nsimulate_seconds = 0.5\nidentifications_dir = \"ids\"\n",
      "rig.toml");
  EXPECT_EQ(c.automation.fit_labels, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(c.automation.fit_sessions, 3);
  EXPECT_TRUE(c.automation.validation_label.empty());
  EXPECT_FALSE(c.automation.sivia);
  EXPECT_FALSE(c.automation.simulate);
  EXPECT_EQ(c.automation.simulate_seconds, 0.5);
  EXPECT_EQ(c.automation.identifications_dir, "ids");
}

TEST(RigConfig, AutomationErrorsNameLineAndField) {
  const ConfigError both =
      error_of("[automation]\nfit_labels = [\"x\"]\n\nvalidation_label = \"x\"\n");
  EXPECT_EQ(both.field(), "automation.validation_label");
  EXPECT_EQ(both.line(), 4);
  EXPECT_NE(std::string(both.what()).find("also one of fit_labels"), std::string::npos);

  const ConfigError none = error_of("[automation]\nfit_labels = []\n");
  EXPECT_EQ(none.field(), "automation.fit_labels");
  EXPECT_NE(std::string(none.what()).find("at least one label"), std::string::npos);

  const ConfigError twice = error_of("[automation]\n\nfit_labels = [\"a\", \"a\"]\n");
  EXPECT_EQ(twice.line(), 3);
  EXPECT_NE(std::string(twice.what()).find("'a' is given twice"), std::string::npos);

  EXPECT_EQ(error_of("[automation]\nfit_labels = [\"\"]\n").field(), "automation.fit_labels");
  EXPECT_EQ(error_of("[automation]\nfit_labels = [1]\n").field(), "automation.fit_labels");
  EXPECT_EQ(error_of("[automation]\nfit_sessions = 0\n").field(), "automation.fit_sessions");
  EXPECT_EQ(error_of("[automation]\nsivia = \"yes\"\n").field(), "automation.sivia");
  EXPECT_EQ(error_of("[automation]\nsimulate_seconds = 0\n").field(),
            "automation.simulate_seconds");
  EXPECT_EQ(error_of("[automation]\nidentifications_dir = \"\"\n").field(),
            "automation.identifications_dir");
  const ConfigError typo = error_of("[automation]\nfit_label = [\"a\"]\n");
  EXPECT_EQ(typo.field(), "automation.fit_label");
  EXPECT_EQ(typo.line(), 2);
}

TEST(RigConfig, SimulationTapsAreReadWithTheirImpulsesInMilliNewtonMetreSeconds) {
  EXPECT_TRUE(parse_rig_config("", "empty.toml").simulation.taps.empty());
  EXPECT_TRUE(load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml").simulation.taps.empty());

  const RigConfig one = parse_rig_config(
      "[simulation]\ntap_times_s = [20.0, 40]\ntap_impulse_mnm_s = 2.0\n", "rig.toml");
  ASSERT_EQ(one.simulation.taps.size(), 2u);
  EXPECT_EQ(one.simulation.taps[0].time_s, 20.0);
  EXPECT_EQ(one.simulation.taps[1].time_s, 40.0);
  EXPECT_DOUBLE_EQ(one.simulation.taps[0].impulse_nm_s, 2e-3);
  EXPECT_DOUBLE_EQ(one.simulation.taps[1].impulse_nm_s, 2e-3);

  const RigConfig each = parse_rig_config(
      "[simulation]\ntap_times_s = [0, 1.5]\ntap_impulse_mnm_s = [1.5, -2]\n", "rig.toml");
  ASSERT_EQ(each.simulation.taps.size(), 2u);
  EXPECT_DOUBLE_EQ(each.simulation.taps[0].impulse_nm_s, 1.5e-3);
  EXPECT_DOUBLE_EQ(each.simulation.taps[1].impulse_nm_s, -2e-3);

  // An impulse without times taps nothing.
  EXPECT_TRUE(
      parse_rig_config("[simulation]\ntap_impulse_mnm_s = 3\n", "r").simulation.taps.empty());
}

TEST(RigConfig, BadTapsAreRefusedAtTheirLine) {
  struct Case {
    const char* value;  // of the key, which is on line 3
    int line;
    const char* problem;
  };
  const auto check = [](const char* key, const Case& c) {
    const std::string text =
        std::string("[simulation]\n# the taps\n") + key + " = " + c.value + "\n";
    SCOPED_TRACE(text);
    const ConfigError e = error_of(text);
    EXPECT_EQ(e.file(), "rig.toml");
    EXPECT_EQ(e.line(), c.line) << e.what();
    EXPECT_EQ(e.field(), std::string("simulation.") + key);
    EXPECT_NE(std::string(e.what()).find(c.problem), std::string::npos) << e.what();
  };
  for (const Case& c : std::vector<Case>{
           {"[20.0, 10.0]", 3, "must be strictly increasing"},
           {"[\n  20.0,\n  40.0,\n  30.0,\n]", 6, "must be strictly increasing"},
           {"[20.0, 20.0]", 3, "must be strictly increasing"},
           {"[nan]", 3, "must be finite"},
           {"[10, inf]", 3, "must be finite"},
           {"[-1.0]", 3, "entries must be in [0, 1e9]"},
           {"[2e9]", 3, "entries must be in [0, 1e9]"},
           {"[\"20\"]", 3, "must be an array of numbers"},
           {"20.0", 3, "must be an array of numbers"},
           {"[[20.0]]", 3, "must be an array of numbers"},
       }) {
    check("tap_times_s", c);
  }
  for (const Case& c : std::vector<Case>{
           {"nan", 3, "must be finite"},
           {"-inf", 3, "must be finite"},
           {"\"2.0\"", 3, "must be a number"},
           {"[1.0, nan]", 3, "must be finite"},
           {"[1.0, true]", 3, "must be an array of numbers"},
           {"[1.0]", 3, "must be one number or an array as long as tap_times_s (0)"},
       }) {
    check("tap_impulse_mnm_s", c);
  }
  // Against the times given.
  const ConfigError e =
      error_of("[simulation]\ntap_times_s = [20.0, 40.0]\n\ntap_impulse_mnm_s = [1.0, 2.0, 3.0]\n");
  EXPECT_EQ(e.line(), 4);
  EXPECT_NE(std::string(e.what()).find("an array as long as tap_times_s (2)"), std::string::npos)
      << e.what();
}

}  // namespace
}  // namespace furuta::config

namespace furuta::config {
namespace {

// Issue 8: every limit the daemon's safety rests on refuses a bad value with file, line and field,
// whatever the kind of bad (wrong type, NaN, infinity, out of range), and never falls back to its
// default. Policy: a key left out takes the documented default (rig.toml lists them all); a key
// given with a bad value is always an error.
TEST(RigConfig, EverySafetyLimitRefusesBadValuesWithFileLineAndField) {
  struct Limit {
    const char* section;
    const char* key;
    std::vector<const char*> bad;  // besides the wrong types and non-finite values tried for all
  };
  const std::vector<Limit> limits = {
      {"safety", "arm_limit_deg", {"0", "-10", "721", "1e308"}},
      {"safety", "max_duty", {"0", "-0.5", "1.01", "1e308"}},
      {"safety", "stale_report_cycles", {"0", "-1", "1001", "4.0", "9223372036854775807"}},
      {"safety", "min_supply_v", {"-1", "40"}},
      {"safety", "max_supply_v", {"0", "-1", "5"}},
      {"safety", "stop_braking", {"-0.1", "1.5"}},
      {"safety", "stuck_arm_cycles", {"0", "-1", "1001", "4.5"}},
      {"safety", "stuck_arm_min_duty", {"0", "-0.1", "1.01"}},
      {"safety", "stuck_pendulum_arm_travel_deg", {"0", "-1", "36001", "1e308"}},
      {"limits", "max_amplitude_duty", {"0", "-0.1", "0.7", "1.5"}},
      {"limits", "max_duration_s", {"0", "-1"}},
      {"limits", "max_arm_switch_deg", {"0", "-1", "150", "1e308"}},
      {"limits", "max_commands_per_s", {"0", "-5", "1001", "5.5"}},
      {"excitation", "amplitude_duty", {"0", "0.6", "1e308"}},
      {"excitation", "arm_switch_deg", {"-1", "136"}},
      {"excitation", "board_acceleration_pct_per_s", {"0", "24.5", "6251", "-6250"}},
      {"daemon", "period_ms", {"0", "0.05", "1001"}},
  };
  const std::vector<const char*> always_bad = {"nan",  "-nan",  "inf",       "-inf",      "\"0.5\"",
                                               "true", "[0.5]", "{ x = 1 }", "1979-05-27"};
  for (const Limit& limit : limits) {
    std::vector<const char*> values = limit.bad;
    values.insert(values.end(), always_bad.begin(), always_bad.end());
    for (const char* value : values) {
      // The key on line 3, after a comment line, so the line number cannot be the section's.
      const std::string text =
          std::string("[") + limit.section + "]\n# the limit\n" + limit.key + " = " + value + "\n";
      SCOPED_TRACE(text);
      const ConfigError e = error_of(text);
      EXPECT_EQ(e.file(), "rig.toml");
      EXPECT_EQ(e.line(), 3) << e.what();
      EXPECT_EQ(e.field(), std::string(limit.section) + "." + limit.key) << e.what();
      EXPECT_EQ(std::string(e.what()).rfind("rig.toml:3: " + e.field() + ": ", 0), 0u) << e.what();
    }
  }
}

TEST(RigConfig, AMissingSafetyLimitTakesTheDocumentedDefault) {
  const RigConfig c = parse_rig_config("[safety]\n", "rig.toml");
  const SafetyConfig defaults;
  EXPECT_EQ(c.safety.max_duty, defaults.max_duty);
  EXPECT_EQ(c.safety.stale_report_cycles, defaults.stale_report_cycles);
  EXPECT_EQ(c.safety.min_supply_v, defaults.min_supply_v);
  EXPECT_EQ(c.safety.max_supply_v, defaults.max_supply_v);
  EXPECT_EQ(c.limits.max_commands_per_s, CommandLimitsConfig{}.max_commands_per_s);
  // The shipped file states the same values.
  const RigConfig shipped = load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  EXPECT_EQ(shipped.safety.max_duty, defaults.max_duty);
  EXPECT_EQ(shipped.safety.stale_report_cycles, defaults.stale_report_cycles);
  EXPECT_NEAR(shipped.safety.arm_limit_rad, 150 * std::numbers::pi / 180, 1e-12);
}

// rig.toml says "the values below are the defaults", so a key left out must mean what the file
// shows. The arm limit defaulted to 2.6 rad (149.0 deg) against the file's 150, and
// max_arm_switch_deg to 2.4 rad (137.5 deg) against 135: a file without max_arm_switch_deg accepted
// arm_switch_deg = 136, which the shipped documentation says is refused.
TEST(RigConfig, TheShippedFileStatesTheDefaults) {
  const RigConfig empty = parse_rig_config("", "empty.toml");
  const RigConfig shipped = load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml");
  EXPECT_NEAR(empty.safety.arm_limit_rad, shipped.safety.arm_limit_rad, 1e-12);
  EXPECT_EQ(empty.safety.max_duty, shipped.safety.max_duty);
  EXPECT_EQ(empty.safety.stale_report_cycles, shipped.safety.stale_report_cycles);
  EXPECT_EQ(empty.safety.min_supply_v, shipped.safety.min_supply_v);
  EXPECT_EQ(empty.safety.max_supply_v, shipped.safety.max_supply_v);
  EXPECT_EQ(empty.safety.stop_braking_fraction, shipped.safety.stop_braking_fraction);
  EXPECT_EQ(empty.safety.stuck_arm_cycles, shipped.safety.stuck_arm_cycles);
  EXPECT_EQ(empty.safety.stuck_arm_min_duty, shipped.safety.stuck_arm_min_duty);
  EXPECT_NEAR(empty.safety.stuck_pendulum_arm_travel_rad,
              shipped.safety.stuck_pendulum_arm_travel_rad, 1e-12);
  EXPECT_EQ(empty.limits.max_amplitude_duty, shipped.limits.max_amplitude_duty);
  EXPECT_EQ(empty.limits.max_duration_s, shipped.limits.max_duration_s);
  EXPECT_NEAR(empty.limits.max_arm_switch_rad, shipped.limits.max_arm_switch_rad, 1e-12);
  EXPECT_EQ(empty.limits.max_commands_per_s, shipped.limits.max_commands_per_s);
  EXPECT_EQ(empty.excitation.amplitude_duty, shipped.excitation.amplitude_duty);
  EXPECT_NEAR(empty.excitation.arm_switch_rad, shipped.excitation.arm_switch_rad, 1e-12);
  EXPECT_EQ(empty.excitation.board_acceleration_pct_per_s,
            shipped.excitation.board_acceleration_pct_per_s);
  EXPECT_EQ(empty.daemon.period_ns, shipped.daemon.period_ns);
  EXPECT_EQ(empty.daemon.rest_check_s, shipped.daemon.rest_check_s);
  EXPECT_EQ(empty.daemon.reconnect_interval_ms, shipped.daemon.reconnect_interval_ms);
  EXPECT_EQ(empty.daemon.command_key_file, shipped.daemon.command_key_file);
  EXPECT_EQ(empty.daemon.command_window_s, shipped.daemon.command_window_s);
}

TEST(RigConfig, ALimitMisspelledOrInTheWrongSectionIsAnError) {
  for (const char* text : {"[safety]\nmax_dutty = 0.5\n", "[limits]\nmax_duty = 0.5\n",
                           "max_duty = 0.5\n", "[Safety]\nmax_duty = 0.5\n", "safety = 1\n",
                           "[safety]\nmax_duty = 0.5\nmax_duty = 0.4\n"}) {
    SCOPED_TRACE(text);
    const ConfigError e = error_of(text);
    EXPECT_EQ(e.file(), "rig.toml");
    EXPECT_GT(e.line(), 0) << e.what();
  }
}

}  // namespace
}  // namespace furuta::config

namespace furuta::config {
namespace {

// Choices are read once, into the enum of the configuration: a user compares no strings.
TEST(RigConfig, ChoicesAreReadAsTheirEnumValues) {
  EXPECT_EQ(load_rig_config(FURUTA_SOURCE_DIR "/config/rig.toml").sivia.inner_test,
            SiviaInnerTest::witness);
  EXPECT_EQ(parse_rig_config("", "empty.toml").sivia.inner_test, SiviaInnerTest::witness);
  const std::vector<std::pair<const char*, SiviaInnerTest>> inner = {
      {"witness", SiviaInnerTest::witness},
      {"intermediate_value", SiviaInnerTest::intermediate_value},
      {"for_all_data", SiviaInnerTest::for_all_data},
      {"none", SiviaInnerTest::none},
  };
  for (const auto& [name, value] : inner) {
    SCOPED_TRACE(name);
    EXPECT_EQ(parse_rig_config(std::string("[sivia]\ninner_test = \"") + name + "\"\n", "rig.toml")
                  .sivia.inner_test,
              value);
  }
  EXPECT_STREQ(error_of("[sivia]\n\ninner_test = \"Witness\"\n").what(),
               "rig.toml:3: sivia.inner_test: 'Witness' is not one of: witness, "
               "intermediate_value, for_all_data, none");
  EXPECT_EQ(parse_rig_config("[rig]\nbackend = \"libusb\"\n", "rig.toml").backend,
            UsbBackend::libusb);
  EXPECT_EQ(parse_rig_config("[rig]\nbackend = \"hidapi\"\n", "rig.toml").backend,
            UsbBackend::hidapi);
  EXPECT_STREQ(error_of("[rig]\nbackend = \"usb\"\n").what(),
               "rig.toml:2: rig.backend: 'usb' is not one of: simulated, hidapi, libusb");
}

}  // namespace
}  // namespace furuta::config
