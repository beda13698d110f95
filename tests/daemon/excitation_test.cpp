#include "furuta/daemon/excitation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "allocation_counter.hpp"

namespace furuta::daemon::excitation_test {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = std::numbers::pi;

constexpr ProfileKind kAllProfiles[] = {ProfileKind::bang_bang, ProfileKind::free_decay,
                                        ProfileKind::step,      ProfileKind::prbs,
                                        ProfileKind::chirp,     ProfileKind::multisine};

ExcitationSpec spec_of(ProfileKind kind, std::uint64_t seed = 1) {
  ExcitationSpec spec;
  spec.kind = kind;
  spec.seed = seed;
  spec.amplitude_duty = 0.3;
  spec.duration_s = 10.0;
  spec.switch_period_s = 0.5;
  spec.switch_period_jitter = 0.4;
  spec.arm_switch_rad = 0.8;
  return spec;
}

// An arm angle that wanders past the bang-bang thresholds now and then.
double wandering_arm(double t) {
  return 1.2 * std::sin(0.7 * t) + 0.3 * std::sin(5.1 * t);
}

// Duty at t = k * step for k = 0.. while t < end, from a fresh excitation.
std::vector<double> run(const ExcitationSpec& spec, double step, double end,
                        const std::function<double(double)>& arm = wandering_arm) {
  Excitation excitation(spec);
  std::vector<double> out;
  for (std::int64_t k = 0;; ++k) {
    const double t = static_cast<double>(k) * step;
    if (t >= end) break;
    out.push_back(excitation.duty(t, arm(t)));
  }
  return out;
}

// The message of the invalid_argument the constructor throws, or "" when it accepts the spec.
std::string rejection(const ExcitationSpec& spec) {
  try {
    Excitation excitation(spec);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

bool starts_with(const std::string& text, const std::string& prefix) {
  return text.rfind(prefix, 0) == 0;
}

TEST(ProfileKind, NamesRoundTripAndUnknownNamesDoNotParse) {
  for (auto kind : kAllProfiles) {
    const auto parsed = parse_profile_kind(to_string(kind));
    ASSERT_TRUE(parsed.has_value()) << to_string(kind);
    EXPECT_EQ(*parsed, kind);
  }
  EXPECT_EQ(to_string(ProfileKind::bang_bang), "bang_bang");
  EXPECT_EQ(to_string(ProfileKind::multisine), "multisine");
  EXPECT_FALSE(parse_profile_kind("").has_value());
  EXPECT_FALSE(parse_profile_kind("BANG_BANG").has_value());
  EXPECT_FALSE(parse_profile_kind("bang_bang ").has_value());
  EXPECT_FALSE(parse_profile_kind("sine").has_value());
}

struct BadSpec {
  std::string name;
  std::function<void(ExcitationSpec&)> change;
  std::string field;
};

TEST(ExcitationSpec, EveryInvalidFieldIsRejectedByName) {
  using K = ProfileKind;
  const auto kind = [](K k) { return [k](ExcitationSpec& s) { s.kind = k; }; };
  const std::vector<BadSpec> cases = {
      {"amplitude 0", [](auto& s) { s.amplitude_duty = 0.0; }, "amplitude_duty"},
      {"amplitude negative", [](auto& s) { s.amplitude_duty = -0.1; }, "amplitude_duty"},
      {"amplitude above 1", [](auto& s) { s.amplitude_duty = 1.0000001; }, "amplitude_duty"},
      {"amplitude nan", [](auto& s) { s.amplitude_duty = kNan; }, "amplitude_duty"},
      {"amplitude inf", [](auto& s) { s.amplitude_duty = kInf; }, "amplitude_duty"},
      {"duration 0", [](auto& s) { s.duration_s = 0.0; }, "duration_s"},
      {"duration negative", [](auto& s) { s.duration_s = -1.0; }, "duration_s"},
      {"duration nan", [](auto& s) { s.duration_s = kNan; }, "duration_s"},
      {"duration inf", [](auto& s) { s.duration_s = kInf; }, "duration_s"},
      {"duration huge", [](auto& s) { s.duration_s = 1e300; }, "duration_s"},
      {"kind out of range", [](auto& s) { s.kind = static_cast<K>(42); }, "kind"},
      {"period negative", [](auto& s) { s.switch_period_s = -0.5; }, "switch_period_s"},
      {"period nan", [](auto& s) { s.switch_period_s = kNan; }, "switch_period_s"},
      {"period inf", [](auto& s) { s.switch_period_s = kInf; }, "switch_period_s"},
      {"period tiny", [](auto& s) { s.switch_period_s = 1e-9; }, "switch_period_s"},
      {"jitter negative", [](auto& s) { s.switch_period_jitter = -0.1; }, "switch_period_jitter"},
      {"jitter 1", [](auto& s) { s.switch_period_jitter = 1.0; }, "switch_period_jitter"},
      {"jitter nan", [](auto& s) { s.switch_period_jitter = kNan; }, "switch_period_jitter"},
      {"threshold negative", [](auto& s) { s.arm_switch_rad = -0.1; }, "arm_switch_rad"},
      {"threshold nan", [](auto& s) { s.arm_switch_rad = kNan; }, "arm_switch_rad"},
      {"threshold inf", [](auto& s) { s.arm_switch_rad = kInf; }, "arm_switch_rad"},
      {"nothing to switch on",
       [](auto& s) {
         s.switch_period_s = 0.0;
         s.arm_switch_rad = 0.0;
       },
       "switch_period_s"},
      {"step time negative",
       [&](auto& s) {
         kind(K::step)(s);
         s.step_time_s = -0.1;
       },
       "step_time_s"},
      {"step time nan",
       [&](auto& s) {
         kind(K::step)(s);
         s.step_time_s = kNan;
       },
       "step_time_s"},
      {"step at the end",
       [&](auto& s) {
         kind(K::step)(s);
         s.step_time_s = s.duration_s;
       },
       "step_time_s"},
      {"prbs order 1",
       [&](auto& s) {
         kind(K::prbs)(s);
         s.prbs_order = 1;
       },
       "prbs_order"},
      {"prbs order 17",
       [&](auto& s) {
         kind(K::prbs)(s);
         s.prbs_order = 17;
       },
       "prbs_order"},
      {"prbs bit period 0",
       [&](auto& s) {
         kind(K::prbs)(s);
         s.prbs_bit_period_s = 0.0;
       },
       "prbs_bit_period_s"},
      {"prbs bit period nan",
       [&](auto& s) {
         kind(K::prbs)(s);
         s.prbs_bit_period_s = kNan;
       },
       "prbs_bit_period_s"},
      {"prbs bit period tiny",
       [&](auto& s) {
         kind(K::prbs)(s);
         s.prbs_bit_period_s = 1e-12;
       },
       "prbs_bit_period_s"},
      {"chirp f0 negative",
       [&](auto& s) {
         kind(K::chirp)(s);
         s.chirp_f0_hz = -1.0;
       },
       "chirp_f0_hz"},
      {"chirp f1 nan",
       [&](auto& s) {
         kind(K::chirp)(s);
         s.chirp_f1_hz = kNan;
       },
       "chirp_f1_hz"},
      {"chirp f1 inf",
       [&](auto& s) {
         kind(K::chirp)(s);
         s.chirp_f1_hz = kInf;
       },
       "chirp_f1_hz"},
      {"multisine no components",
       [&](auto& s) {
         kind(K::multisine)(s);
         s.multisine_components = 0;
       },
       "multisine_components"},
      {"multisine 17 components",
       [&](auto& s) {
         kind(K::multisine)(s);
         s.multisine_components = 17;
       },
       "multisine_components"},
      {"multisine f_min 0",
       [&](auto& s) {
         kind(K::multisine)(s);
         s.multisine_f_min_hz = 0.0;
       },
       "multisine_f_min_hz"},
      {"multisine f_min nan",
       [&](auto& s) {
         kind(K::multisine)(s);
         s.multisine_f_min_hz = kNan;
       },
       "multisine_f_min_hz"},
      {"multisine f_max below f_min",
       [&](auto& s) {
         kind(K::multisine)(s);
         s.multisine_f_max_hz = 0.1;
       },
       "multisine_f_max_hz"},
      {"multisine f_max inf",
       [&](auto& s) {
         kind(K::multisine)(s);
         s.multisine_f_max_hz = kInf;
       },
       "multisine_f_max_hz"},
  };
  for (const auto& c : cases) {
    ExcitationSpec spec = spec_of(ProfileKind::bang_bang);
    c.change(spec);
    const std::string message = rejection(spec);
    EXPECT_TRUE(starts_with(message, c.field + ": ")) << c.name << ": \"" << message << "\"";
  }
}

TEST(ExcitationSpec, MessagesSayTheRuleAndTheValue) {
  ExcitationSpec spec = spec_of(ProfileKind::free_decay);
  spec.amplitude_duty = 1.5;
  EXPECT_EQ(rejection(spec), "amplitude_duty: must be in (0, 1], got 1.5");
  spec = spec_of(ProfileKind::prbs);
  spec.prbs_order = 20;
  EXPECT_EQ(rejection(spec), "prbs_order: must be in 2..16, got 20");
  spec = spec_of(ProfileKind::bang_bang);
  spec.switch_period_s = 0.0;
  spec.arm_switch_rad = 0.0;
  EXPECT_NE(rejection(spec).find("arm_switch_rad"), std::string::npos) << rejection(spec);
}

TEST(ExcitationSpec, OnlyTheChosenProfilesParametersAreChecked) {
  ExcitationSpec spec = spec_of(ProfileKind::free_decay);
  spec.prbs_order = 99;
  spec.switch_period_s = -1.0;
  spec.multisine_components = 0;
  spec.chirp_f0_hz = kNan;
  spec.step_time_s = 1e9;
  EXPECT_EQ(rejection(spec), "");
  spec.kind = ProfileKind::prbs;
  EXPECT_TRUE(starts_with(rejection(spec), "prbs_order: "));
}

TEST(ExcitationSpec, EdgesOfTheValidRangesAreAccepted) {
  ExcitationSpec spec = spec_of(ProfileKind::bang_bang);
  spec.amplitude_duty = 1.0;
  spec.switch_period_jitter = 0.999;
  EXPECT_EQ(rejection(spec), "");
  spec.switch_period_s = 0.0;  // thresholds only
  EXPECT_EQ(rejection(spec), "");
  spec.switch_period_s = 0.5;
  spec.arm_switch_rad = 0.0;  // timer only
  EXPECT_EQ(rejection(spec), "");
  spec = spec_of(ProfileKind::step);
  spec.step_time_s = 0.0;
  EXPECT_EQ(rejection(spec), "");
  for (int order : {2, 16}) {
    spec = spec_of(ProfileKind::prbs);
    spec.prbs_order = order;
    EXPECT_EQ(rejection(spec), "") << order;
  }
  spec = spec_of(ProfileKind::multisine);
  spec.multisine_components = 1;
  spec.multisine_f_max_hz = spec.multisine_f_min_hz;  // irrelevant with a single component
  EXPECT_EQ(rejection(spec), "");
  spec.multisine_components = 16;
  spec.multisine_f_max_hz = 5.0;
  EXPECT_EQ(rejection(spec), "");
}

TEST(Excitation, EveryProfileStaysWithinTheAmplitudeForEverySeed) {
  for (auto kind : kAllProfiles) {
    for (std::uint64_t seed : {1ULL, 2ULL, 7ULL, 12345ULL, 0xFFFFFFFFFFFFFFFFULL}) {
      for (double amplitude : {0.05, 0.3, 1.0}) {
        ExcitationSpec spec = spec_of(kind, seed);
        spec.amplitude_duty = amplitude;
        for (double step : {0.016, 0.001, 0.0003}) {
          double peak = 0.0;
          for (double d : run(spec, step, spec.duration_s)) {
            ASSERT_TRUE(std::isfinite(d));
            ASSERT_LE(std::fabs(d), amplitude) << to_string(kind) << " seed " << seed;
            peak = std::max(peak, std::fabs(d));
          }
          if (kind != ProfileKind::free_decay) {
            EXPECT_GT(peak, 0.9 * amplitude) << to_string(kind);
          }
        }
      }
    }
  }
}

TEST(Excitation, DutyIsZeroBeforeTheStartAtAndPastTheDurationAndForNanTime) {
  for (auto kind : kAllProfiles) {
    Excitation early(spec_of(kind));
    EXPECT_EQ(early.duty(-1.0, 0.0), 0.0) << to_string(kind);
    EXPECT_EQ(early.duty(kNan, 0.0), 0.0) << to_string(kind);
    Excitation excitation(spec_of(kind));
    const double duration = excitation.spec().duration_s;
    for (double t = 0.0; t < duration; t += 0.016) excitation.duty(t, 0.0);
    EXPECT_FALSE(excitation.finished(std::nextafter(duration, 0.0)));
    EXPECT_TRUE(excitation.finished(duration));
    EXPECT_EQ(excitation.duty(duration, 0.0), 0.0) << to_string(kind);
    EXPECT_EQ(excitation.duty(duration + 0.016, 5.0), 0.0) << to_string(kind);
    EXPECT_EQ(excitation.duty(1e12, -5.0), 0.0) << to_string(kind);
    EXPECT_EQ(excitation.duty(kInf, 0.0), 0.0) << to_string(kind);
  }
}

TEST(Excitation, TheSameSeedGivesTheSameSessionAndSeedsDiffer) {
  for (auto kind : kAllProfiles) {
    EXPECT_EQ(run(spec_of(kind, 5), 0.016, 10.0), run(spec_of(kind, 5), 0.016, 10.0))
        << to_string(kind);
  }
  // Seeds matter where there is randomness: the jittered timer and the PRBS starting state.
  EXPECT_NE(run(spec_of(ProfileKind::bang_bang, 5), 0.016, 10.0),
            run(spec_of(ProfileKind::bang_bang, 6), 0.016, 10.0));
  EXPECT_NE(run(spec_of(ProfileKind::prbs, 5), 0.016, 10.0),
            run(spec_of(ProfileKind::prbs, 6), 0.016, 10.0));
}

TEST(Excitation, FreeDecayIsZeroAndStepSwitchesOnAtItsTime) {
  for (double d : run(spec_of(ProfileKind::free_decay), 0.001, 10.0)) ASSERT_EQ(d, 0.0);
  ExcitationSpec spec = spec_of(ProfileKind::step);
  spec.step_time_s = 0.5;
  Excitation step(spec);
  EXPECT_EQ(step.duty(0.0, 0.0), 0.0);
  EXPECT_EQ(step.duty(std::nextafter(0.5, 0.0), 0.0), 0.0);
  EXPECT_EQ(step.duty(0.5, 0.0), 0.3);
  EXPECT_EQ(step.duty(9.99, 3.0), 0.3);
}

// --- bang-bang ---

TEST(BangBang, FixedPeriodStartsPositiveAndFlipsEveryPeriod) {
  ExcitationSpec spec = spec_of(ProfileKind::bang_bang);
  spec.switch_period_s = 0.5;
  spec.switch_period_jitter = 0.0;
  spec.arm_switch_rad = 0.0;
  Excitation excitation(spec);
  for (int k = 0; k < 10000; ++k) {
    const double t = (k + 0.5) * 1e-3;  // between boundaries, away from rounding questions
    const int period = k / 500;
    ASSERT_EQ(excitation.duty(t, 100.0), period % 2 == 0 ? 0.3 : -0.3) << t;
  }
  Excitation at_edges(spec);
  EXPECT_EQ(at_edges.duty(0.0, 0.0), 0.3);
  EXPECT_EQ(at_edges.duty(std::nextafter(0.5, 0.0), 0.0), 0.3);
  EXPECT_EQ(at_edges.duty(0.5, 0.0), -0.3);
  EXPECT_EQ(at_edges.duty(1.0, 0.0), 0.3);
}

TEST(BangBang, SkippedCyclesKeepTheSchedule) {
  ExcitationSpec spec = spec_of(ProfileKind::bang_bang);
  spec.switch_period_jitter = 0.0;
  spec.arm_switch_rad = 0.0;
  Excitation excitation(spec);
  EXPECT_EQ(excitation.duty(0.1, 0.0), 0.3);
  EXPECT_EQ(excitation.duty(1.1, 0.0), 0.3);   // two periods elapsed: two flips
  EXPECT_EQ(excitation.duty(1.6, 0.0), -0.3);  // one more
  EXPECT_EQ(excitation.duty(3.2, 0.0), 0.3);   // 2.0, 2.5 and 3.0 elapsed: three flips
  EXPECT_EQ(excitation.duty(5.2, 0.0), 0.3);   // 3.5 .. 5.0: four flips
}

// Times at which the sign changed, sampling every dt with the arm at the centre.
std::vector<double> switch_times(const ExcitationSpec& spec, double dt) {
  Excitation excitation(spec);
  std::vector<double> times;
  double last = excitation.duty(0.0, 0.0);
  for (std::int64_t k = 1;; ++k) {
    const double t = static_cast<double>(k) * dt;
    if (t >= spec.duration_s) break;
    const double d = excitation.duty(t, 0.0);
    if (d != last) times.push_back(t);
    last = d;
  }
  return times;
}

TEST(BangBang, JitteredPeriodsAreDrawnAcrossTheRange) {
  ExcitationSpec spec = spec_of(ProfileKind::bang_bang, 3);
  spec.switch_period_s = 0.5;
  spec.switch_period_jitter = 0.5;
  spec.arm_switch_rad = 0.0;
  spec.duration_s = 200.0;
  const double dt = 1e-4;
  const auto times = switch_times(spec, dt);
  ASSERT_GT(times.size(), 300U);
  double shortest = 1e9;
  double longest = 0.0;
  double sum = times[0];
  EXPECT_GE(times[0], 0.25 - dt);
  EXPECT_LE(times[0], 0.75 + dt);
  for (std::size_t i = 1; i < times.size(); ++i) {
    const double interval = times[i] - times[i - 1];
    shortest = std::min(shortest, interval);
    longest = std::max(longest, interval);
    sum += interval;
  }
  EXPECT_GE(shortest, 0.25 - 2 * dt);
  EXPECT_LE(longest, 0.75 + 2 * dt);
  EXPECT_LT(shortest, 0.3);  // uniform over the range: the ends are reached
  EXPECT_GT(longest, 0.7);
  EXPECT_NEAR(sum / static_cast<double>(times.size()), 0.5, 0.03);
}

TEST(BangBang, ThresholdsAloneSwitchWhenTheArmGoesBeyondThem) {
  ExcitationSpec spec = spec_of(ProfileKind::bang_bang);
  spec.switch_period_s = 0.0;
  spec.arm_switch_rad = 0.3;
  spec.duration_s = 100.0;
  Excitation excitation(spec);
  double t = 0.0;
  const auto at = [&](double arm) { return excitation.duty(t += 0.016, arm); };
  EXPECT_EQ(at(0.0), 0.3);
  EXPECT_EQ(at(0.3), 0.3);  // exactly at the threshold is not beyond it
  EXPECT_EQ(at(0.3001), -0.3);
  EXPECT_EQ(at(0.5), -0.3);
  EXPECT_EQ(at(0.0), -0.3);  // back inside: keeps going the same way
  EXPECT_EQ(at(-0.3), -0.3);
  EXPECT_EQ(at(-0.31), 0.3);
  EXPECT_EQ(at(-0.2), 0.3);
  EXPECT_EQ(at(kNan), 0.3);  // an unknown angle switches nothing (the supervisor stops on it)
  EXPECT_EQ(at(kInf), -0.3);
  EXPECT_EQ(at(-kInf), 0.3);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(at(0.1), 0.3);  // no timer: nothing else switches
}

TEST(BangBang, AnArmStartingBeyondAThresholdIsPushedBack) {
  ExcitationSpec spec = spec_of(ProfileKind::bang_bang);
  spec.arm_switch_rad = 0.3;
  Excitation excitation(spec);
  EXPECT_EQ(excitation.duty(0.0, 0.4), -0.3);
}

TEST(BangBang, AThresholdOverridesTheTimerAndRestartsIt) {
  ExcitationSpec spec = spec_of(ProfileKind::bang_bang);
  spec.switch_period_s = 1.0;
  spec.switch_period_jitter = 0.0;
  spec.arm_switch_rad = 0.3;
  Excitation excitation(spec);
  EXPECT_EQ(excitation.duty(0.0, 0.0), 0.3);
  EXPECT_EQ(excitation.duty(0.4, 0.35), -0.3);  // threshold: timer restarts, next switch at 1.4
  EXPECT_EQ(excitation.duty(1.0, 0.0), -0.3);   // the old schedule's switch does not happen
  EXPECT_EQ(excitation.duty(1.39, 0.0), -0.3);
  EXPECT_EQ(excitation.duty(1.4, 0.0), 0.3);  // a full period after the threshold switch
  EXPECT_EQ(excitation.duty(2.0, 0.0), 0.3);
  // The timer flips at 2.4, but the arm is beyond -0.3: the duty keeps pointing back (+).
  EXPECT_EQ(excitation.duty(2.4, -0.5), 0.3);
  EXPECT_EQ(excitation.duty(3.0, -0.2), 0.3);
  EXPECT_EQ(excitation.duty(3.4, -0.2), -0.3);  // restarted at 2.4: next switch at 3.4
}

TEST(BangBang, WithThresholdsTheDutyAlwaysPointsBackAndTheArmStaysNear) {
  // A toy arm: duty drives its acceleration against viscous friction.
  for (std::uint64_t seed : {1ULL, 2ULL, 3ULL}) {
    ExcitationSpec spec = spec_of(ProfileKind::bang_bang, seed);
    spec.duration_s = 120.0;
    spec.switch_period_s = 0.7;
    spec.switch_period_jitter = 0.5;
    spec.arm_switch_rad = 0.5;
    Excitation excitation(spec);
    double q = 0.0;
    double dq = 0.0;
    double widest = 0.0;
    int beyond = 0;
    for (int k = 0; k * 0.016 < spec.duration_s; ++k) {
      const double d = excitation.duty(k * 0.016, q);
      if (q > spec.arm_switch_rad) {
        ASSERT_LT(d, 0.0) << "k " << k;
        ++beyond;
      }
      if (q < -spec.arm_switch_rad) {
        ASSERT_GT(d, 0.0) << "k " << k;
        ++beyond;
      }
      dq += 0.016 * (20.0 * d - 2.0 * dq);
      q += 0.016 * dq;
      widest = std::max(widest, std::fabs(q));
    }
    EXPECT_GT(beyond, 0);  // the thresholds were actually exercised
    EXPECT_LT(widest, 1.5);
  }
}

// --- PRBS ---

// One value per bit, sampled mid-bit, as +1 / 0.
std::vector<int> prbs_bits(int order, std::uint64_t seed, std::size_t count) {
  ExcitationSpec spec = spec_of(ProfileKind::prbs, seed);
  spec.prbs_order = order;
  spec.prbs_bit_period_s = 0.01;
  spec.duration_s = 0.01 * static_cast<double>(count + 1);
  Excitation excitation(spec);
  std::vector<int> bits;
  for (std::size_t k = 0; k < count; ++k) {
    const double d = excitation.duty((static_cast<double>(k) + 0.5) * 0.01, 0.0);
    EXPECT_EQ(std::fabs(d), 0.3);
    bits.push_back(d > 0 ? 1 : 0);
  }
  return bits;
}

TEST(Prbs, EveryOrderIsMaximalLength) {
  for (int order = 2; order <= 16; ++order) {
    const std::size_t period = (std::size_t{1} << order) - 1;
    const auto bits = prbs_bits(order, 1, 2 * period);
    // Periodic with 2^n - 1 ...
    for (std::size_t k = 0; k < period; ++k) ASSERT_EQ(bits[k], bits[k + period]) << order;
    // ... and every non-zero n-bit state appears once in a period: nothing shorter, nothing missed.
    std::set<std::uint32_t> windows;
    std::size_t ones = 0;
    for (std::size_t k = 0; k < period; ++k) {
      std::uint32_t window = 0;
      for (int b = 0; b < order; ++b)
        window = (window << 1) | static_cast<std::uint32_t>(bits[k + b]);
      windows.insert(window);
      ones += static_cast<std::size_t>(bits[k]);
    }
    EXPECT_EQ(windows.size(), period) << "order " << order;
    EXPECT_EQ(windows.count(0U), 0U) << "order " << order;
    EXPECT_EQ(ones, (period + 1) / 2) << "order " << order;  // balanced: one more +1 than -1
    for (std::size_t d = 1; d < period; ++d) {
      if (period % d != 0) continue;
      bool repeats = true;
      for (std::size_t k = 0; k + d < 2 * period && repeats; ++k) repeats = bits[k] == bits[k + d];
      EXPECT_FALSE(repeats) << "order " << order << " repeats every " << d;
    }
  }
}

TEST(Prbs, ValuesHoldForABitAndSeedsShiftTheSequence) {
  ExcitationSpec spec = spec_of(ProfileKind::prbs);
  spec.prbs_order = 5;
  spec.prbs_bit_period_s = 0.048;
  Excitation excitation(spec);
  // Three loop cycles of 16 ms per bit: all three see the same value.
  for (int bit = 0; bit < 100; ++bit) {
    const double first = excitation.duty(bit * 0.048 + 0.001, 0.0);
    EXPECT_EQ(excitation.duty(bit * 0.048 + 0.017, 0.0), first);
    EXPECT_EQ(excitation.duty(bit * 0.048 + 0.033, 0.0), first);
  }
  const auto a = prbs_bits(7, 1, 127);
  const auto b = prbs_bits(7, 99, 254);
  bool found_shift = false;
  for (std::size_t shift = 0; shift < 127 && !found_shift; ++shift) {
    found_shift = std::equal(a.begin(), a.end(), b.begin() + static_cast<std::ptrdiff_t>(shift));
  }
  EXPECT_TRUE(found_shift);  // another seed: the same sequence from another starting state
}

// --- chirp and multisine ---

// The sweep's phase at time t, without the seed's starting phase.
double sweep_phase(double t) {
  return 2 * kPi * (0.5 * t + (4.0 - 0.5) * t * t / (2 * 20.0));
}

TEST(Chirp, FollowsTheLinearSweepFromTheSeedsStartingPhase) {
  ExcitationSpec spec = spec_of(ProfileKind::chirp);
  spec.chirp_f0_hz = 0.5;
  spec.chirp_f1_hz = 4.0;
  spec.duration_s = 20.0;
  std::vector<double> starts;
  for (std::uint64_t seed : {1, 2, 1}) {
    spec.seed = seed;
    Excitation excitation(spec);
    // The starting phase from the first two values: sin from the first, cos from the step.
    const double d0 = excitation.duty(0.0, 0.0) / 0.3;
    const double d1 = excitation.duty(1e-3, 0.0) / 0.3;
    const double w = sweep_phase(1e-3);
    const double start = std::atan2(d0, (d1 - d0 * std::cos(w)) / std::sin(w));
    starts.push_back(start);
    int crossings = 0;
    double last = 0.0;
    for (int k = 0; k < 20000; ++k) {
      const double t = k * 1e-3;
      const double d = excitation.duty(t, 0.0);
      ASSERT_NEAR(d, 0.3 * std::sin(sweep_phase(t) + start), 1e-9) << t;
      if (k > 0 && (d > 0) != (last > 0)) ++crossings;
      last = d;
    }
    // The phase runs through 2 * (f0 + f1) / 2 * T = 45 cycles: 90 sign changes.
    EXPECT_NEAR(crossings, 90, 1);
  }
  EXPECT_GT(std::abs(std::remainder(starts[0] - starts[1], 2 * kPi)), 1e-3);  // another seed
  EXPECT_DOUBLE_EQ(starts[0], starts[2]);                                     // the same seed
}

TEST(Multisine, PeakEqualsTheAmplitudeAndIsNeverExceeded) {
  for (int components : {1, 2, 3, 8, 16}) {
    for (double duration : {1.0, 10.0, 60.0}) {
      ExcitationSpec spec = spec_of(ProfileKind::multisine);
      spec.multisine_components = components;
      spec.duration_s = duration;
      spec.amplitude_duty = 0.4;
      double peak = 0.0;
      for (double d : run(spec, 1e-4, duration)) {
        ASSERT_LE(std::fabs(d), 0.4);
        peak = std::max(peak, std::fabs(d));
      }
      EXPECT_GT(peak, 0.4 * 0.999) << components << " components over " << duration << " s";
    }
  }
}

// The seed shifts the signal in time (by tau), which adds 2 pi f tau to each Schroeder phase: with
// components at 0.5 * 2^k Hz, component k's shift is 2^k times the first one's.
TEST(Multisine, ComponentsAreLogSpacedWithEqualAmplitudesAndShiftedSchroederPhases) {
  ExcitationSpec spec = spec_of(ProfileKind::multisine);
  spec.multisine_components = 4;
  spec.multisine_f_min_hz = 0.5;
  spec.multisine_f_max_hz = 4.0;  // 0.5, 1, 2, 4 Hz
  spec.duration_s = 64.0;         // whole periods of every component: no leakage between them
  const double dt = 1e-3;
  const auto duty = run(spec, dt, spec.duration_s);
  const double freqs[] = {0.5, 1.0, 2.0, 4.0};
  double first_magnitude = 0.0;
  double first_shift = 0.0;
  for (int k = 0; k < 4; ++k) {
    std::complex<double> c = 0.0;
    for (std::size_t i = 0; i < duty.size(); ++i) {
      c += duty[i] * std::polar(1.0, -2 * kPi * freqs[k] * static_cast<double>(i) * dt);
    }
    c *= 2.0 / static_cast<double>(duty.size());
    // sin(w t + phi) projects to exp(i (phi - pi/2)).
    const double index = k + 1;
    const double schroeder = -kPi * index * (index - 1) / 4;
    const double shift = std::remainder(std::arg(c) - (schroeder - kPi / 2), 2 * kPi);
    if (k == 0) first_shift = shift;
    EXPECT_NEAR(std::remainder(shift - std::pow(2.0, k) * first_shift, 2 * kPi), 0.0, 1e-3)
        << freqs[k] << " Hz";
    if (k == 0) first_magnitude = std::abs(c);
    EXPECT_NEAR(std::abs(c), first_magnitude, 1e-3 * first_magnitude) << freqs[k] << " Hz";
  }
  EXPECT_GT(first_magnitude, 0.05);
  // Nothing in between: a frequency that is not a component projects to (almost) zero.
  std::complex<double> off = 0.0;
  for (std::size_t i = 0; i < duty.size(); ++i) {
    off += duty[i] * std::polar(1.0, -2 * kPi * 1.5 * static_cast<double>(i) * dt);
  }
  EXPECT_LT(std::abs(off) * 2.0 / static_cast<double>(duty.size()), 1e-3);
}

// --- the real-time contract ---

TEST(Excitation, DutyDoesNotAllocate) {
  for (auto kind : kAllProfiles) {
    Excitation excitation(spec_of(kind));
    double sum = 0.0;
    std::size_t allocations = 0;
    std::size_t deallocations = 0;
    {
      furuta::testing::ScopedAllocationCounter counter;
      for (int k = 0; k < 1000; ++k) sum += excitation.duty(k * 0.016, wandering_arm(k * 0.016));
      allocations = counter.allocations();
      deallocations = counter.deallocations();
    }
    EXPECT_EQ(allocations, 0U) << to_string(kind);
    EXPECT_EQ(deallocations, 0U) << to_string(kind);
    EXPECT_TRUE(std::isfinite(sum));
  }
}

}  // namespace
}  // namespace furuta::daemon::excitation_test
