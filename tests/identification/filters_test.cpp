// The preprocessing filters, judged by what they must do: the Butterworth by its frequency response
// against the analytic bilinear-transform magnitude, filtfilt by zero phase and exact treatment of
// constants and ramps, the Remez differentiator by equiripple (alternation) and its achieved
// bounds, and the whole chain on signals whose derivatives are known.
#include "furuta/identification/filters.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <iostream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace furuta::identification::filters_test {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kFs = 62.5;  // the rig's 16 ms loop

// Expects `f` to throw std::invalid_argument whose message names `parameter`.
void expect_invalid(const std::function<void()>& f, const std::string& parameter) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one naming " << parameter;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(parameter), std::string::npos) << e.what();
  }
}

// |H|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^(2N)): the Butterworth through the bilinear
// transform with pre-warping.
double analytic_butterworth(int order, double f, double fc, double fs) {
  const double r = std::tan(kPi * f / fs) / std::tan(kPi * fc / fs);
  return 1.0 / std::sqrt(1.0 + std::pow(r, 2 * order));
}

double db(double magnitude) {
  return 20 * std::log10(magnitude);
}

// ---------------------------------------------------------------------------------------------
// Butterworth

TEST(ButterworthTest, Order8HasHalfPowerAtTheCutoffAndUnitGainBelow) {
  const IirFilter f = design_butterworth_lowpass(8, 5.0, kFs);
  ASSERT_EQ(f.sections.size(), 4u);
  EXPECT_NEAR(std::abs(f.response(5.0, kFs)), 1 / std::sqrt(2.0), 1e-6);
  EXPECT_NEAR(std::abs(f.response(0.0, kFs)), 1.0, 1e-12);
  for (double hz : {0.1, 0.5, 1.0}) EXPECT_NEAR(std::abs(f.response(hz, kFs)), 1.0, 1e-6) << hz;
  // Zeros at z = -1: nothing passes at Nyquist.
  EXPECT_LT(std::abs(f.response(kFs / 2, kFs)), 1e-12);
}

TEST(ButterworthTest, MagnitudeIsMonotonicWithoutRipple) {
  for (int order : {2, 8, 10}) {
    const IirFilter f = design_butterworth_lowpass(order, 5.0, kFs);
    double previous = std::abs(f.response(0.0, kFs));
    for (int i = 1; i <= 3000; ++i) {
      const double m = std::abs(f.response(kFs / 2 * i / 3000.0, kFs));
      ASSERT_LE(m, previous + 1e-13) << "order " << order << " at step " << i;
      previous = m;
    }
  }
}

TEST(ButterworthTest, StopBandAttenuationAtTwiceTheCutoff) {
  const IirFilter f = design_butterworth_lowpass(8, 5.0, kFs);
  const double attenuation = -db(std::abs(f.response(10.0, kFs)));
  const double analytic = -db(analytic_butterworth(8, 10.0, 5.0, kFs));
  // An analogue 8th-order Butterworth gives 10 log10(1 + 2^16) = 48.2 dB one octave up; the
  // bilinear transform's warping (tan) adds to it.
  EXPECT_GT(attenuation, 10 * std::log10(1 + std::pow(2.0, 16)));
  EXPECT_NEAR(attenuation, analytic, 0.1);
  std::cout << "[ measured ] order 8, 5 Hz at 62.5 Hz: " << attenuation << " dB at 10 Hz (analytic "
            << analytic << " dB)\n";
}

TEST(ButterworthTest, MatchesTheAnalyticMagnitudeForOrders1To10AndSeveralCutoffs) {
  double worst = 0;
  for (int order = 1; order <= 10; ++order) {
    for (double cutoff : {0.3, 1.0, 5.0, 12.5, 25.0, 30.0}) {
      const IirFilter f = design_butterworth_lowpass(order, cutoff, kFs);
      ASSERT_EQ(f.sections.size(), static_cast<std::size_t>((order + 1) / 2));
      for (const SecondOrderSection& s : f.sections) {
        // Stable: both poles inside the unit circle (|a2| < 1 and |a1| < 1 + a2).
        EXPECT_LT(std::abs(s.a2), 1.0);
        EXPECT_LT(std::abs(s.a1), 1.0 + s.a2);
      }
      for (int i = 0; i <= 1000; ++i) {
        const double hz = kFs / 2 * i / 1000.0;
        const double error =
            std::abs(std::abs(f.response(hz, kFs)) - analytic_butterworth(order, hz, cutoff, kFs));
        worst = std::max(worst, error);
        ASSERT_LT(error, 1e-6) << "order " << order << ", cut-off " << cutoff << " Hz, at " << hz;
      }
    }
  }
  std::cout << "[ measured ] max |H| error vs analytic, orders 1-10, cut-offs 0.3-30 Hz: " << worst
            << "\n";
}

TEST(ButterworthTest, TheHighestOrderAtTheLowestCutoffKeepsItsShape) {
  // Order 20 at 0.07 Hz: liquid's float gain underflows to 0 and its poles sit within 1e-3 of z
  // = 1.
  const IirFilter f = design_butterworth_lowpass(20, 0.07, kFs);
  EXPECT_NEAR(std::abs(f.response(0.0, kFs)), 1.0, 1e-12);
  EXPECT_NEAR(std::abs(f.response(0.07, kFs)), 1 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(std::abs(f.response(0.14, kFs)), analytic_butterworth(20, 0.14, 0.07, kFs), 1e-9);
  const std::vector<double> x(200, 2.0);
  for (double y : filtfilt(f, x)) ASSERT_NEAR(y, 2.0, 1e-9);
}

TEST(ButterworthTest, RejectsBadArgumentsNamingThem) {
  expect_invalid([] { design_butterworth_lowpass(0, 5, kFs); }, "order");
  expect_invalid([] { design_butterworth_lowpass(-3, 5, kFs); }, "order");
  expect_invalid([] { design_butterworth_lowpass(21, 5, kFs); }, "order");
  expect_invalid([] { design_butterworth_lowpass(8, 0, kFs); }, "cutoff_hz");
  expect_invalid([] { design_butterworth_lowpass(8, -1, kFs); }, "cutoff_hz");
  expect_invalid([] { design_butterworth_lowpass(8, kFs / 2, kFs); }, "cutoff_hz");
  expect_invalid([] { design_butterworth_lowpass(8, 0.05, kFs); }, "cutoff_hz");  // < fs / 1000
  expect_invalid([] { design_butterworth_lowpass(8, NAN, kFs); }, "cutoff_hz");
  expect_invalid([] { design_butterworth_lowpass(8, 5, 0); }, "sample_rate_hz");
  expect_invalid([] { design_butterworth_lowpass(8, 5, INFINITY); }, "sample_rate_hz");
}

// ---------------------------------------------------------------------------------------------
// filtfilt

std::vector<double> sampled(std::size_t n, const std::function<double(double)>& f) {
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = f(static_cast<double>(i) / kFs);
  return x;
}

TEST(FiltfiltTest, KeepsTheInputLength) {
  const IirFilter f = design_butterworth_lowpass(8, 5.0, kFs);
  for (std::size_t n : {0u, 1u, 2u, 5u, 27u, 28u, 1000u}) {
    const std::vector<double> x = sampled(n, [](double t) { return std::sin(3 * t); });
    EXPECT_EQ(filtfilt(f, x).size(), n);
    EXPECT_EQ(filtfilt(f, x, 0).size(), n);
    EXPECT_EQ(filtfilt(f, x, 5000).size(), n);
  }
  const std::vector<double> one{2.5};
  EXPECT_DOUBLE_EQ(filtfilt(f, one)[0], 2.5);
  expect_invalid([&] { filtfilt(f, one, -2); }, "pad");
}

TEST(FiltfiltTest, AConstantComesOutUnchanged) {
  const IirFilter f = design_butterworth_lowpass(8, 5.0, kFs);
  for (double level : {0.0, 3.7, -1234.5}) {
    const std::vector<double> x(500, level);
    for (double y : filtfilt(f, x)) ASSERT_NEAR(y, level, 1e-12 * std::max(1.0, std::abs(level)));
  }
}

TEST(FiltfiltTest, ASinusoidInThePassBandKeepsItsPhaseAndLosesHSquared) {
  const IirFilter f = design_butterworth_lowpass(8, 5.0, kFs);
  for (double hz : {1.0, 4.0, 5.0}) {
    const std::vector<double> x =
        sampled(2000, [&](double t) { return std::sin(2 * kPi * hz * t + 0.3); });
    const std::vector<double> y = filtfilt(f, x);
    const double gain = std::norm(f.response(hz, kFs));  // |H|^2: once forward, once backward
    double worst = 0;
    for (std::size_t i = 300; i + 300 < x.size(); ++i)
      worst = std::max(worst, std::abs(y[i] - gain * x[i]));
    EXPECT_LT(worst, 1e-9) << hz << " Hz";
    // Zero phase: the cross-correlation peaks at lag 0.
    int best_lag = 99;
    double best = -1e300;
    for (int lag = -5; lag <= 5; ++lag) {
      double c = 0;
      for (std::size_t i = 300; i + 300 < x.size(); ++i)
        c += y[i] * x[static_cast<std::size_t>(static_cast<long>(i) + lag)];
      if (c > best) {
        best = c;
        best_lag = lag;
      }
    }
    EXPECT_EQ(best_lag, 0) << hz << " Hz";
  }
  // Far in the stop band, nothing is left.
  const std::vector<double> x = sampled(2000, [](double t) { return std::sin(2 * kPi * 15 * t); });
  const std::vector<double> y = filtfilt(f, x);
  for (std::size_t i = 300; i + 300 < y.size(); ++i) ASSERT_LT(std::abs(y[i]), 1e-7);
}

TEST(FiltfiltTest, ARampIsPreservedIncludingTheEdges) {
  const IirFilter f = design_butterworth_lowpass(8, 5.0, kFs);
  const double slope = 2.0;  // rad/s: a fast arm
  const std::vector<double> x = sampled(625, [&](double t) { return 0.3 + slope * t; });
  // The odd reflection continues the ramp, and each pass starts in a ramp's steady state, so
  // nothing but rounding is left anywhere, whatever the padding.
  for (std::ptrdiff_t pad : {-1, 0, 5, 200}) {
    const std::vector<double> y = filtfilt(f, x, pad);
    double worst = 0;
    for (std::size_t i = 0; i < x.size(); ++i) worst = std::max(worst, std::abs(y[i] - x[i]));
    EXPECT_LT(worst, 1e-11) << "pad " << pad;
    if (pad == -1)
      std::cout << "[ measured ] 2 rad/s ramp through filtfilt: max error " << worst << " rad\n";
  }
}

TEST(FiltfiltTest, AStepResponseIsSymmetric) {
  const IirFilter f = design_butterworth_lowpass(8, 5.0, kFs);
  // Long enough that the ringing has died (below 1e-15) where the passes turn round.
  std::vector<double> x(1000, 0.0);
  std::fill(x.begin() + 500, x.end(), 1.0);
  const std::vector<double> y = filtfilt(f, x);
  // Zero phase about the step half-way between samples 499 and 500: y[500 + k] = 1 - y[499 - k].
  for (std::size_t k = 0; k < 500; ++k) ASSERT_NEAR(y[500 + k] + y[499 - k], 1.0, 1e-12) << k;
  EXPECT_GT(y[500], 0.5);  // rises through 1/2 at the step
  EXPECT_LT(y[499], 0.5);
  EXPECT_NEAR(y[0], 0.0, 1e-12);
  EXPECT_NEAR(y[999], 1.0, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Remez differentiator

// The design's weighted error at f: relative in the pass band, and in the stop band the gain as a
// fraction of the pass-band edge gain, counted at a tenth (the weight the implementation
// documents).
double weighted_error(const FirDifferentiator& d, double hz) {
  const double a = d.response(hz).imag();
  if (hz <= d.passband_hz) return (a - 2 * kPi * hz) / (2 * kPi * hz);
  return 0.1 * a / (2 * kPi * d.passband_hz);
}

struct Extremum {
  double hz, error;
};

// The local extrema of the weighted error over both bands, found on a fine grid and polished by
// golden section (independently of the designer's own search).
std::vector<Extremum> extrema(const FirDifferentiator& d) {
  std::vector<Extremum> out;
  const double nyquist = d.sample_rate_hz / 2;
  for (auto [lo, hi] :
       {std::pair{d.passband_hz * 1e-6, d.passband_hz}, std::pair{d.stopband_hz, nyquist}}) {
    const int n = 4000;
    std::vector<double> f(n + 1), e(n + 1);
    for (int i = 0; i <= n; ++i) {
      f[i] = lo + (hi - lo) * i / n;
      e[i] = weighted_error(d, f[i]);
    }
    for (int i = 0; i <= n; ++i) {
      const double s = e[i] >= 0 ? 1 : -1;
      if ((i > 0 && s * e[i - 1] > s * e[i]) || (i < n && s * e[i + 1] > s * e[i])) continue;
      double a = f[std::max(i - 1, 0)], b = f[std::min(i + 1, n)];
      const double g = (std::sqrt(5.0) - 1) / 2;
      for (int step = 0; step < 80; ++step) {
        const double c = b - g * (b - a), dd = a + g * (b - a);
        if (s * weighted_error(d, c) >= s * weighted_error(d, dd))
          b = dd;
        else
          a = c;
      }
      const double at = (a + b) / 2;
      const double value = s * weighted_error(d, at) > s * e[i] ? weighted_error(d, at) : e[i];
      // Skip the zero of the odd-length response at Nyquist, which is no extremum of the error.
      if (std::abs(value) > 1e-9)
        out.push_back({s * weighted_error(d, at) > s * e[i] ? at : f[i], value});
    }
  }
  return out;
}

// Equiripple: the extrema alternate in sign, number at least the count of free coefficients plus
// one (the alternation theorem's certificate of optimality), and all have one magnitude.
void expect_equiripple(const FirDifferentiator& d, double tolerance) {
  const std::vector<Extremum> ex = extrema(d);
  const std::size_t free_coefficients = d.taps.size() / 2;
  ASSERT_GE(ex.size(), free_coefficients + 1);
  double lo = 1e300, hi = 0;
  for (std::size_t i = 0; i < ex.size(); ++i) {
    if (i > 0) {
      EXPECT_LT(ex[i].error * ex[i - 1].error, 0) << "no alternation at " << ex[i].hz << " Hz";
    }
    lo = std::min(lo, std::abs(ex[i].error));
    hi = std::max(hi, std::abs(ex[i].error));
  }
  EXPECT_LT((hi - lo) / hi, tolerance) << d.taps.size() << " taps";
  // The designer's own figures agree with the level.
  EXPECT_NEAR(d.max_passband_relative_error, hi, 1e-6 * hi);
  EXPECT_NEAR(d.max_stopband_gain, 10 * hi * 2 * kPi * d.passband_hz, 1e-6 * d.max_stopband_gain);
  std::cout << "[ measured ] " << d.taps.size() << " taps, " << d.passband_hz << "/"
            << d.stopband_hz << " Hz: " << d.iterations << " iterations, " << ex.size()
            << " extrema (need " << free_coefficients + 1 << "), level spread " << (hi - lo) / hi
            << ", pass-band relative error " << d.max_passband_relative_error << ", stop-band gain "
            << d.max_stopband_gain << " 1/s\n";
}

TEST(RemezDifferentiatorTest, TapsAreExactlyAntisymmetric) {
  for (int n : {31, 32}) {
    const FirDifferentiator d = design_fir_differentiator(n, 8, 12, kFs);
    ASSERT_EQ(d.taps.size(), static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) EXPECT_EQ(d.taps[i], -d.taps[n - 1 - i]) << i;
    if (n % 2 == 1) {
      EXPECT_EQ(d.taps[n / 2], 0.0);
    }
    // About its centre the response is purely imaginary.
    for (double hz : {1.0, 7.0, 20.0}) EXPECT_LT(std::abs(d.response(hz).real()), 1e-12);
  }
}

TEST(RemezDifferentiatorTest, TypeIIIIsEquirippleWithTheStatedBounds) {
  const FirDifferentiator d = design_fir_differentiator(31, 8, 12, kFs);
  expect_equiripple(d, 1e-6);
  EXPECT_LT(d.max_passband_relative_error, 0.006);
  EXPECT_LT(d.max_stopband_gain, 3.0);
  EXPECT_GE(d.iterations, 2);
  EXPECT_LE(d.iterations, 20);
  // At low frequency the slope is 2 pi f within the bound.
  for (double hz : {0.01, 1.0, 3.0, 8.0}) {
    EXPECT_NEAR(d.response(hz).imag(), 2 * kPi * hz,
                2 * kPi * hz * d.max_passband_relative_error * (1 + 1e-9));
  }
}

TEST(RemezDifferentiatorTest, TheIdentificationDefaultsAreEquiripple) {
  // preprocessing's defaults: 31 taps, 5 / 10 Hz; and a longer one.
  const FirDifferentiator d31 = design_fir_differentiator(31, 5, 10, kFs);
  expect_equiripple(d31, 1e-6);
  EXPECT_LT(d31.max_passband_relative_error, 0.0025);
  const FirDifferentiator d61 = design_fir_differentiator(61, 5, 10, kFs);
  expect_equiripple(d61, 1e-6);
  EXPECT_LT(d61.max_passband_relative_error, 5e-5);
}

TEST(RemezDifferentiatorTest, TypeIVIsEquiripple) {
  expect_equiripple(design_fir_differentiator(32, 8, 12, kFs), 1e-6);
  expect_equiripple(design_fir_differentiator(20, 5, 10, kFs), 1e-6);
  const FirDifferentiator two = design_fir_differentiator(2, 5, 10, kFs);
  ASSERT_EQ(two.taps.size(), 2u);
  EXPECT_EQ(two.taps[0], -two.taps[1]);
}

TEST(RemezDifferentiatorTest, LongFiltersStillConverge) {
  const FirDifferentiator d = design_fir_differentiator(101, 5, 8, kFs);
  expect_equiripple(d, 1e-6);
  EXPECT_LT(d.iterations, 40);  // over both stages: 25 coefficients from an even start, then 50
}

// A least-squares design of the same length and weights: the minimax design must have the smaller
// maximum weighted error (by definition) and both must beat a central difference in the stop band.
TEST(RemezDifferentiatorTest, BeatsLeastSquaresOnTheMaximumAndCentralDifferenceInTheStopBand) {
  const int n = 31;
  const double fp = 8, fs_band = 12;
  const FirDifferentiator remez = design_fir_differentiator(n, fp, fs_band, kFs);

  const int m = n / 2;
  std::vector<double> rows_hz;
  for (int i = 1; i <= 2000; ++i) rows_hz.push_back(fp * i / 2000.0);
  for (int i = 0; i <= 2000; ++i) rows_hz.push_back(fs_band + (kFs / 2 - fs_band) * i / 2000.0);
  Eigen::MatrixXd a(rows_hz.size(), m);
  Eigen::VectorXd b(rows_hz.size());
  for (std::size_t r = 0; r < rows_hz.size(); ++r) {
    const double hz = rows_hz[r];
    const double w = 2 * kPi * hz / kFs;
    const bool pass = hz <= fp;
    const double weight = pass ? 1 / w : 0.1 / (2 * kPi * fp / kFs);
    for (int k = 1; k <= m; ++k) a(r, k - 1) = weight * std::sin(k * w);
    b(r) = pass ? 1.0 : 0.0;
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  FirDifferentiator ls;
  ls.sample_rate_hz = kFs;
  ls.passband_hz = fp;
  ls.stopband_hz = fs_band;
  ls.taps.assign(n, 0.0);
  for (int k = 1; k <= m; ++k) {
    ls.taps[m - k] = c(k - 1) / 2 * kFs;
    ls.taps[m + k] = -c(k - 1) / 2 * kFs;
  }
  double ls_max = 0, ls_stop = 0;
  for (double hz : rows_hz) {
    ls_max = std::max(ls_max, std::abs(weighted_error(ls, hz)));
    if (hz >= fs_band) ls_stop = std::max(ls_stop, std::abs(ls.response(hz)));
  }
  const double remez_max = remez.max_passband_relative_error;
  EXPECT_LT(remez_max, ls_max);

  FirDifferentiator central;
  central.sample_rate_hz = kFs;
  central.passband_hz = fp;
  central.stopband_hz = fs_band;
  central.taps = {kFs / 2, 0.0, -kFs / 2};
  double central_stop = 0;
  for (double hz : rows_hz) {
    if (hz >= fs_band) central_stop = std::max(central_stop, std::abs(central.response(hz)));
  }
  EXPECT_LT(remez.max_stopband_gain, central_stop / 10);
  std::cout << "[ measured ] 31 taps, 8/12 Hz: max weighted error Remez " << remez_max
            << " vs least squares " << ls_max << "; stop-band gain Remez "
            << remez.max_stopband_gain << " vs least squares " << ls_stop
            << " vs central difference " << central_stop << " 1/s\n";
}

TEST(RemezDifferentiatorTest, RejectsBadArgumentsNamingThem) {
  expect_invalid([] { design_fir_differentiator(1, 5, 10, kFs); }, "num_taps");
  expect_invalid([] { design_fir_differentiator(0, 5, 10, kFs); }, "num_taps");
  expect_invalid([] { design_fir_differentiator(100000, 5, 10, kFs); }, "num_taps");
  expect_invalid([] { design_fir_differentiator(31, 0, 10, kFs); }, "passband_hz");
  expect_invalid([] { design_fir_differentiator(31, -1, 10, kFs); }, "passband_hz");
  expect_invalid([] { design_fir_differentiator(31, NAN, 10, kFs); }, "passband_hz");
  expect_invalid([] { design_fir_differentiator(31, 5, 5, kFs); }, "stopband_hz");
  expect_invalid([] { design_fir_differentiator(31, 5, 4, kFs); }, "stopband_hz");
  expect_invalid([] { design_fir_differentiator(31, 5, kFs / 2, kFs); }, "stopband_hz");
  expect_invalid([] { design_fir_differentiator(31, 5, 10, 0); }, "sample_rate_hz");
  expect_invalid([] { design_fir_differentiator(31, 5, 10, NAN); }, "sample_rate_hz");
}

// ---------------------------------------------------------------------------------------------
// differentiate

// The filter's gain on a slope: sum_j h[j] (c - j) / fs (1 for an ideal differentiator).
double slope_gain(const FirDifferentiator& d) {
  const double c = (static_cast<double>(d.taps.size()) - 1) / 2;
  double g = 0;
  for (std::size_t j = 0; j < d.taps.size(); ++j) g += d.taps[j] * (c - static_cast<double>(j));
  return g / d.sample_rate_hz;
}

TEST(DifferentiateTest, ARampGivesOneValueAtEverySampleIncludingTheEdges) {
  const FirDifferentiator d = design_fir_differentiator(31, 5, 10, kFs);
  const double g = slope_gain(d);
  // The slope gain is the relative error at f -> 0, within the design bound.
  EXPECT_LE(std::abs(g - 1), d.max_passband_relative_error * (1 + 1e-9));
  for (std::size_t n : {200u, 16u, 5u, 2u}) {  // shorter than the filter too: repeated reflection
    const std::vector<double> x = sampled(n, [](double t) { return -0.4 + 1.7 * t; });
    const std::vector<double> v = differentiate(d, x);
    ASSERT_EQ(v.size(), n);
    for (double y : v) ASSERT_NEAR(y, 1.7 * g, 1e-11) << n << " samples";
  }
  const std::vector<double> one{3.0};
  EXPECT_EQ(differentiate(d, one), std::vector<double>{0.0});
  EXPECT_TRUE(differentiate(d, std::vector<double>{}).empty());
}

TEST(DifferentiateTest, ASinusoidInsideMatchesItsDerivativeWithinTheBound) {
  const FirDifferentiator d = design_fir_differentiator(31, 5, 10, kFs);
  for (double hz : {0.5, 2.0, 4.5}) {
    const double w = 2 * kPi * hz;
    const std::vector<double> x = sampled(1000, [&](double t) { return std::sin(w * t); });
    const std::vector<double> v = differentiate(d, x);
    double worst = 0;
    for (std::size_t i = 15; i + 15 < x.size(); ++i) {
      worst = std::max(worst, std::abs(v[i] - w * std::cos(w * i / kFs)));
    }
    EXPECT_LE(worst, w * d.max_passband_relative_error * (1 + 1e-6)) << hz << " Hz";
  }
}

TEST(DifferentiateTest, RefusesAnEvenLengthFilter) {
  const FirDifferentiator d = design_fir_differentiator(32, 5, 10, kFs);
  const std::vector<double> x(100, 1.0);
  expect_invalid([&] { differentiate(d, x); }, "filter");
}

// ---------------------------------------------------------------------------------------------
// The whole chain: low-pass, then the differentiator twice, as preprocessing does.

struct Chain {
  IirFilter lowpass = design_butterworth_lowpass(8, 5.0, kFs);
  FirDifferentiator diff = design_fir_differentiator(31, 5, 10, kFs);
};

TEST(FilterChainTest, TwoSinusoidsGiveTheirVelocityAndAcceleration) {
  const Chain chain;
  const double a = 1.2, f = 0.7, b = 0.4, g = 2.3;
  const double wf = 2 * kPi * f, wg = 2 * kPi * g;
  auto q = [&](double t) { return a * std::sin(wf * t) + b * std::sin(wg * t + 0.5); };
  auto dq = [&](double t) { return a * wf * std::cos(wf * t) + b * wg * std::cos(wg * t + 0.5); };
  auto ddq = [&](double t) {
    return -a * wf * wf * std::sin(wf * t) - b * wg * wg * std::sin(wg * t + 0.5);
  };
  const double step = 2 * kPi / 4096;  // the pendulum encoder
  const double delta = chain.diff.max_passband_relative_error;

  for (bool quantised : {false, true}) {
    std::vector<double> x = sampled(625, q);
    if (quantised) {
      for (double& v : x) v = step * std::round(v / step);
    }
    const std::vector<double> filtered = filtfilt(chain.lowpass, x);
    const std::vector<double> v = differentiate(chain.diff, filtered);
    const std::vector<double> acc = differentiate(chain.diff, v);
    // Away from the edges: two half-lengths of the differentiator and the low-pass transient.
    const std::size_t edge = 31 + 30;
    double ev = 0, ea = 0;
    for (std::size_t i = edge; i + edge < x.size(); ++i) {
      const double t = i / kFs;
      ev = std::max(ev, std::abs(v[i] - dq(t)));
      ea = std::max(ea, std::abs(acc[i] - ddq(t)));
    }
    // Without noise the errors are the differentiator's slope error (once, then twice) on each
    // component plus the low-pass's pass-band droop (|H(2.3 Hz)|^2 = 1 - 3e-6).
    const double v_bound = delta * (a * wf + b * wg) + 1e-5 * (a * wf + b * wg);
    const double a_bound = (2 * delta + delta * delta) * (a * wf * wf + b * wg * wg) +
                           1e-5 * (a * wf * wf + b * wg * wg);
    if (!quantised) {
      EXPECT_LT(ev, v_bound);
      EXPECT_LT(ea, a_bound);
    } else {
      // Quantisation adds noise: a step of 1.5e-3 rad is 4.4e-4 rad rms, 1.8e-4 rad once the
      // low-pass keeps the 5 of 31 Hz; differentiating that multiplies it by at most 2 pi 5 Hz each
      // time, 5.6e-3 rad/s and 0.18 rad/s^2 rms. The allowances are about 8 of those.
      EXPECT_LT(ev, v_bound + 0.05);
      EXPECT_LT(ea, a_bound + 1.5);
    }
    std::cout << "[ measured ] chain on two sinusoids" << (quantised ? " (4096-count encoder)" : "")
              << ": max velocity error " << ev << " rad/s (of " << a * wf + b * wg
              << "), max acceleration error " << ea << " rad/s^2 (of " << a * wf * wf + b * wg * wg
              << ")\n";
  }
}

TEST(FilterChainTest, ACubicDifferentiatesToItsDerivativeInside) {
  const Chain chain;
  // t in [0, 10] s: q' from 0.8 down to -1.0 and back, q''' = 0.12.
  auto q = [](double t) { return 0.5 + 0.8 * t - 0.3 * t * t + 0.02 * t * t * t; };
  auto dq = [](double t) { return 0.8 - 0.6 * t + 0.06 * t * t; };
  auto ddq = [](double t) { return -0.6 + 0.12 * t; };
  const std::vector<double> x = sampled(625, q);
  const std::vector<double> filtered = filtfilt(chain.lowpass, x);
  const std::vector<double> v = differentiate(chain.diff, filtered);
  const std::vector<double> acc = differentiate(chain.diff, v);

  // On a cubic a centred antisymmetric filter is exact up to two moments: it returns
  // g1 q' + g3 q''' with g1 the slope gain (1 within the design error) and g3 = sum h (c-j)^3 / 6
  // fs^3.
  const double g1 = slope_gain(chain.diff);
  const double c = 15;
  double g3 = 0;
  for (std::size_t j = 0; j < 31; ++j) g3 += chain.diff.taps[j] * std::pow(c - j, 3.0);
  g3 /= 6 * std::pow(kFs, 3.0);
  // The odd reflection of a cubic is no cubic: the low-pass's edge transient must die out first.
  const std::size_t edge = 160;
  double ev = 0, ea = 0, ev_moment = 0;
  for (std::size_t i = edge; i + edge < x.size(); ++i) {
    const double t = i / kFs;
    ev = std::max(ev, std::abs(v[i] - dq(t)));
    ea = std::max(ea, std::abs(acc[i] - ddq(t)));
    ev_moment = std::max(ev_moment, std::abs(v[i] - (g1 * dq(t) + g3 * 0.12)));
  }
  // The low-pass is flat to order 16 at DC, so inside it leaves the cubic alone; what is left is
  // exactly the two moments.
  EXPECT_LT(ev_moment, 1e-8);
  EXPECT_LT(ev, chain.diff.max_passband_relative_error * 1.0 + std::abs(g3) * 0.12 + 1e-8);
  // Twice over, the second pass sees a quadratic: acceleration = g1^2 q''.
  const double delta = chain.diff.max_passband_relative_error;
  EXPECT_LT(ea, (2 * delta + delta * delta) * 0.6 + 1e-6);
  std::cout << "[ measured ] chain on a cubic: max velocity error " << ev << " rad/s, acceleration "
            << ea << " rad/s^2 (g1 - 1 = " << g1 - 1 << ", g3 = " << g3 << " s^2)\n";
}

}  // namespace
}  // namespace furuta::identification::filters_test
