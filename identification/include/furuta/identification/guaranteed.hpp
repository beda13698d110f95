#pragma once
// Guaranteed identification (paper section III.C, eq. 8-11): every parameter vector consistent with
// the data and its bounded errors, paved by SIVIA into inner / boundary / outer boxes.
//
// Each sample's data are intervals (value +- configured bound). A parameter box is outer when some
// sample's two model rows cannot meet their outputs for any data in the data box (or, with
// q-relaxation, more than q samples say so); inner when, for every sample, data inside the data box
// provably exist that map each parameter of the box onto the outputs. The existence proof is an
// intermediate-value (Poincare-Miranda) witness over the two accelerations: see README.

#include <array>
#include <atomic>
#include <cstddef>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "furuta/identification/lsmi.hpp"
#include "furuta/interval/box.hpp"
#include "furuta/interval/sivia.hpp"

namespace furuta::identification {

using interval::Box;
using interval::Interval;

// |error| <= absolute + relative * |value|.
struct ChannelErrorBound {
  double absolute = 0;
  double relative = 0;
};

struct DataErrorBounds {
  ChannelErrorBound q2, dq1, dq2, ddq1, ddq2, tau;
};

// One sample's data as intervals: what was measured, widened by its bound.
struct IntervalSample {
  std::string experiment;
  std::size_t index = 0;  // in its experiment's series
  double t_s = 0;
  Interval q2, dq1, dq2, ddq1, ddq2, tau;
};

// The samples of the experiments (trimmed at both ends like the LSMI) as intervals.
std::vector<IntervalSample> interval_samples(const std::vector<const JointSeries*>& experiments,
                                             const DataErrorBounds& bounds, std::size_t trim);

// The regressor D (docs/model.md) over data intervals: every D(q2, dq1, dq2, ddq1, ddq2) for data
// in the intervals lies in these enclosures.
struct RegressorEnclosure {
  std::array<Interval, model::kParameterCount> row1, row2;
};
RegressorEnclosure regressor_enclosure(const Interval& q2, const Interval& dq1, const Interval& dq2,
                                       const Interval& ddq1, const Interval& ddq2);

enum class InnerTest {
  // Proves "data exist" (the set P): either the accelerations solved from both rows with q2, dq1,
  // dq2 at points of their intervals and tau at a point of [tau] lie inside their intervals for
  // every p of the box, or (Poincare-Miranda) the rows change sign across the faces of the
  // acceleration rectangle.
  witness,
  intermediate_value,  // the Poincare-Miranda faces alone (for measuring)
  for_all_data,        // the image over the whole data box inside [y]: proves only "for all data"
  none,
};

enum class SampleVerdict { consistent, inconsistent, unknown };

// The values of the carried components (not unknown) for which the inner test proves a box: the
// point of each one's prior midpoint for `witness` and `intermediate_value` (their rows are built
// there, see SampleConstraints), the whole prior for `for_all_data` and `none` (their rows carry
// the prior). Unknown components keep their prior interval.
Box inner_test_carried(const Box& prior, const std::array<bool, model::kParameterCount>& unknown,
                       InnerTest kind);

// The per-sample constraints of one problem (prior box and which components are unknown), with
// what the tests need precomputed. The model is linear in p, so each row is a fixed interval
// coefficient per parameter (depending on the data only); the carried components (not unknown)
// are folded into a constant once: their prior interval for the outer test and contraction, their
// prior's midpoint for the inner witness (P asks for one mu in the carried intervals serving every
// sample, and the midpoint is such a mu). Carried components are never contracted.
class SampleConstraints {
 public:
  SampleConstraints(std::vector<IntervalSample> samples, const Box& prior,
                    const std::array<bool, model::kParameterCount>& unknown);
  std::size_t size() const { return samples_.size(); }
  const IntervalSample& sample(std::size_t i) const { return samples_[i]; }

  // No p in the box and no data in sample i's data box satisfy both rows.
  bool proves_inconsistent(std::size_t i, const Box& p) const;
  // Every p in the box has data in sample i's data box satisfying both rows.
  bool proves_consistent(std::size_t i, const Box& p, InnerTest kind) const;
  // Forward-backward propagation of sample i's two rows onto the box's unknown components; false
  // when it empties the box.
  bool contract(std::size_t i, Box& p) const;
  // All samples at once: the rows form A p in Y (A, Y intervals, 2 per sample), so every consistent
  // p satisfies p in C Y + (I - C A) p for any matrix C; with C the pseudo-inverse of A's midpoint
  // the unknowns decouple and a few Gauss-Seidel sweeps contract strongly where one sample's rows,
  // with every other unknown wide, cannot. False when it empties the box. Sound for q = 0 only.
  bool contract_all(Box& p) const;

  // One row as constant + sum over the unknowns of coefficient * p[index].
  struct LinearRow {
    Interval constant{0.0};
    std::array<Interval, model::kParameterCount> coefficient{};
    std::array<int, model::kParameterCount> index{};
    int terms = 0;
  };

 private:
  struct Precomputed {
    LinearRow row1, row2;                  // over the data box, carried components at their prior
    LinearRow row1_ddq1_lo, row1_ddq1_hi;  // witness faces (carried components at midpoints)
    LinearRow row2_ddq2_lo, row2_ddq2_hi;
    // The rows as M(p) ddq + r(p) at the witness point: M = [a11 a12; a12 a22].
    LinearRow a11, a12, a22, r1, r2;
  };
  void build_preconditioned_system(const std::array<bool, model::kParameterCount>& unknown);
  bool faces_separate(const Precomputed& pre, const Interval& y1, const Box& p) const;
  bool solved_inside(std::size_t i, const Precomputed& pre, const Box& p) const;
  std::vector<IntervalSample> samples_;
  std::vector<Precomputed> pre_;
  // The preconditioned system over the unknowns (indices in unknown_index_).
  std::vector<int> unknown_index_;
  std::vector<Interval> cy_;  // C Y
  std::vector<Interval> g_;   // I - C A, row-major
};

struct GuaranteedOptions {
  // Prior box over p = [mu1, mu2, mu3, mu4, mug, fv1, fv2]; components with `unknown` false are
  // carried as intervals (the paper's Table II mu's) and never bisected.
  Box prior{Box(model::kParameterCount)};
  std::array<bool, model::kParameterCount> unknown{false, false, false, false, false, true, true};
  // Boundary boxes stop at this width: relative to each unknown's prior width, or absolute.
  double epsilon = 0.01;
  bool epsilon_relative = true;
  bool contract = true;
  InnerTest inner = InnerTest::witness;
  // On each box epsilon stops undecided, try the inner test on sub-boxes around its centre (half,
  // a quarter, a tenth of its unknowns' widths) and carve the first proven one out as inner: a
  // feasible set smaller than an epsilon box still gets an inner part (the central feasible box).
  bool probe_inner = true;
  int q = 0;  // samples allowed to be inconsistent (q-relaxed intersection)
  int threads = 0;
  std::function<void(std::size_t tested, std::size_t pending)> progress;
  // A cap on boxes tested (the rest stays boundary: sound, marked truncated) and a stop flag.
  std::size_t max_boxes = 50'000'000;
  // At most this many contractions kept with their boxes (interval::SiviaOptions).
  std::size_t max_kept_contractions = 100'000;
  const std::atomic<bool>* cancel = nullptr;
};

struct GuaranteedResult {
  // paving.inner holds the boxes as SIVIA bisected them, the carried components at their whole
  // prior (so that inner and boundary stay an outer approximation); the inner test proved them
  // only with the carried components at `inner_carried`: see proven_inner.
  interval::SubPaving paving;
  std::array<bool, model::kParameterCount> unknown{};
  InnerTest inner = InnerTest::witness;  // options.inner
  // inner_test_carried(prior, unknown, options.inner).
  Box inner_carried;
  std::size_t samples = 0;
  int q = 0;
  // Samples inconsistent with every parameter of the outer approximation (with q > 0: the faulty
  // readings the relaxation tolerated).
  std::vector<std::size_t> inconsistent_samples;
  // When the set is empty: why, and the samples that cause it.
  bool empty = false;
  std::string finding;
  std::vector<std::size_t> excluding_samples;

  // An inner box as its proof holds: the unknowns' intervals with the carried components at
  // `inner_carried`. Every point of it is in the set; a point of the paving's box with a carried
  // component elsewhere in its prior is only not excluded.
  Box proven_inner(const Box& inner_box) const;
  // proven_inner of every paving.inner box, in order.
  std::vector<Box> proven_inner_boxes() const;
};

// The constraints must have been built with options.prior and options.unknown.
GuaranteedResult guaranteed_identification(const SampleConstraints& constraints,
                                           const GuaranteedOptions& options);

// Area (or volume) of a list of boxes over the unknowns only.
double unknowns_volume(const std::vector<Box>& boxes,
                       const std::array<bool, model::kParameterCount>& unknown);

// The prior of the paper's problem: mu's = centre +- percent (Table II: 12, 12, 10, 12, 15), fv1
// and fv2 in [-1.5, 1.5].
Box paper_prior(const model::Parameters<double>& mu_centre,
                const std::array<double, 5>& mu_percent = {12, 12, 10, 12, 15},
                double friction_limit = 1.5);

}  // namespace furuta::identification
