#pragma once
// Coverage rates of measurements by validated tubes (the paper's Table III; see
// validated/README.md, "Scenarios and coverage").
//
//   std::vector<const Tube*> pieces = {&result.tube};
//   Coverage c = coverage(pieces, FurutaDynamics::q2, t_s, q2_rad, CoverageMode::step);
//   c.rate()  // covered / all measurements, in [0, 1]
//
// A tube set is one tube, or the pieces of a split run (every solution lies in at least one
// piece's tube). It encloses every solution only up to the earliest end of its pieces (a piece
// that failed early no longer holds its part of the solutions), so that is the set's time
// reached; a measurement after it is not covered and is counted apart.

#include <cstddef>
#include <span>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/validated/integrator.hpp"

namespace furuta::validated {

enum class CoverageMode {
  // The paper's: a measurement (t_k, y_k) is covered when t_k lies in a step's [t0, t1] and y_k
  // in that step's enclosure over the whole step (`TubeStep::over`). Draconian for fast motion:
  // a step's box is the hull over its whole time span, but a lag of a few milliseconds between
  // the measurement and the model moves y_k out of it.
  step,
  // y_k inside the enclosure at t_k itself (`Tube::enclosure_at`, the step's Taylor form
  // evaluated at t_k): what the tube says about that instant.
  interpolated,
};

const char* to_string(CoverageMode mode);

struct Coverage {
  std::size_t measurements = 0;  // all measurements given
  std::size_t in_time = 0;       // N_t: measurement times within [t_start, t_reached]
  std::size_t covered = 0;       // N_q: of those, the values inside the tube
  std::size_t outside_time = 0;  // before t_start or after t_reached: not covered
  double t_start_s = 0.0;
  double t_reached_s = 0.0;  // the earliest end among the pieces

  // Covered over all measurements (those the tube never reached count as not covered). 0 when
  // there are no measurements.
  double rate() const;
  // The paper's N_q / N_t: covered over the measurements the tube reached. 0 when none.
  double rate_in_time() const;
};

// The coverage of the measurements (t_s[k], value[k]) of state component `component` by the tube
// set. Times need not be sorted. std::invalid_argument when there is no piece, a piece is null,
// the pieces differ in dimension or start, the component is out of range, or the spans differ in
// length. `covered`, when given, receives the outcome per measurement.
Coverage coverage(const std::vector<const Tube*>& pieces, std::size_t component,
                  std::span<const double> t_s, std::span<const double> value, CoverageMode mode,
                  std::vector<bool>* covered = nullptr);

// The earliest end among the pieces (the time up to which the set encloses every solution).
double time_reached(const std::vector<const Tube*>& pieces);

// The hull of the pieces' enclosures of `component` at time t (empty outside [t_start,
// time_reached]).
interval::Interval enclosure_at(const std::vector<const Tube*>& pieces, std::size_t component,
                                double t);

}  // namespace furuta::validated
