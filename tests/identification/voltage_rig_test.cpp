// A voltage-driven rig recorded by another logger, end to end: simulated, written as CSV in that
// logger's conventions (degrees, the pendulum measured from upright, the arm's sign flipped,
// jittered time stamps), imported by an import spec with a [motor] table, and identified with the
// DC-motor torque. The estimates must come back to the simulated truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "furuta/identification/csv_import.hpp"
#include "furuta/identification/identify.hpp"
#include "furuta/identification/preprocessing.hpp"
#include "furuta/model/model.hpp"
#include "temp_dir.hpp"

namespace furuta::identification::voltage_rig_test {
namespace {

namespace fs = std::filesystem;
constexpr double kPi = std::numbers::pi;
constexpr double kRadToDeg = 180.0 / kPi;

// Not the paper's rig: a heavier arm and less arm friction, so that with this motor the arm's time
// constant is about 150 ms (mu1 over fv1 plus the back-EMF damping), which 10 ms samples resolve.
model::Parameters<double> truth() {
  model::Parameters<double> p;
  p.mu1 = 3.0e-3;
  p.mu2 = 2.56e-3;
  p.mu3 = 1.2e-3;
  p.mu4 = 1.32e-3;
  p.mug = 7.4e-2;
  p.fv1 = 1.5e-2;
  p.fv2 = 6.4e-4;
  return p;
}

// Back-EMF damping at the arm: gear^2 eff k_t k_e / R = 4.3e-3 N m s.
VoltageMotor motor() {
  VoltageMotor m;
  m.torque_constant_nm_per_a = 0.03;
  m.back_emf_v_s_per_rad = 0.03;
  m.resistance_ohm = 3.0;
  m.gear_ratio = 4.0;
  m.efficiency = 0.9;
  return m;
}

double arm_torque(const VoltageMotor& m, double volts, double dq1) {
  return m.gear_ratio * m.efficiency * m.torque_constant_nm_per_a *
         (volts - m.back_emf_v_s_per_rad * m.gear_ratio * dq1) / m.resistance_ohm;
}

// Six sines from 0.23 to 2.69 Hz around the pendulum's 1.2 Hz: smooth and rich.
struct Multisine {
  static constexpr std::array<double, 6> kHz = {0.23, 0.47, 0.83, 1.27, 1.91, 2.69};
  std::array<double, 6> phase{};
  double amplitude_v = 0;
  double operator()(double t) const {
    double sum = 0;
    for (std::size_t i = 0; i < kHz.size(); ++i) sum += std::sin(2 * kPi * kHz[i] * t + phase[i]);
    return amplitude_v * sum / std::sqrt(static_cast<double>(kHz.size()));
  }
};

constexpr double kPeriod = 0.01;  // the other logger's nominal sample period
constexpr double kStart = 1.25;   // its clock at the first row (kept: not shifted to 0)

struct Recording {
  fs::path csv;
  double first_q1 = 0, first_q2 = 0;  // the truth at the first row (project conventions)
  double max_abs_q2_deg = 0;
};

// Simulates `duration_s` (after 2 s of settling into the excitation) with RK4 steps of at most
// 0.5 ms, the voltage held at each step's midpoint, and writes a row at every sample time
// kStart + k kPeriod + jitter (up to +-0.3 ms: irregular enough for the importer to resample).
Recording record(const fs::path& dir, const std::string& name, const Multisine& u,
                 double duration_s) {
  const model::Parameters<double> p = truth();
  const VoltageMotor m = motor();
  Recording r;
  r.csv = dir / name;
  std::ofstream out(r.csv);
  out << "\"time_s\",\"theta_deg\",\"note\",\"alpha_deg\",\"u_V\"\n" << std::fixed;
  model::PendulumState x;
  double t = kStart - 2.0;
  const auto advance_to = [&](double until) {
    const int steps = static_cast<int>(std::ceil((until - t) / 5e-4 - 1e-9));
    const double h = (until - t) / steps;
    for (int i = 0; i < steps; ++i) {
      const double volts = u(t + h / 2);
      x = model::rk4_step(
          p, x, h, [&](const model::PendulumState& s) { return arm_torque(m, volts, s.dq1); });
      t += h;
    }
    t = until;
  };
  const int rows = static_cast<int>(duration_s / kPeriod);
  for (int k = 0; k < rows; ++k) {
    const double jitter = 3e-4 * std::sin(12.9898 * k + 0.7);
    const double tk = kStart + k * kPeriod + (k == 0 ? 0.0 : jitter);
    advance_to(tk);
    if (k == 0) {
      r.first_q1 = x.q1;
      r.first_q2 = x.q2;
    }
    r.max_abs_q2_deg = std::max(r.max_abs_q2_deg, std::abs(x.q2) * kRadToDeg);
    // The logger's conventions: arm angle positive the other way, pendulum from upright.
    out << std::setprecision(6) << tk << "," << std::setprecision(7) << -x.q1 * kRadToDeg << ",ok,"
        << (x.q2 - kPi) * kRadToDeg << "," << u(tk) << "\n";
  }
  return r;
}

fs::path write_spec(const fs::path& dir) {
  const VoltageMotor m = motor();
  std::ostringstream spec;
  spec << std::setprecision(17) << "[csv]\n"
       << "time = \"time_s\"\ntime_unit = \"s\"\n"
       << "arm_angle = \"theta_deg\"\narm_angle_scale = -1\n"
       << "pendulum_angle = \"alpha_deg\"\nangle_unit = \"deg\"\npendulum_zero = \"up\"\n"
       << "input = \"u_V\"\ninput_kind = \"voltage\"\n"
       << "\n[motor]\n"
       << "torque_constant_nm_per_a = " << m.torque_constant_nm_per_a << "\n"
       << "back_emf_v_s_per_rad = " << m.back_emf_v_s_per_rad << "\n"
       << "resistance_ohm = " << m.resistance_ohm << "\n"
       << "gear_ratio = " << m.gear_ratio << "\n"
       << "efficiency = " << m.efficiency << "\n";
  const fs::path path = dir / "import.toml";
  std::ofstream(path) << spec.str();
  return path;
}

// Filters for 100 Hz: stop band 20 Hz below the 50 Hz Nyquist frequency.
IdentifyOptions options_for_10ms() {
  IdentifyOptions o;
  o.preprocess.cutoff_hz = 10.0;
  o.preprocess.differentiator_passband_hz = 10.0;
  o.preprocess.differentiator_stopband_hz = 20.0;
  o.estimate_input_lag = false;
  return o;
}

TEST(VoltageRig, CsvFromAnotherLoggerRecoversTheParameters) {
  testing::TempDir dir;
  const Multisine a{{0.0, 1.1, 2.5, 0.4, 3.9, 5.2}, 3.5};
  const Multisine b{{4.0, 0.3, 1.7, 2.9, 0.8, 3.3}, 3.5};
  const Multisine c{{2.2, 5.0, 0.9, 4.4, 1.6, 0.1}, 3.5};
  const Recording fit_a = record(dir.path(), "a.csv", a, 20.0);
  const Recording fit_b = record(dir.path(), "b.csv", b, 20.0);
  const Recording held_out = record(dir.path(), "c.csv", c, 10.0);
  for (const Recording* r : {&fit_a, &fit_b, &held_out}) {
    std::printf("[ measured ] %s: pendulum up to %.0f deg from hanging\n",
                r->csv.filename().c_str(), r->max_abs_q2_deg);
    EXPECT_GT(r->max_abs_q2_deg, 45.0);   // it swings
    EXPECT_LT(r->max_abs_q2_deg, 120.0);  // but stays clear of swinging over
  }

  const CsvImportSpec spec = load_csv_import_spec(write_spec(dir.path()));
  ASSERT_TRUE(spec.voltage_motor.has_value());
  EXPECT_DOUBLE_EQ(spec.voltage_motor->resistance_ohm, motor().resistance_ohm);
  EXPECT_DOUBLE_EQ(spec.voltage_motor->gear_ratio, motor().gear_ratio);

  std::vector<RawExperiment> experiments;
  for (const Recording* r : {&fit_a, &fit_b}) {
    const ImportedSeries s = import_csv(r->csv, spec);
    // The importer's conventions ran: resampled (jittered stamps), radians, q2 from hanging down,
    // the arm's sign restored, time kept absolute.
    ASSERT_EQ(s.warnings.size(), 1u);
    EXPECT_NE(s.warnings[0].find("resampled"), std::string::npos) << s.warnings[0];
    EXPECT_NEAR(s.sample_period_s, kPeriod, 2e-5);
    EXPECT_DOUBLE_EQ(s.t_s.front(), kStart);
    EXPECT_NEAR(s.q1_rad.front(), r->first_q1, 1e-7);
    EXPECT_NEAR(s.q2_rad.front(), r->first_q2, 1e-7);
    experiments.push_back(experiment_from_csv(s, r->csv.filename().string()));
  }
  const RawExperiment validation =
      experiment_from_csv(import_csv(held_out.csv, spec), held_out.csv.filename().string());

  const Identification id = identify(experiments, validation, options_for_10ms(),
                                     model::MotorData{}, *spec.voltage_motor);
  const model::Parameters<double> expected = truth();
  // mu1, mu3, mu4, mug within 2 %; mu2, fv1, fv2 within 5 %.
  constexpr model::Parameters<double> kBound = {0.02, 0.05, 0.02, 0.02, 0.02, 0.05, 0.05};
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const double estimate = id.combined.estimate[k];
    const double relative = (estimate - expected[k]) / expected[k];
    std::printf("[ measured ] %s %.5e (truth %.5e, %+.2f %%, %.1f sd)\n", model::kParameterNames[k],
                estimate, expected[k], 100 * relative,
                std::abs(estimate - expected[k]) / id.combined.std_dev[k]);
    EXPECT_LT(std::abs(relative), kBound[k]) << model::kParameterNames[k];
  }
  ASSERT_TRUE(id.validation.has_value());
  std::printf("[ measured ] held-out c.csv: torque RMSE %.3e N m = %.2f %% of the range\n",
              id.validation->fit.rmse_nm, id.validation->fit.rmse_percent_of_range);
  EXPECT_LT(id.validation->fit.rmse_percent_of_range, 2.0);
  EXPECT_EQ(id.combined.rank, model::kParameterCount);
}

TEST(VoltageRig, WithoutTheMotorTheVoltageCannotBecomeATorque) {
  testing::TempDir dir;
  const Recording r = record(dir.path(), "a.csv", Multisine{{0, 1, 2, 3, 4, 5}, 3.0}, 2.0);
  const CsvImportSpec spec = load_csv_import_spec(write_spec(dir.path()));
  const RawExperiment e = experiment_from_csv(import_csv(r.csv, spec), "a.csv");
  EXPECT_THROW(preprocess(e, options_for_10ms().preprocess, model::MotorData{}, VoltageMotor{}),
               std::invalid_argument);
}

}  // namespace
}  // namespace furuta::identification::voltage_rig_test
