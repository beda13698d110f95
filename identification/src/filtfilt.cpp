// Zero-phase filtering through a cascade of second-order sections.

#include <algorithm>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/identification/filters.hpp"

namespace furuta::identification {
namespace {

// Transposed direct form II: two state variables per section, and steady states in closed form,
// which is what lets a pass start without a transient.
struct SectionState {
  double z1 = 0, z2 = 0;
};

// The states the cascade would hold after an infinitely long input that is the straight line
// x[n] = level + slope * n around n = 0: the first output is then already the steady-state response
// and no start-up transient is injected at the (artificial) start of the padded signal. With slope
// 0 this is scipy's lfilter_zi scaled by the level; matching the slope too matters because the odd
// reflection continues the signal's slope, and a start from a constant's steady state would inject
// a transient of slope x group delay that the default padding only damps, never removes, by the
// first real sample (docs/measurements/identification.md, "Filters, in full").
std::vector<SectionState> steady_state(const IirFilter& filter, double level, double slope) {
  std::vector<SectionState> states(filter.sections.size());
  double c = filter.gain * level, s = filter.gain * slope;
  for (std::size_t k = 0; k < filter.sections.size(); ++k) {
    const SecondOrderSection& q = filter.sections[k];
    // A section H(u) = B(u) / A(u), u = 1/z, turns a line into the line G (c + s n) - s H'(1):
    // a gain and a lag.
    const double b = q.b0 + q.b1 + q.b2, a = 1.0 + q.a1 + q.a2;
    const double db = q.b1 + 2 * q.b2, da = q.a1 + 2 * q.a2;
    const double gain = b / a;
    const double lag = (db * a - b * da) / (a * a);
    const double c_out = gain * c - s * lag, s_out = gain * s;
    // Transposed direct form II: y[0] = b0 x[0] + z1[0]; z2[0] = b2 x[-1] - a2 y[-1].
    states[k].z1 = c_out - q.b0 * c;
    states[k].z2 = q.b2 * (c - s) - q.a2 * (c_out - s_out);
    c = c_out;
    s = s_out;
  }
  return states;
}

// Samples over which the starting slope is measured: short enough to be the local slope (a mean
// over the whole padding did worse on oscillating signals), and a mean over a few samples rather
// than one difference against encoder steps. Against the constant's steady state it makes a ramp
// exact at the edges and a slow sinusoid better, and is about even on faster ones (there the
// curvature the odd reflection cannot continue dominates the edge error either way;
// docs/measurements/identification.md, "Filters, in full").
constexpr std::ptrdiff_t kSlopeSpan = 4;

// The line the start of `samples` follows: its first value and slope.
std::vector<SectionState> start_state(const IirFilter& filter, const std::vector<double>& samples) {
  const std::ptrdiff_t span = std::min(static_cast<std::ptrdiff_t>(samples.size()) - 1, kSlopeSpan);
  const double slope =
      span > 0 ? (samples[static_cast<std::size_t>(span)] - samples[0]) / static_cast<double>(span)
               : 0.0;
  return steady_state(filter, samples[0], slope);
}

void run_cascade(const IirFilter& filter, std::vector<SectionState> states,
                 std::vector<double>& samples) {
  for (double& x : samples) {
    double v = filter.gain * x;
    for (std::size_t k = 0; k < filter.sections.size(); ++k) {
      const SecondOrderSection& s = filter.sections[k];
      SectionState& st = states[k];
      const double y = s.b0 * v + st.z1;
      st.z1 = s.b1 * v - s.a1 * y + st.z2;
      st.z2 = s.b2 * v - s.a2 * y;
      v = y;
    }
    x = v;
  }
}

}  // namespace

std::vector<double> filtfilt(const IirFilter& filter, std::span<const double> signal,
                             std::ptrdiff_t pad) {
  if (pad < -1) throw std::invalid_argument("pad: must be -1 (default) or >= 0");
  const auto n = static_cast<std::ptrdiff_t>(signal.size());
  if (n == 0) return {};
  if (pad == -1) pad = 3 * (2 * static_cast<std::ptrdiff_t>(filter.sections.size()) + 1);
  pad = std::min(pad, n - 1);

  // Odd reflection about the end values continues the signal's level and slope, so the filter sees
  // no step or kink at either end.
  std::vector<double> work;
  work.reserve(static_cast<std::size_t>(n + 2 * pad));
  const double first = signal[0];
  const double last = signal[static_cast<std::size_t>(n - 1)];
  for (std::ptrdiff_t k = pad; k >= 1; --k)
    work.push_back(2 * first - signal[static_cast<std::size_t>(k)]);
  work.insert(work.end(), signal.begin(), signal.end());
  for (std::ptrdiff_t k = 1; k <= pad; ++k) {
    work.push_back(2 * last - signal[static_cast<std::size_t>(n - 1 - k)]);
  }

  // Each pass starts in the steady state of the line its first samples follow: a constant passes
  // exactly, and so does a ramp, edges included.
  run_cascade(filter, start_state(filter, work), work);
  std::reverse(work.begin(), work.end());
  run_cascade(filter, start_state(filter, work), work);
  std::reverse(work.begin(), work.end());

  return {work.begin() + pad, work.begin() + pad + n};
}

}  // namespace furuta::identification
