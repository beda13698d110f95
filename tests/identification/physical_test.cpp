// check_physical: each condition of the physical region, a violation within noise against a clear
// one, and the causes read from the patterns that each recording mistake gives exactly (the
// derivation is at the top of identification/src/physical.cpp; the command-level measurement in
// tests/app/identify_physical_test.cpp).
#include "furuta/identification/physical.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace furuta::identification {
namespace {

using P = model::Parameters<double>;

P truth() {
  return model::paper_run1();
}
// LSMI-like standard deviations: 1 % of each parameter.
P one_percent(const P& p) {
  return p.map([](double v) { return 0.01 * std::fabs(v); });
}

bool violates(const PhysicalCheck& c, PhysicalCondition condition) {
  for (const auto& v : c.violations) {
    if (v.condition == condition) return true;
  }
  return false;
}

TEST(PhysicalCheck, TheTruthIsConsistentAndWarnsOfNothing) {
  const PhysicalCheck c = check_physical(truth(), one_percent(truth()), truth());
  EXPECT_TRUE(c.consistent());
  EXPECT_EQ(c.cause, LikelyCause::none);
  EXPECT_EQ(c.reference, MagnitudeReference::cad);
  EXPECT_NEAR(*c.inertia_ratio_to_cad, 1.0, 1e-12);
  EXPECT_NEAR(*c.pendulum_frequency_rad_s, std::sqrt(7.4175e-2 / 1.31781e-3), 1e-9);
  EXPECT_EQ(physical_warning(c, RecordingSource::csv, "it"), "");
  // Without std devs or CAD as well.
  EXPECT_TRUE(check_physical(truth()).consistent());
  EXPECT_EQ(check_physical(truth()).cause, LikelyCause::none);
}

TEST(PhysicalCheck, EachConditionIsNamed) {
  const struct {
    double P::*member;
    PhysicalCondition condition;
  } cases[] = {
      {&P::mu1, PhysicalCondition::mu1_positive},   {&P::mu2, PhysicalCondition::mu2_positive},
      {&P::mu3, PhysicalCondition::mu3_positive},   {&P::mu4, PhysicalCondition::mu4_positive},
      {&P::mug, PhysicalCondition::mug_positive},   {&P::fv1, PhysicalCondition::fv1_nonnegative},
      {&P::fv2, PhysicalCondition::fv2_nonnegative}};
  for (const auto& k : cases) {
    P p = truth();
    p.*k.member = -(p.*k.member);
    const PhysicalCheck c = check_physical(p, one_percent(truth()));
    EXPECT_TRUE(violates(c, k.condition)) << condition_text(k.condition);
    EXPECT_TRUE(c.clear()) << condition_text(k.condition);
  }
  // Zero: a strict condition fails, a friction's holds.
  P p = truth();
  p.mu2 = 0;
  p.fv2 = 0;
  const PhysicalCheck c = check_physical(p);
  EXPECT_TRUE(violates(c, PhysicalCondition::mu2_positive));
  EXPECT_FALSE(violates(c, PhysicalCondition::fv2_nonnegative));
}

TEST(PhysicalCheck, AMassMatrixThatIsNotPositiveDefiniteSomewhere) {
  P p = truth();
  p.mu3 = 1.1 * std::sqrt(p.mu1 * p.mu4);  // det M < 0 at q2 = 0, every sign right
  const PhysicalCheck c = check_physical(p, one_percent(p));
  ASSERT_EQ(c.violations.size(), 1u);
  EXPECT_EQ(c.violations[0].condition, PhysicalCondition::mass_matrix_positive_definite);
  EXPECT_NEAR(c.violations[0].margin, p.mu1 * p.mu4 - p.mu3 * p.mu3, 1e-18);
  EXPECT_GT(c.violations[0].sigmas, 0);
  const std::string w = physical_warning(c, RecordingSource::session_log, "the estimate");
  EXPECT_NE(w.find("mu1 mu4 > mu3^2"), std::string::npos) << w;
}

// fv2 a little below 0 on a rig with almost no pendulum friction is noise, not a mistake.
TEST(PhysicalCheck, AViolationWithinNoiseIsSaidToBe) {
  P p = truth();
  p.fv2 = -1e-6;
  P sd = one_percent(truth());
  sd.fv2 = 2e-6;
  const PhysicalCheck c = check_physical(p, sd, truth());
  ASSERT_EQ(c.violations.size(), 1u);
  EXPECT_NEAR(c.violations[0].sigmas, 0.5, 1e-12);
  EXPECT_TRUE(c.violations[0].within_noise);
  EXPECT_FALSE(c.clear());
  EXPECT_EQ(c.cause, LikelyCause::none);
  const std::string w = physical_warning(c, RecordingSource::csv, "the estimate");
  EXPECT_EQ(w.rfind(kPhysicalWarningPrefix, 0), 0u) << w;
  EXPECT_NE(w.find("0.5 sd past the boundary: within noise"), std::string::npos) << w;
  EXPECT_NE(w.find("do not exclude a physical rig"), std::string::npos) << w;

  sd.fv2 = 1e-7;  // now 10 sd: clear, and no pattern explains it
  const PhysicalCheck clear = check_physical(p, sd, truth());
  EXPECT_TRUE(clear.clear());
  EXPECT_EQ(clear.cause, LikelyCause::unknown);
}

// The exact patterns (docs/csv-import.md's table), with and without CAD values.
TEST(PhysicalCheck, SignPatternsNameTheirCause) {
  const P t = truth();
  P pendulum_sign = t, zero = t, zero_and_sign = t, input_sign, arm_sign;
  pendulum_sign.mu3 = -t.mu3;
  zero.mu3 = -t.mu3;
  zero.mug = -t.mug;
  zero_and_sign.mug = -t.mug;
  input_sign = t.map([](double v) { return -v; });
  input_sign.fv1 -= 2 * 0.155;  // the back-EMF, not flipped with the duty
  arm_sign = input_sign;
  arm_sign.mu3 = t.mu3;
  const struct {
    P p;
    LikelyCause cause;
  } cases[] = {{pendulum_sign, LikelyCause::pendulum_sign},
               {zero, LikelyCause::pendulum_zero},
               {zero_and_sign, LikelyCause::pendulum_zero_and_sign},
               {input_sign, LikelyCause::input_sign},
               {arm_sign, LikelyCause::arm_sign}};
  for (const auto& k : cases) {
    for (const bool cad : {false, true}) {
      const PhysicalCheck c =
          check_physical(k.p, one_percent(k.p), cad ? std::optional<P>(t) : std::nullopt);
      EXPECT_EQ(c.cause, k.cause) << cause_name(k.cause) << (cad ? " with CAD" : "");
      EXPECT_EQ(c.candidates.size(), 1u) << cause_name(k.cause);
    }
  }
}

TEST(PhysicalCheck, WarningsNameTheSettingToCheckForEachSource) {
  P p = truth();
  p.mu3 = -p.mu3;
  const PhysicalCheck c = check_physical(p, one_percent(p));
  const std::string csv = physical_warning(c, RecordingSource::csv, "the LSMI estimate");
  EXPECT_NE(csv.find("violates mu3 > 0 (mu3 = -0.000821, 1e+02 sd past the boundary)"),
            std::string::npos)
      << csv;
  EXPECT_NE(csv.find("Likely cause: the pendulum angle counted the other way"), std::string::npos);
  EXPECT_NE(csv.find("pendulum_angle_scale"), std::string::npos) << csv;
  const std::string log = physical_warning(c, RecordingSource::session_log, "the LSMI estimate");
  EXPECT_NE(log.find("[encoders.pendulum] sign"), std::string::npos) << log;
}

// Units and gains keep every sign: CAD values tell them apart; without, only an angle unit's
// garbled ratios show.
TEST(PhysicalCheck, MagnitudesAgainstCad) {
  const P t = truth();
  const auto scaled = [&](double inertia, double gravity, double friction) {
    P p = t;
    p.mu1 *= inertia;
    p.mu2 *= inertia;
    p.mu3 *= inertia;
    p.mu4 *= inertia;
    p.mug *= gravity;
    p.fv1 *= friction;
    p.fv2 *= friction;
    return p;
  };
  const P gain = scaled(20, 20, 20);
  const P time = scaled(1e-6, 1, 1e-3);  // time stamps 1000 times too small
  // Degrees read as radians, as measured in tests/app/identify_physical_test.cpp (fv1 made
  // positive: a torque input has no back-EMF to drive it below 0).
  const P angle = {0.012 * t.mu1,  6.7e-6 * t.mu2, 9.8e-6 * t.mu3, 2.7e-6 * t.mu4,
                   1.1e-4 * t.mug, 0.26 * t.fv1,   5.9e-5 * t.fv2};
  // The angle unit scales nothing alike: it is named only when the recordings show angles beyond
  // radians (here an arm that travelled 80 "rad", 80 degrees read as radians).
  RecordingEvidence degrees;
  degrees.shortest_s = 10;
  degrees.steps = 1000;
  degrees.largest_arm_travel_rad = 80;
  EXPECT_EQ(check_physical(gain, one_percent(gain), t).cause, LikelyCause::input_gain);
  EXPECT_EQ(check_physical(time, one_percent(time), t).cause, LikelyCause::time_unit);
  EXPECT_EQ(check_physical(angle, one_percent(angle), t, &degrees).cause, LikelyCause::angle_unit);
  EXPECT_TRUE(check_physical(angle, one_percent(angle), t, &degrees).consistent());
  const std::string w = physical_warning(check_physical(angle, one_percent(angle), t, &degrees),
                                         RecordingSource::csv, "the estimate");
  EXPECT_NE(w.find("lies inside the physical region, but its magnitudes are no rig's"),
            std::string::npos)
      << w;
  EXPECT_NE(w.find("angle_unit"), std::string::npos) << w;

  // Without CAD a gain is invisible (every ratio kept); the angle unit's ratios are not.
  EXPECT_EQ(check_physical(gain, one_percent(gain)).cause, LikelyCause::none);
  const PhysicalCheck internal = check_physical(angle, one_percent(angle), std::nullopt, &degrees);
  EXPECT_EQ(internal.reference, MagnitudeReference::internal);
  EXPECT_EQ(internal.cause, LikelyCause::angle_unit);
}

// A recording of `seconds` at 16 ms: the arm swinging 0.5 rad, the pendulum 0.2 rad, at 1 Hz.
RawExperiment swinging(double seconds) {
  RawExperiment e;
  e.sample_period_s = 0.016;
  for (double t = 0; t <= seconds; t += e.sample_period_s) {
    e.t_s.push_back(t);
    e.q1.push_back(0.5 * std::sin(2 * M_PI * t));
    e.q2.push_back(0.2 * std::sin(2 * M_PI * t + 1));
    e.input.push_back(0.3);
  }
  return e;
}

// Before, magnitudes no pattern of the parameters explains were put down to "the angles' unit"
// whatever the recordings were: a 1.4 s session, a CSV with one reading of 1e5. Each cause is now
// named only when a check on the recordings found it, else "unknown".
TEST(PhysicalCheck, ACauseTheMagnitudesCannotTellIsNamedOnlyFromTheRecordings) {
  const P t = truth();
  const P garbled = {0.012 * t.mu1,  6.7e-6 * t.mu2, 9.8e-6 * t.mu3, 2.7e-6 * t.mu4,
                     1.1e-4 * t.mug, 0.26 * t.fv1,   5.9e-5 * t.fv2};
  const auto cause = [&](const std::vector<RawExperiment>& recordings) {
    const RecordingEvidence evidence = recording_evidence(recordings);
    return check_physical(garbled, one_percent(garbled), t, &evidence).cause;
  };
  // Ten seconds in radians: nothing in the data explains it.
  EXPECT_EQ(cause({swinging(10)}), LikelyCause::unknown);
  EXPECT_EQ(check_physical(garbled, one_percent(garbled), t).cause, LikelyCause::unknown);
  // 1.4 s: too short.
  const RecordingEvidence short_one = recording_evidence({swinging(1.4)});
  EXPECT_TRUE(short_one.short_recording());
  EXPECT_FALSE(short_one.angles_not_radians());
  EXPECT_EQ(cause({swinging(1.4)}), LikelyCause::too_short);
  // One reading of 1e5: a spike, not a unit.
  RawExperiment spiked = swinging(10);
  spiked.q2[300] = 1e5;
  const RecordingEvidence spike = recording_evidence({spiked});
  EXPECT_TRUE(spike.spikes());
  EXPECT_FALSE(spike.angles_not_radians());
  EXPECT_EQ(cause({spiked}), LikelyCause::spike);
  // The same swings in degrees: the arm travels 28.6 "rad", beyond a turn.
  RawExperiment degrees = swinging(10);
  for (double& q : degrees.q1) q *= 180 / M_PI;
  for (double& q : degrees.q2) q *= 180 / M_PI;
  EXPECT_TRUE(recording_evidence({degrees}).angles_not_radians());
  EXPECT_EQ(cause({degrees}), LikelyCause::angle_unit);
  // The warning says "unknown" when nothing was found, and names the check when one was.
  const RecordingEvidence none = recording_evidence({swinging(10)});
  const std::string unknown = physical_warning(
      check_physical(garbled, one_percent(garbled), t, &none), RecordingSource::csv, "it");
  EXPECT_NE(unknown.find("Likely cause: unknown"), std::string::npos) << unknown;
  EXPECT_EQ(unknown.find("Likely cause: the angles' unit"), std::string::npos) << unknown;
  const std::string spiked_text = physical_warning(
      check_physical(garbled, one_percent(garbled), t, &spike), RecordingSource::csv, "it");
  EXPECT_NE(spiked_text.find("jump faster than 80 rad/s"), std::string::npos) << spiked_text;
  EXPECT_EQ(cause_name(LikelyCause::spike), std::string("spike"));
  EXPECT_EQ(cause_name(LikelyCause::too_short), std::string("too short"));
}

// Balance sessions: the duty follows the measured angles, noise included, so least squares is
// biased and may give mug < 0 with mu3 > 0, the pattern of a pendulum zeroed upright and counted
// the other way. On mostly closed-loop recordings that pattern names the loop, not the encoder.
TEST(PhysicalCheck, OnClosedLoopRecordingsTheCauseIsTheLoopNotARecordingMistake) {
  const P t = truth();
  P biased = t;
  biased.mug = -0.4 * t.mug;
  RecordingEvidence open_loop = recording_evidence({swinging(30)});
  EXPECT_FALSE(open_loop.closed_loop());
  EXPECT_EQ(check_physical(biased, one_percent(t), t, &open_loop).cause,
            LikelyCause::pendulum_zero_and_sign);

  RecordingEvidence closed = open_loop;
  closed.closed_loop_share = 0.8;
  EXPECT_TRUE(closed.closed_loop());
  const PhysicalCheck c = check_physical(biased, one_percent(t), t, &closed);
  EXPECT_EQ(c.cause, LikelyCause::closed_loop);
  EXPECT_EQ(c.candidates, std::vector<LikelyCause>{LikelyCause::closed_loop});
  EXPECT_EQ(cause_name(LikelyCause::closed_loop), std::string("closed loop"));
  const std::string text = physical_warning(c, RecordingSource::session_log, "it");
  EXPECT_NE(text.find("Likely cause: closed-loop data"), std::string::npos) << text;
  EXPECT_NE(text.find("least squares on it is biased"), std::string::npos) << text;
  EXPECT_NE(text.find("The output-error fit, which simulates the model with the applied duty, is "
                      "the estimate to use"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("zero upright"), std::string::npos) << text;
  EXPECT_EQ(text.find("[encoders.pendulum]"), std::string::npos) << text;
  EXPECT_EQ(text.find("--diagnose"), std::string::npos) << "no recording mistake to refit";

  // What the recordings themselves show still stands beside the loop.
  RecordingEvidence closed_short = recording_evidence({swinging(1.4)});
  closed_short.closed_loop_share = 1.0;
  EXPECT_EQ(check_physical(biased, one_percent(t), t, &closed_short).candidates,
            (std::vector<LikelyCause>{LikelyCause::closed_loop, LikelyCause::too_short}));
  // Half the samples or fewer in closed loop: the open-loop causes as before.
  RecordingEvidence half = open_loop;
  half.closed_loop_share = 0.5;
  EXPECT_EQ(check_physical(biased, one_percent(t), t, &half).cause,
            LikelyCause::pendulum_zero_and_sign);
  // A consistent estimate has no cause, closed loop or not.
  EXPECT_EQ(check_physical(t, one_percent(t), t, &closed).cause, LikelyCause::none);
}

}  // namespace
}  // namespace furuta::identification
