// Butterworth low-pass as second-order sections: liquid-dsp designs it, this file lifts the design
// to double precision and evaluates the cascade's response.

#include <liquid/liquid.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/identification/filters.hpp"

namespace furuta::identification {
namespace {

// Far above any use here; a typo (80 for 8) then fails at once instead of designing nonsense.
constexpr int kMaxOrder = 20;

// Below this cut-off (relative to the sample rate) liquid's float poles stray from the exact ones
// by a sizeable part of their spacing at high orders; 0.06 Hz at 62.5 Hz is far below any use
// here.
constexpr double kMinRelativeCutoff = 1e-3;

// A matched liquid pole must sit this close to its exact counterpart, as a fraction of the smallest
// distance between two exact poles: close enough that the match cannot be ambiguous, loose enough
// for single-precision rounding of a pole that crowds z = 1 at low cut-offs.
constexpr double kPoleMatchFraction = 0.25;

void require(bool ok, const char* parameter, const std::string& why) {
  if (!ok) throw std::invalid_argument(std::string(parameter) + ": " + why);
}

// The bilinear-transform Butterworth poles in the z plane, upper half plane and real axis only
// (the others are their conjugates). The pre-warped analogue cut-off tan(pi fc / fs) puts -3 dB
// exactly at the requested cut-off.
std::vector<std::complex<double>> exact_digital_poles(int order, double normalised_cutoff) {
  const double omega = std::tan(std::numbers::pi * normalised_cutoff);
  std::vector<std::complex<double>> poles;
  // The first order / 2 analogue poles lie in the upper half plane, and so do their images.
  for (int k = 0; k < order / 2; ++k) {
    const double angle = std::numbers::pi * (2.0 * k + order + 1) / (2.0 * order);
    const std::complex<double> s = std::polar(omega, angle);
    poles.push_back((1.0 + s) / (1.0 - s));
  }
  if (order % 2 == 1) poles.emplace_back((1.0 - omega) / (1.0 + omega), 0.0);
  return poles;
}

// A section's pole in the upper half plane (or on the real axis for a first-order section).
std::complex<double> section_pole(double a1, double a2, bool first_order) {
  if (first_order) return {-a1, 0.0};
  const std::complex<double> discriminant(a1 * a1 - 4.0 * a2, 0.0);
  const std::complex<double> root = (-a1 + std::sqrt(discriminant)) / 2.0;
  return {root.real(), std::abs(root.imag())};
}

}  // namespace

std::complex<double> IirFilter::response(double frequency_hz, double sample_rate_hz) const {
  const std::complex<double> z_inv =
      std::polar(1.0, -2.0 * std::numbers::pi * frequency_hz / sample_rate_hz);
  std::complex<double> h = gain;
  for (const SecondOrderSection& s : sections) {
    h *= (s.b0 + z_inv * (s.b1 + z_inv * s.b2)) / (1.0 + z_inv * (s.a1 + z_inv * s.a2));
  }
  return h;
}

IirFilter design_butterworth_lowpass(int order, double cutoff_hz, double sample_rate_hz) {
  require(order >= 1 && order <= kMaxOrder, "order",
          "must be in [1, " + std::to_string(kMaxOrder) + "], got " + std::to_string(order));
  require(std::isfinite(sample_rate_hz) && sample_rate_hz > 0, "sample_rate_hz",
          "must be finite and positive");
  require(std::isfinite(cutoff_hz) && cutoff_hz > 0 && cutoff_hz < sample_rate_hz / 2, "cutoff_hz",
          "must be in (0, sample_rate_hz / 2)");
  require(cutoff_hz >= kMinRelativeCutoff * sample_rate_hz, "cutoff_hz",
          "below 1e-3 of the sample rate, liquid-dsp's single-precision design cannot place the "
          "poles (they crowd z = 1 closer than float resolves)");

  // liquid's cut-off is relative to the sample rate, in (0, 0.5).
  const double fc = cutoff_hz / sample_rate_hz;
  const int section_count = (order + 1) / 2;
  std::vector<float> b(3 * static_cast<std::size_t>(section_count));
  std::vector<float> a(b.size());
  // The ripple and attenuation arguments only matter for Chebyshev and elliptic designs.
  if (liquid_iirdes(LIQUID_IIRDES_BUTTER, LIQUID_IIRDES_LOWPASS, LIQUID_IIRDES_SOS,
                    static_cast<unsigned>(order), static_cast<float>(fc), 0.0f, 1.0f, 60.0f,
                    b.data(), a.data()) != 0) {
    throw std::runtime_error("liquid_iirdes failed for a Butterworth low-pass of order " +
                             std::to_string(order));
  }

  // liquid works in single precision. Rounding a1, a2 to float moves a pole near z = 1 enough to
  // change the magnitude at low cut-offs (and the DC gain, which would stop filtfilt returning a
  // constant unchanged; docs/measurements/identification.md, "Filters, in full"). So each liquid
  // pole is replaced by the exact pole it approximates, computed in double; a pole that matches
  // nothing means liquid's conventions are not what this code assumes, which must fail loudly.
  std::vector<std::complex<double>> exact = exact_digital_poles(order, fc);
  double separation = 2.0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    for (std::size_t j = i + 1; j < exact.size(); ++j) {
      separation = std::min(separation, std::abs(exact[i] - exact[j]));
    }
  }
  const double tolerance = kPoleMatchFraction * separation;
  std::vector<bool> used(exact.size(), false);

  IirFilter filter;
  for (int s = 0; s < section_count; ++s) {
    const std::size_t i = 3 * static_cast<std::size_t>(s);
    const bool first_order = b[i + 2] == 0.0f && a[i + 2] == 0.0f;
    const std::complex<double> approximate =
        section_pole(a[i + 1] / a[i], a[i + 2] / a[i], first_order);
    std::size_t best = exact.size();
    for (std::size_t k = 0; k < exact.size(); ++k) {
      const bool real = exact[k].imag() == 0.0;
      if (used[k] || real != first_order) continue;
      if (best == exact.size() ||
          std::abs(exact[k] - approximate) < std::abs(exact[best] - approximate)) {
        best = k;
      }
    }
    if (best == exact.size() || std::abs(exact[best] - approximate) > tolerance) {
      throw std::logic_error("liquid_iirdes section " + std::to_string(s) +
                             " has a pole matching no Butterworth pole");
    }
    used[best] = true;
    const std::complex<double> p = exact[best];

    // The zeros are all at z = -1: numerator (1, 2, 1) or (1, 1, 0). liquid's are exact multiples
    // of those, unless its float gain underflowed to 0 (order 20 near the lowest cut-off).
    const double shape[3] = {1.0, first_order ? 1.0 : 2.0, first_order ? 0.0 : 1.0};
    if (b[i] != 0.0f) {
      for (int k = 1; k < 3; ++k) {
        if (std::abs(b[i + k] / b[i] - shape[k]) > 1e-6) {
          throw std::logic_error("liquid_iirdes section " + std::to_string(s) +
                                 " has zeros away from z = -1");
        }
      }
    }
    SecondOrderSection section;
    section.a1 = first_order ? -p.real() : -2.0 * p.real();
    section.a2 = first_order ? 0.0 : std::norm(p);
    // Unit DC gain per section, so the cascade's is 1 to rounding and intermediate signals keep the
    // input's scale.
    const double dc = (1.0 + section.a1 + section.a2) / (shape[0] + shape[1] + shape[2]);
    section.b0 = shape[0] * dc;
    section.b1 = shape[1] * dc;
    section.b2 = shape[2] * dc;
    filter.sections.push_back(section);
  }
  filter.gain = 1.0;
  return filter;
}

}  // namespace furuta::identification
