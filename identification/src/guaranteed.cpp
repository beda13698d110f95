#include "furuta/identification/guaranteed.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace furuta::identification {

namespace {

bool is_zero(const Interval& a) {
  return a.lo() == 0 && a.hi() == 0;
}

using LinearRow = SampleConstraints::LinearRow;

// constant + sum_j a_j p_idx(j): the exact range for independent coefficients and parameters,
// rounded outward.
Interval evaluate(const LinearRow& row, const Box& p) {
  Interval sum = row.constant;
  for (int j = 0; j < row.terms; ++j) sum += row.coefficient[j] * p[row.index[j]];
  return sum;
}

// HC4-revise on constant + sum_j a_j p_j = y: forward terms, intersection with y, then each term's
// projection back onto its parameter (the other terms' sum from prefix and suffix sums). False when
// the box is emptied.
bool contract_linear(const LinearRow& row, const Interval& y, Box& p) {
  const int n = row.terms;
  std::array<Interval, model::kParameterCount> term;
  for (int j = 0; j < n; ++j) term[j] = row.coefficient[j] * p[row.index[j]];
  // prefix[j] = constant + term[0..j-1]; suffix[j] = term[j..n-1].
  std::array<Interval, model::kParameterCount + 1> prefix, suffix;
  prefix[0] = row.constant;
  for (int j = 0; j < n; ++j) prefix[j + 1] = prefix[j] + term[j];
  suffix[n] = Interval(0.0);
  for (int j = n - 1; j >= 0; --j) suffix[j] = suffix[j + 1] + term[j];
  const Interval sum = intersect(prefix[n], y);
  if (sum.is_empty()) return false;
  for (int j = 0; j < n; ++j) {
    const Interval t = intersect(term[j], sum - (prefix[j] + suffix[j + 1]));
    if (t.is_empty()) return false;
    Interval coefficient = row.coefficient[j];
    Interval parameter = p[row.index[j]];
    interval::bwd_mul(t, coefficient, parameter);
    if (parameter.is_empty()) return false;
    p[row.index[j]] = parameter;
  }
  return true;
}

// The range of constant + sum_j a_j p_idx(j) in plain round-to-nearest floating point: an estimate
// without outward rounding, used only to decide to skip work, never for a verdict.
struct RowEstimate {
  double lo, hi;
};
RowEstimate estimate(const LinearRow& row, const Box& p) {
  RowEstimate e{row.constant.lo(), row.constant.hi()};
  for (int j = 0; j < row.terms; ++j) {
    const Interval& a = row.coefficient[j];
    const Interval& x = p[row.index[j]];
    const double ll = a.lo() * x.lo(), lh = a.lo() * x.hi(), hl = a.hi() * x.lo(),
                 hh = a.hi() * x.hi();
    e.lo += std::min(std::min(ll, lh), std::min(hl, hh));
    e.hi += std::max(std::max(ll, lh), std::max(hl, hh));
  }
  return e;
}

// Whether contract_linear(row, y, p) would leave p as it is, decided in plain floating point. With
// the image [L, H] and S = [L, H] & y, term j's range t_j is cut to c_j = t_j & (S - R_j), R_j the
// other terms' range [L - t_j.lo, H - t_j.hi]; p_j then keeps exactly its points x for which some
// a in a_j gives a x in c_j. That set is connected within p_j (or its hull is p_j), so p_j stays
// whole when both its bounds qualify: a_j x_lo and a_j x_hi (the products already formed for t_j)
// both meet c_j. The rigorous revise encloses that set, so it would not contract either (beyond
// rounding). Skipping a contraction is always sound (it only contracts less), so this decision need
// not be rigorous (a NaN image says "not idle", and the rigorous revise runs).
bool contraction_is_idle(const LinearRow& row, const Interval& y, const Box& p) {
  const int n = row.terms;
  // Per term: the products a_lo x_lo, a_hi x_lo (the bound x_lo) and a_lo x_hi, a_hi x_hi.
  std::array<double, model::kParameterCount> lo_min, lo_max, hi_min, hi_max, tl, th;
  double lo = row.constant.lo(), hi = row.constant.hi();
  for (int j = 0; j < n; ++j) {
    const Interval& a = row.coefficient[j];
    const Interval& x = p[row.index[j]];
    const double ll = a.lo() * x.lo(), hl = a.hi() * x.lo(), lh = a.lo() * x.hi(),
                 hh = a.hi() * x.hi();
    lo_min[j] = std::min(ll, hl);
    lo_max[j] = std::max(ll, hl);
    hi_min[j] = std::min(lh, hh);
    hi_max[j] = std::max(lh, hh);
    tl[j] = std::min(lo_min[j], hi_min[j]);
    th[j] = std::max(lo_max[j], hi_max[j]);
    lo += tl[j];
    hi += th[j];
  }
  const double s_lo = std::max(lo, y.lo()), s_hi = std::min(hi, y.hi());
  if (!(s_lo <= s_hi)) return false;
  for (int j = 0; j < n; ++j) {
    const double cut_lo = std::max(tl[j], s_lo - (hi - th[j]));
    const double cut_hi = std::min(th[j], s_hi - (lo - tl[j]));
    if (cut_lo <= tl[j] && cut_hi >= th[j]) continue;  // the term keeps its range
    if (!(lo_min[j] <= cut_hi && lo_max[j] >= cut_lo && hi_min[j] <= cut_hi &&
          hi_max[j] >= cut_lo)) {
      return false;
    }
  }
  return true;
}

// A row's coefficients split into the unknowns' terms and a constant from the carried components
// (each carried p_k given as an interval: its prior, or its midpoint).
LinearRow reduce(const std::array<Interval, model::kParameterCount>& a, const Box& carried,
                 const std::array<bool, model::kParameterCount>& unknown) {
  LinearRow row;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (is_zero(a[k])) continue;
    if (unknown[k]) {
      row.coefficient[row.terms] = a[k];
      row.index[row.terms] = k;
      ++row.terms;
    } else {
      row.constant += a[k] * carried[k];
    }
  }
  return row;
}

Interval widened(double value, const ChannelErrorBound& bound) {
  const double b = std::nextafter(bound.absolute + bound.relative * std::abs(value),
                                  std::numeric_limits<double>::infinity());
  return Interval(value) + Interval(-b, b);
}

Interval point_of(const Interval& x) {
  return Interval(x.mid());
}

}  // namespace

Box inner_test_carried(const Box& prior, const std::array<bool, model::kParameterCount>& unknown,
                       InnerTest kind) {
  Box carried = prior;
  const bool at_midpoint = kind == InnerTest::witness || kind == InnerTest::intermediate_value;
  for (std::size_t k = 0; k < prior.size() && k < model::kParameterCount; ++k) {
    if (!unknown[k] && at_midpoint) carried[k] = point_of(prior[k]);
  }
  return carried;
}

Box GuaranteedResult::proven_inner(const Box& inner_box) const {
  Box proven = inner_box;
  for (std::size_t k = 0; k < proven.size() && k < inner_carried.size(); ++k) {
    if (!unknown[k]) proven[k] = inner_carried[k];
  }
  return proven;
}

std::vector<Box> GuaranteedResult::proven_inner_boxes() const {
  std::vector<Box> out;
  out.reserve(paving.inner.size());
  for (const Box& b : paving.inner) out.push_back(proven_inner(b));
  return out;
}

std::vector<IntervalSample> interval_samples(const std::vector<const JointSeries*>& experiments,
                                             const DataErrorBounds& bounds, std::size_t trim) {
  std::vector<IntervalSample> out;
  for (const JointSeries* e : experiments) {
    if (e->size() <= 2 * trim) continue;
    for (std::size_t i = trim; i + trim < e->size(); ++i) {
      IntervalSample s;
      s.experiment = e->name;
      s.index = i;
      s.t_s = e->t_s[i];
      s.q2 = widened(e->q2[i], bounds.q2);
      s.dq1 = widened(e->dq1[i], bounds.dq1);
      s.dq2 = widened(e->dq2[i], bounds.dq2);
      s.ddq1 = widened(e->ddq1[i], bounds.ddq1);
      s.ddq2 = widened(e->ddq2[i], bounds.ddq2);
      s.tau = widened(e->tau[i], bounds.tau);
      out.push_back(std::move(s));
    }
  }
  return out;
}

RegressorEnclosure regressor_enclosure(const Interval& q2, const Interval& dq1, const Interval& dq2,
                                       const Interval& ddq1, const Interval& ddq2) {
  const Interval s = interval::sin(q2);
  const Interval c = interval::cos(q2);
  // s^2 and s c as single enclosures where they repeat; sqr keeps s^2 non-negative.
  const Interval s2 = interval::sqr(s);
  const Interval sc = s * c;
  RegressorEnclosure r;
  const Interval zero(0.0);
  r.row1 = {ddq1,
            s2 * ddq1 + Interval(2.0) * sc * dq1 * dq2,
            c * ddq2 - s * interval::sqr(dq2),
            zero,
            zero,
            dq1,
            zero};
  r.row2 = {zero, -(sc * interval::sqr(dq1)), c * ddq1, ddq2, s, zero, dq2};
  return r;
}

SampleConstraints::SampleConstraints(std::vector<IntervalSample> samples, const Box& prior,
                                     const std::array<bool, model::kParameterCount>& unknown)
    : samples_(std::move(samples)) {
  if (prior.size() != static_cast<std::size_t>(model::kParameterCount)) {
    throw std::invalid_argument("guaranteed identification: the prior box needs 7 components");
  }
  // The witness rows: carried components at the points the inner test proves with.
  const Box midpoints = inner_test_carried(prior, unknown, InnerTest::witness);
  pre_.reserve(samples_.size());
  for (const IntervalSample& d : samples_) {
    Precomputed p;
    const RegressorEnclosure full = regressor_enclosure(d.q2, d.dq1, d.dq2, d.ddq1, d.ddq2);
    p.row1 = reduce(full.row1, prior, unknown);
    p.row2 = reduce(full.row2, prior, unknown);
    // The witness rectangle: q2, dq1, dq2 fixed at points of their intervals, (ddq1, ddq2) free.
    const Interval q2 = point_of(d.q2), dq1 = point_of(d.dq1), dq2 = point_of(d.dq2);
    const auto face = [&](const Interval& ddq1, const Interval& ddq2) {
      return regressor_enclosure(q2, dq1, dq2, ddq1, ddq2);
    };
    p.row1_ddq1_lo = reduce(face(Interval(d.ddq1.lo()), d.ddq2).row1, midpoints, unknown);
    p.row1_ddq1_hi = reduce(face(Interval(d.ddq1.hi()), d.ddq2).row1, midpoints, unknown);
    p.row2_ddq2_lo = reduce(face(d.ddq1, Interval(d.ddq2.lo())).row2, midpoints, unknown);
    p.row2_ddq2_hi = reduce(face(d.ddq1, Interval(d.ddq2.hi())).row2, midpoints, unknown);
    const Interval sn = interval::sin(q2), cs = interval::cos(q2), zero(0.0), one(1.0);
    using Row = std::array<Interval, model::kParameterCount>;
    p.a11 = reduce(Row{one, interval::sqr(sn), zero, zero, zero, zero, zero}, midpoints, unknown);
    p.a12 = reduce(Row{zero, zero, cs, zero, zero, zero, zero}, midpoints, unknown);
    p.a22 = reduce(Row{zero, zero, zero, one, zero, zero, zero}, midpoints, unknown);
    p.r1 = reduce(Row{zero, Interval(2.0) * sn * cs * dq1 * dq2, -(sn * interval::sqr(dq2)), zero,
                      zero, dq1, zero},
                  midpoints, unknown);
    p.r2 = reduce(Row{zero, -(sn * cs * interval::sqr(dq1)), zero, zero, sn, zero, dq2}, midpoints,
                  unknown);
    pre_.push_back(p);
  }
  build_preconditioned_system(unknown);
}

void SampleConstraints::build_preconditioned_system(
    const std::array<bool, model::kParameterCount>& unknown) {
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (unknown[k]) unknown_index_.push_back(k);
  }
  const auto n = static_cast<Eigen::Index>(unknown_index_.size());
  const auto rows = static_cast<Eigen::Index>(2 * pre_.size());
  if (n == 0 || rows < n) return;
  // Row r of A over the unknowns, and its right-hand side y - constant.
  std::vector<std::array<Interval, model::kParameterCount>> a(static_cast<std::size_t>(rows));
  std::vector<Interval> y(static_cast<std::size_t>(rows));
  Eigen::MatrixXd mid(rows, n);
  for (std::size_t i = 0; i < pre_.size(); ++i) {
    for (int r = 0; r < 2; ++r) {
      const LinearRow& row = r == 0 ? pre_[i].row1 : pre_[i].row2;
      const std::size_t at = 2 * i + static_cast<std::size_t>(r);
      a[at].fill(Interval(0.0));
      for (int j = 0; j < row.terms; ++j) {
        const auto col = std::find(unknown_index_.begin(), unknown_index_.end(), row.index[j]) -
                         unknown_index_.begin();
        a[at][static_cast<std::size_t>(col)] = row.coefficient[j];
      }
      y[at] = (r == 0 ? samples_[i].tau : Interval(0.0)) - row.constant;
      for (Eigen::Index c = 0; c < n; ++c) {
        const Interval& e = a[at][static_cast<std::size_t>(c)];
        mid(static_cast<Eigen::Index>(at), c) = std::isfinite(e.mid()) ? e.mid() : 0.0;
      }
    }
  }
  // Any C is sound; the pseudo-inverse of the midpoint (columns scaled, since units differ) makes
  // I - C A small.
  const Eigen::VectorXd scale = mid.colwise().norm().cwiseMax(1e-300).transpose();
  const Eigen::MatrixXd scaled = mid * scale.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd c_scaled = scaled.completeOrthogonalDecomposition().pseudoInverse();
  const Eigen::MatrixXd c = scale.cwiseInverse().asDiagonal() * c_scaled;
  cy_.assign(static_cast<std::size_t>(n), Interval(0.0));
  g_.assign(static_cast<std::size_t>(n * n), Interval(0.0));
  for (Eigen::Index k = 0; k < n; ++k) {
    Interval cy(0.0);
    std::vector<Interval> ca(static_cast<std::size_t>(n), Interval(0.0));
    for (Eigen::Index r = 0; r < rows; ++r) {
      // Any C is sound, so an entry the pseudo-inverse left non-finite (a column of subnormal
      // coefficients scaled by 1e300) is taken as 0: Interval(inf) would be empty and empty the
      // box.
      const double ckr = c(k, r);
      if (ckr == 0 || !std::isfinite(ckr)) continue;
      const Interval ck(ckr);
      cy += ck * y[static_cast<std::size_t>(r)];
      for (Eigen::Index j = 0; j < n; ++j) {
        const Interval& e = a[static_cast<std::size_t>(r)][static_cast<std::size_t>(j)];
        if (!is_zero(e)) ca[static_cast<std::size_t>(j)] += ck * e;
      }
    }
    cy_[static_cast<std::size_t>(k)] = cy;
    for (Eigen::Index j = 0; j < n; ++j) {
      g_[static_cast<std::size_t>(k * n + j)] =
          Interval(k == j ? 1.0 : 0.0) - ca[static_cast<std::size_t>(j)];
    }
  }
}

bool SampleConstraints::contract_all(Box& p) const {
  const std::size_t n = unknown_index_.size();
  if (cy_.empty()) return true;
  for (int sweep = 0; sweep < 3; ++sweep) {
    bool shrank = false;
    for (std::size_t k = 0; k < n; ++k) {
      Interval v = cy_[k];
      for (std::size_t j = 0; j < n; ++j) {
        const Interval& g = g_[k * n + j];
        if (!is_zero(g)) v += g * p[static_cast<std::size_t>(unknown_index_[j])];
      }
      Interval& target = p[static_cast<std::size_t>(unknown_index_[k])];
      const Interval next = intersect(target, v);
      if (next.is_empty()) return false;
      if (next.width() < 0.9 * target.width()) shrank = true;
      target = next;
    }
    if (!shrank) break;
  }
  return true;
}

bool SampleConstraints::proves_inconsistent(std::size_t i, const Box& p) const {
  const Precomputed& pre = pre_[i];
  // Most samples are plainly consistent with the box: the floating-point estimates of both rows'
  // ranges meet their outputs. Answering "not proven" is always sound; when an estimate misses (or
  // is NaN), the outward-rounded evaluation decides.
  const RowEstimate e1 = estimate(pre.row1, p), e2 = estimate(pre.row2, p);
  if (e1.lo <= samples_[i].tau.hi() && e1.hi >= samples_[i].tau.lo() && e2.lo <= 0 && e2.hi >= 0) {
    return false;
  }
  if (evaluate(pre.row1, p).is_disjoint(samples_[i].tau)) return true;
  return !evaluate(pre.row2, p).contains(0.0);
}

bool SampleConstraints::proves_consistent(std::size_t i, const Box& p, InnerTest kind) const {
  const Precomputed& pre = pre_[i];
  const Interval& y1 = samples_[i].tau;
  switch (kind) {
    case InnerTest::none:
      return false;
    case InnerTest::for_all_data:
      return evaluate(pre.row1, p).is_subset(y1) && evaluate(pre.row2, p).is_subset(Interval(0.0));
    case InnerTest::intermediate_value:
      return faces_separate(pre, y1, p);
    case InnerTest::witness:
      return solved_inside(i, pre, p) || faces_separate(pre, y1, p);
  }
  return false;
}

// Poincare-Miranda on the rectangle [ddq1] x [ddq2]: F1 = row1 - c (some c in [y1]) of opposite
// signs on the faces ddq1 = lo, hi; F2 = row2 of opposite signs on the faces ddq2 = lo, hi; each
// face evaluated over the other acceleration's whole interval and the whole box. Then for every p
// a zero exists inside the rectangle: data in the data box meeting both outputs.
bool SampleConstraints::faces_separate(const Precomputed& pre, const Interval& y1,
                                       const Box& p) const {
  const Interval f1_lo = evaluate(pre.row1_ddq1_lo, p);
  const Interval f1_hi = evaluate(pre.row1_ddq1_hi, p);
  const auto separates = [&](const Interval& below, const Interval& above) {
    return std::max(below.hi(), y1.lo()) <= std::min(above.lo(), y1.hi());
  };
  if (!separates(f1_lo, f1_hi) && !separates(f1_hi, f1_lo)) return false;
  const Interval f2_lo = evaluate(pre.row2_ddq2_lo, p);
  const Interval f2_hi = evaluate(pre.row2_ddq2_hi, p);
  return (f2_lo.hi() <= 0 && f2_hi.lo() >= 0) || (f2_hi.hi() <= 0 && f2_lo.lo() >= 0);
}

// With q2, dq1, dq2 at the witness point and tau = c in [y1], both rows are M(p) ddq = r(p, c), a
// 2x2 linear system. If its solution (Cramer's rule over the box) lies inside the acceleration
// intervals for every p, that solution is the data point: the segment through the data box along
// which the rows are continuous is the one traced by ddq(p). c is chosen to aim the solution at the
// rectangle's centre for the box's midpoint.
bool SampleConstraints::solved_inside(std::size_t i, const Precomputed& pre, const Box& p) const {
  const IntervalSample& d = samples_[i];
  const Interval a11 = evaluate(pre.a11, p), a12 = evaluate(pre.a12, p), a22 = evaluate(pre.a22, p),
                 r1 = evaluate(pre.r1, p), r2 = evaluate(pre.r2, p);
  const Interval det = a11 * a22 - interval::sqr(a12);
  if (det.contains(0.0)) return false;
  const double aim = a11.mid() * d.ddq1.mid() + a12.mid() * d.ddq2.mid() + r1.mid();
  const double c = std::clamp(aim, d.tau.lo(), d.tau.hi());
  // A NaN aim (overflowing data) would make Interval(c) empty, and the empty set is a subset of
  // anything: no proof then.
  if (!std::isfinite(c)) return false;
  const Interval b1 = Interval(c) - r1, b2 = -r2;
  const Interval ddq1 = (a22 * b1 - a12 * b2) / det;
  if (!ddq1.is_subset(d.ddq1)) return false;
  const Interval ddq2 = (a11 * b2 - a12 * b1) / det;
  return ddq2.is_subset(d.ddq2);
}

// HC4-revise of both rows, each skipped when the floating-point check says it would leave the box
// as it is: most rows, once the box is near the set's hull, so a sweep costs about one estimate per
// row instead of a rigorous revise.
bool SampleConstraints::contract(std::size_t i, Box& p) const {
  // Sweeps go through the samples in order, and a sample's precomputed rows are far apart (the
  // witness rows sit between them): fetch the next sample's two rows ahead.
  if (i + 2 < pre_.size()) {
    const char* next = reinterpret_cast<const char*>(&pre_[i + 2]);
    for (std::size_t at = 0; at < 2 * sizeof(LinearRow); at += 64) __builtin_prefetch(next + at);
  }
  const Precomputed& pre = pre_[i];
  const Interval& tau = samples_[i].tau;
  if (!contraction_is_idle(pre.row1, tau, p) && !contract_linear(pre.row1, tau, p)) return false;
  const Interval zero(0.0);
  return contraction_is_idle(pre.row2, zero, p) || contract_linear(pre.row2, zero, p);
}

Box paper_prior(const model::Parameters<double>& mu_centre, const std::array<double, 5>& mu_percent,
                double friction_limit) {
  Box prior(model::kParameterCount);
  for (int k = 0; k < 5; ++k) {
    const double half = std::abs(mu_centre[k]) * mu_percent[k] / 100.0;
    prior[k] = Interval(mu_centre[k]) + Interval(-half, half);
  }
  prior[5] = Interval(-friction_limit, friction_limit);
  prior[6] = Interval(-friction_limit, friction_limit);
  return prior;
}

GuaranteedResult guaranteed_identification(const SampleConstraints& constraints,
                                           const GuaranteedOptions& options) {
  if (options.prior.size() != static_cast<std::size_t>(model::kParameterCount)) {
    throw std::invalid_argument("guaranteed identification: the prior box needs 7 components");
  }
  if (options.q < 0) throw std::invalid_argument("guaranteed identification: q must be >= 0");
  const std::size_t n = constraints.size();
  if (n == 0) throw std::invalid_argument("guaranteed identification: no samples");

  // How often each sample was the one that proved a box outer: the culprits of an empty set.
  auto outer_causes = std::make_unique<std::atomic<std::uint64_t>[]>(n);
  const std::size_t q = static_cast<std::size_t>(options.q);

  std::atomic<std::size_t> inner_hint{0};
  // Whether every parameter of the box is consistent with all samples but q (the inner verdict).
  // The verdict does not depend on the order the samples are tried in, so start at the sample that
  // last failed (in any thread; neighbouring boxes tend to fail at the same samples) and go round.
  const auto proven_inner = [&](const Box& box) {
    const std::size_t start = inner_hint.load(std::memory_order_relaxed);
    std::size_t unproven = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = start + k < n ? start + k : start + k - n;
      if (!constraints.proves_consistent(i, box, options.inner)) {
        inner_hint.store(i, std::memory_order_relaxed);
        if (++unproven > q) return false;
      }
    }
    return true;
  };

  const interval::BoxTest test = [&](Box& box) -> interval::BoxDecision {
    using interval::BoxVerdict;
    if (q == 0) {
      // Contract sample after sample; repeat the sweep while it still shrinks some unknown by more
      // than a tenth (couplings between rows need a few sweeps), at most four times.
      for (int sweep = 0; sweep < (options.contract ? 4 : 1); ++sweep) {
        const Box before = box;
        if (options.contract && !constraints.contract_all(box)) return {BoxVerdict::outer};
        for (std::size_t i = 0; i < n; ++i) {
          const bool out = options.contract ? !constraints.contract(i, box)
                                            : constraints.proves_inconsistent(i, box);
          if (out) {
            outer_causes[i].fetch_add(1, std::memory_order_relaxed);
            return {BoxVerdict::outer};
          }
        }
        bool shrank = false;
        for (std::size_t k = 0; k < model::kParameterCount; ++k) {
          if (options.unknown[k] && box[k].width() < 0.9 * before[k].width()) shrank = true;
        }
        if (!shrank) break;
      }
      if (options.inner == InnerTest::none) return {BoxVerdict::undecided};
      return {proven_inner(box) ? BoxVerdict::inner : BoxVerdict::undecided};
    }
    // q-relaxed: outer when more than q samples are proven inconsistent, inner when at most q are
    // not proven consistent. (No contraction: one sample alone may be an outlier.)
    std::size_t inconsistent = 0;
    for (std::size_t i = 0; i < n && inconsistent <= q; ++i) {
      if (constraints.proves_inconsistent(i, box)) ++inconsistent;
    }
    if (inconsistent > q) return {BoxVerdict::outer};
    if (options.inner == InnerTest::none) return {BoxVerdict::undecided};
    return {proven_inner(box) ? BoxVerdict::inner : BoxVerdict::undecided};
  };

  interval::SiviaOptions sivia;
  if (options.probe_inner && options.inner != InnerTest::none) {
    // Sub-boxes of a fraction of the box's unknowns' widths around its centre; carried components
    // keep their whole interval. The inner test is inclusion-monotone (a box proven inner proves
    // its sub-boxes), so the smallest is tried first and, once proven, grown; when it fails no
    // larger one around that centre can succeed. With few unknowns, centres a quarter-width away
    // along each unknown are tried too (the set's interior need not be at the box's centre).
    const int unknowns =
        static_cast<int>(std::count(options.unknown.begin(), options.unknown.end(), true));
    sivia.inner_probe = [&, unknowns](const Box& box) -> std::optional<Box> {
      const auto sub_box = [&](double fraction, int shifted, double shift) {
        Box sub = box;
        for (std::size_t k = 0; k < model::kParameterCount; ++k) {
          if (!options.unknown[k]) continue;
          const double w = box[k].width();
          const double c = box[k].mid() + (static_cast<int>(k) == shifted ? shift * w : 0.0);
          sub[k] = intersect(Interval(c - 0.5 * fraction * w, c + 0.5 * fraction * w), box[k]);
        }
        return sub;
      };
      const auto grown_from = [&](int shifted, double shift) -> std::optional<Box> {
        Box proven = sub_box(0.1, shifted, shift);
        if (proven.is_empty() || !proven_inner(proven)) return std::nullopt;
        for (const double fraction : {0.25, 0.5}) {
          Box larger = sub_box(fraction, shifted, shift);
          if (!proven_inner(larger)) break;
          proven = std::move(larger);
        }
        return proven;
      };
      if (auto found = grown_from(-1, 0)) return found;
      if (unknowns > 3) return std::nullopt;
      for (std::size_t k = 0; k < model::kParameterCount; ++k) {
        if (!options.unknown[k]) continue;
        for (const double shift : {-0.25, 0.25}) {
          if (auto found = grown_from(k, shift)) return found;
        }
      }
      return std::nullopt;
    };
  }
  sivia.epsilon = options.epsilon;
  sivia.threads = options.threads;
  sivia.progress = options.progress;
  sivia.max_boxes = options.max_boxes;
  sivia.max_kept_contractions = options.max_kept_contractions;
  sivia.cancel = options.cancel;
  sivia.scale.assign(model::kParameterCount, 0.0);
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    if (options.unknown[k]) {
      sivia.scale[k] = options.epsilon_relative ? options.prior[k].width() : 1.0;
    }
  }

  GuaranteedResult result;
  result.unknown = options.unknown;
  result.inner = options.inner;
  result.inner_carried = inner_test_carried(options.prior, options.unknown, options.inner);
  result.samples = n;
  result.q = options.q;
  result.paving = interval::sivia(options.prior, test, sivia);

  if (result.paving.empty_inner_and_boundary()) {
    result.empty = true;
    for (std::size_t i = 0; i < n; ++i) {
      Box prior = options.prior;
      if (constraints.proves_inconsistent(i, prior) || !constraints.contract(i, prior)) {
        result.excluding_samples.push_back(i);
      }
    }
    if (result.excluding_samples.empty()) {
      std::vector<std::size_t> order(n);
      for (std::size_t i = 0; i < n; ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return outer_causes[a].load() > outer_causes[b].load();
      });
      for (std::size_t k = 0; k < std::min<std::size_t>(10, n); ++k) {
        if (outer_causes[order[k]].load() > 0) result.excluding_samples.push_back(order[k]);
      }
    }
    std::ostringstream why;
    why << "no parameter is consistent with the data: ";
    if (result.excluding_samples.empty()) {
      why << "no single sample excludes the prior box";
    } else {
      why << "samples ";
      for (std::size_t k = 0; k < std::min<std::size_t>(result.excluding_samples.size(), 10); ++k) {
        const IntervalSample& s = constraints.sample(result.excluding_samples[k]);
        why << (k ? ", " : "") << s.experiment << "#" << s.index << " (t = " << s.t_s << " s)";
      }
      if (result.excluding_samples.size() > 10) why << " and more";
      why << " exclude it";
    }
    why << "; the error bounds may be too tight, or the model incomplete (unmodelled friction, "
           "a lag, a faulty sensor: try q-relaxation)";
    result.finding = why.str();
  } else {
    const Box hull = result.paving.outer_hull();
    for (std::size_t i = 0; i < n; ++i) {
      if (constraints.proves_inconsistent(i, hull)) result.inconsistent_samples.push_back(i);
    }
  }
  return result;
}

double unknowns_volume(const std::vector<Box>& boxes,
                       const std::array<bool, model::kParameterCount>& unknown) {
  double total = 0;
  for (const Box& b : boxes) {
    double v = 1;
    for (std::size_t k = 0; k < model::kParameterCount; ++k) {
      if (unknown[k]) v *= b[k].width();
    }
    total += v;
  }
  return total;
}

}  // namespace furuta::identification
