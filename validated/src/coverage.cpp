#include "furuta/validated/coverage.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace furuta::validated {

namespace {

void check_pieces(const std::vector<const Tube*>& pieces, std::size_t component) {
  if (pieces.empty()) throw std::invalid_argument("coverage: no tube");
  for (const Tube* tube : pieces) {
    if (tube == nullptr) throw std::invalid_argument("coverage: null tube");
    if (tube->dimension != pieces.front()->dimension || tube->t_start != pieces.front()->t_start) {
      throw std::invalid_argument("coverage: the tubes differ in dimension or start time");
    }
  }
  if (component >= pieces.front()->dimension) {
    throw std::invalid_argument("coverage: component " + std::to_string(component) +
                                " out of range (dimension " +
                                std::to_string(pieces.front()->dimension) + ")");
  }
}

// The paper's test on one piece: some step whose [t0, t1] holds t has y in its box over the step.
bool covered_by_a_step(const Tube& tube, std::size_t component, double t, double y) {
  auto it = std::lower_bound(tube.steps.begin(), tube.steps.end(), t,
                             [](const TubeStep& s, double time) { return s.t1 < time; });
  bool any_step = false;
  // A time on a step boundary lies in two steps: either may cover it.
  for (; it != tube.steps.end() && it->t0 <= t; ++it) {
    any_step = true;
    if (it->over[component].contains(y)) return true;
  }
  // A tube without steps holds its initial box at t_start only.
  return !any_step && t == tube.t_start && tube.initial[component].contains(y);
}

}  // namespace

const char* to_string(CoverageMode mode) {
  switch (mode) {
    case CoverageMode::step:
      return "step";
    case CoverageMode::interpolated:
      return "interpolated";
  }
  return "?";
}

double Coverage::rate() const {
  return measurements == 0 ? 0.0 : static_cast<double>(covered) / static_cast<double>(measurements);
}

double Coverage::rate_in_time() const {
  return in_time == 0 ? 0.0 : static_cast<double>(covered) / static_cast<double>(in_time);
}

double time_reached(const std::vector<const Tube*>& pieces) {
  check_pieces(pieces, 0);
  double t = std::numeric_limits<double>::infinity();
  for (const Tube* tube : pieces) t = std::min(t, tube->t_end());
  return t;
}

interval::Interval enclosure_at(const std::vector<const Tube*>& pieces, std::size_t component,
                                double t) {
  check_pieces(pieces, component);
  if (!(t >= pieces.front()->t_start && t <= time_reached(pieces))) {
    return interval::Interval::empty();
  }
  interval::Interval h = interval::Interval::empty();
  for (const Tube* tube : pieces) h = hull(h, tube->enclosure_at(t)[component]);
  return h;
}

Coverage coverage(const std::vector<const Tube*>& pieces, std::size_t component,
                  std::span<const double> t_s, std::span<const double> value, CoverageMode mode,
                  std::vector<bool>* covered) {
  check_pieces(pieces, component);
  if (t_s.size() != value.size()) {
    throw std::invalid_argument("coverage: " + std::to_string(t_s.size()) + " times but " +
                                std::to_string(value.size()) + " values");
  }
  if (covered != nullptr) covered->assign(t_s.size(), false);
  Coverage c;
  c.measurements = t_s.size();
  c.t_start_s = pieces.front()->t_start;
  c.t_reached_s = time_reached(pieces);
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    const double t = t_s[k];
    if (!(t >= c.t_start_s && t <= c.t_reached_s)) {
      ++c.outside_time;
      continue;
    }
    ++c.in_time;
    const bool inside = std::any_of(pieces.begin(), pieces.end(), [&](const Tube* tube) {
      return mode == CoverageMode::step ? covered_by_a_step(*tube, component, t, value[k])
                                        : tube->enclosure_at(t)[component].contains(value[k]);
    });
    if (!inside) continue;
    ++c.covered;
    if (covered != nullptr) (*covered)[k] = true;
  }
  return c;
}

}  // namespace furuta::validated
