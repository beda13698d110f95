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

// Transposed direct form II: two state variables per section, and a steady state that has a closed
// form, which is what makes the start-up transient vanish for a constant input.
struct SectionState {
  double z1 = 0, z2 = 0;
};

// The states the cascade would hold after an infinitely long constant input `level`, so that the
// first output sample already equals the steady-state response and no step transient is injected at
// the (artificial) start of the padded signal.
std::vector<SectionState> steady_state(const IirFilter& filter, double level) {
  std::vector<SectionState> states(filter.sections.size());
  double in = filter.gain * level;
  for (std::size_t k = 0; k < filter.sections.size(); ++k) {
    const SecondOrderSection& s = filter.sections[k];
    const double out = in * (s.b0 + s.b1 + s.b2) / (1.0 + s.a1 + s.a2);
    states[k].z2 = s.b2 * in - s.a2 * out;
    states[k].z1 = s.b1 * in - s.a1 * out + states[k].z2;
    in = out;
  }
  return states;
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

  run_cascade(filter, steady_state(filter, work.front()), work);
  std::reverse(work.begin(), work.end());
  run_cascade(filter, steady_state(filter, work.front()), work);
  std::reverse(work.begin(), work.end());

  return {work.begin() + pad, work.begin() + pad + n};
}

}  // namespace furuta::identification
