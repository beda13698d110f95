// The whole LSMI identification as `furuta identify` runs it: two 10 s sessions at 16 ms plus a
// held-out one, preprocessed (Butterworth, filtfilt, FIR differentiator), fitted per experiment and
// combined, and validated. Run: build/release/bench/identification_bench
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "furuta/identification/identify.hpp"
#include "furuta/model/model.hpp"

namespace {

using namespace furuta;

// A session generated from the model (the paper's parameters, eq. 4 motor) without the daemon:
// a smooth six-sine duty of amplitude 0.3, RK4 at 1 ms, sampled every 16 ms for 10 s.
identification::RawExperiment session(double phase, const std::string& name) {
  const furuta::model::Parameters<double> p = furuta::model::paper_run1();
  const furuta::model::MotorData motor;
  constexpr std::array<double, 6> hz = {0.23, 0.47, 0.83, 1.27, 1.91, 2.69};
  const auto duty = [&](double t) {
    double sum = 0;
    for (std::size_t i = 0; i < hz.size(); ++i) {
      sum += std::sin(2 * std::numbers::pi * hz[i] * t + phase * static_cast<double>(i + 1));
    }
    return 0.3 * sum / std::sqrt(6.0);
  };
  identification::RawExperiment e;
  e.name = name;
  e.sample_period_s = 0.016;
  e.input_kind = identification::InputKind::duty;
  furuta::model::PendulumState x;
  constexpr int kStepsPerSample = 16;
  constexpr double h = 1e-3;
  for (int k = 0; k < 625; ++k) {
    const double t = k * e.sample_period_s;
    e.t_s.push_back(t);
    e.q1.push_back(x.q1);
    e.q2.push_back(x.q2);
    e.input.push_back(duty(t));
    for (int s = 0; s < kStepsPerSample; ++s) {
      const double d = duty(t + (s + 0.5) * h);
      x = furuta::model::rk4_step(p, x, h, [&](const furuta::model::PendulumState& state) {
        return motor.arm_torque_nm(d, state.dq1);
      });
    }
  }
  return e;
}

struct Sessions {
  std::vector<identification::RawExperiment> fit;
  identification::RawExperiment held_out;
};
const Sessions& sessions() {
  static const Sessions s{{session(0.0, "s1"), session(1.3, "s2")}, session(2.9, "s3")};
  return s;
}

// The simulated rig's configuration: 15 Hz cut-off, order 8, 31 taps, input lag 2 ms given.
identification::IdentifyOptions options(bool estimate_lag) {
  identification::IdentifyOptions o;
  o.preprocess.cutoff_hz = 15.0;
  o.preprocess.differentiator_passband_hz = 15.0;
  o.preprocess.differentiator_stopband_hz = 30.0;
  o.preprocess.input_lag_s = 2e-3;
  o.estimate_input_lag = estimate_lag;
  return o;
}

// One iteration = identify() of two sessions plus the held-out one (what `furuta identify` spends
// between reading the logs and writing the results). state.range(0): 1 = estimate the input lag
// (--estimate-input-lag, a golden-section search of about 30 LSMI solves).
void BM_IdentifyTwoSessionsPlusHeldOut(benchmark::State& state) {
  const Sessions& s = sessions();
  const identification::IdentifyOptions o = options(state.range(0) != 0);
  const furuta::model::MotorData motor;
  for (auto _ : state) {
    identification::Identification id = identification::identify(s.fit, s.held_out, o, motor);
    benchmark::DoNotOptimize(id.combined.estimate);
  }
  state.SetLabel(state.range(0) ? "estimating the input lag" : "input lag given");
}
BENCHMARK(BM_IdentifyTwoSessionsPlusHeldOut)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The parts: one session's preprocessing, and one LSMI solve over two sessions.
void BM_PreprocessOneSession(benchmark::State& state) {
  const identification::RawExperiment& e = sessions().fit.front();
  const identification::PreprocessOptions o = options(false).preprocess;
  const furuta::model::MotorData motor;
  for (auto _ : state) {
    benchmark::DoNotOptimize(identification::preprocess(e, o, motor).tau.data());
  }
}
BENCHMARK(BM_PreprocessOneSession)->Unit(benchmark::kMillisecond);

void BM_LsmiTwoSessions(benchmark::State& state) {
  const identification::PreprocessOptions o = options(false).preprocess;
  const furuta::model::MotorData motor;
  const identification::JointSeries a = identification::preprocess(sessions().fit[0], o, motor);
  const identification::JointSeries b = identification::preprocess(sessions().fit[1], o, motor);
  identification::LsmiOptions lsmi;
  lsmi.trim_samples = identification::edge_samples(o);
  for (auto _ : state) {
    benchmark::DoNotOptimize(identification::solve_lsmi({&a, &b}, lsmi).estimate);
  }
}
BENCHMARK(BM_LsmiTwoSessions)->Unit(benchmark::kMillisecond);

}  // namespace
