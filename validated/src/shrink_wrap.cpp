// Shrink wrapping of the Taylor-model flow's error part (see shrink_wrap.hpp). Why the test on
// delta is enough: for z and e fixed, G(z') = z' - A (p(z') - p(z) - e) over z' in
// Z = z_s + [-delta, delta] (the other variables at z) is
//   G(z') - z_s = (I - A M)(z' - z_s) + A e,  M the mean-value matrix of p's rows in the slots,
// whose entries lie in the slots' partial derivatives over the widened box W = [-(1 + delta),
// 1 + delta] x [-1, 1]. So |G(z') - z_s| <= |I - A M| delta + |A e| <= delta: G maps Z into itself,
// Brouwer gives z' in Z with G(z') = z'. The test is strict, C delta + a < delta with delta > 0
// and C = |I - A M| >= 0, so C's spectral radius is below 1 (Perron-Frobenius): every A M is
// invertible, A with it, and G(z') = z' means p(z') = p(z) + e. Each row has its own mean-value
// point, on the segment from z_s to z', inside W. With z' = q w, w in [-1, 1]: p(q w) = p(z) + e.
//
// A may depend on anything held fixed in that argument, the other variables z_theta (the
// parameters) among them: the argument runs for each z_theta on its own. Taking A(z_theta) as the
// first-order inverse of the slots' linear coefficients L(z_theta) leaves in I - A M only what
// L's first-order dependence on the parameters does not explain, so C is bounded as a Taylor
// model in z_theta (the rows' own points in the slots bounded into each entry's remainder). With
// a constant A, the parameters' spread over the bench box soon makes C pass 1; with A(z_theta)
// the parameters' part of C stays small, and the slots' own nonlinear terms, which each wrap
// multiplies by (1 + delta)^(degree - 1) against the linear ones, are what end it
// (docs/measurements/taylor-model-flow.md, "Taylor models III").
//
// A may as well depend on z itself, the slots included (the argument runs for each z and e; the
// point z' sought is near z, not z). At the base point (attempt_wrap_at_base_point), A(z) is D(z)'s
// inverse to the models' order, D the rows' derivatives in the slots, by Newton's iteration on
// models; then I - A M = (I - A D(z)) + A (D(z) - M), and each row of M is D's row at a point of
// the segment from z to z', within delta of z in the slots and inside W, so |D(z) - M| <= sum_l
// |dD / dz_l over W| delta_l. C is thus left with D's change within delta of z, where the attempt
// over the box keeps its change over all of W. The Furuta arm's left-out row, whose error is
// carried from step to step, needs that: over the box its delta comes out well above its |A e|
// each step, and the carried error grows by as much (docs/measurements/taylor-model-flow.md,
// "Taylor models V").

#include "shrink_wrap.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

namespace furuta::validated::detail {

Eigen::MatrixXd linear_part(const std::vector<TaylorModel>& p, const std::vector<std::size_t>& rows,
                            const std::vector<std::size_t>& slots, std::size_t kept, double scale) {
  const MonomialSpace& space = *p.front().space();
  const std::size_t m = rows.size();
  const auto em = static_cast<Eigen::Index>(m);
  Eigen::MatrixXd l(em, em);
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      l(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          j == kept ? (i == j ? scale : 0.0) : p[rows[i]].coefficient(space.variable(slots[j]));
    }
  }
  return l;
}

std::optional<Eigen::MatrixXd> linear_part_inverse(const std::vector<TaylorModel>& p,
                                                   const std::vector<std::size_t>& rows,
                                                   const std::vector<std::size_t>& slots,
                                                   std::size_t kept, double scale) {
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(linear_part(p, rows, slots, kept, scale));
  if (!lu.isInvertible()) return std::nullopt;
  Eigen::MatrixXd a = lu.inverse();
  if (!a.allFinite()) return std::nullopt;
  return a;
}

namespace {

constexpr std::size_t kNone = static_cast<std::size_t>(-1);
constexpr int kNewtonIterations = 3;
constexpr double kDeltaMargin = 0.01;
constexpr int kDeltaAttempts = 16;

using ModelMatrix = std::vector<std::vector<TaylorModel>>;

// I - left right.
ModelMatrix residual(const ModelMatrix& left, const ModelMatrix& right,
                     const std::shared_ptr<const MonomialSpace>& space) {
  const std::size_t m = left.size();
  ModelMatrix r(m, std::vector<TaylorModel>(m));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      TaylorModel sum(space, Interval(i == j ? 1.0 : 0.0));
      for (std::size_t k = 0; k < m; ++k) sum -= left[i][k] * right[k][j];
      r[i][j] = std::move(sum);
    }
  }
  return r;
}

// A ~ d^-1 by Newton's iteration A <- A + A (I - d A) from a0, each A kept as its polynomial.
ModelMatrix inverse_model(const ModelMatrix& d, const Eigen::MatrixXd& a0,
                          const std::shared_ptr<const MonomialSpace>& space) {
  const std::size_t m = d.size();
  ModelMatrix am(m, std::vector<TaylorModel>(m));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t k = 0; k < m; ++k) {
      am[i][k] = TaylorModel(
          space, Interval(a0(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k))));
    }
  }
  for (int iteration = 0; iteration < kNewtonIterations; ++iteration) {
    const ModelMatrix r = residual(d, am, space);
    ModelMatrix next(m, std::vector<TaylorModel>(m));
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t j = 0; j < m; ++j) {
        TaylorModel sum = am[i][j];
        for (std::size_t k = 0; k < m; ++k) sum += am[i][k] * r[k][j];
        next[i][j] = sum.polynomial();
      }
    }
    am = std::move(next);
  }
  return am;
}

// Krawczyk's test with the preconditioner am (a polynomial in z): the smallest delta found, each
// slot's at most max_delta (the kept slot's unbounded), with C delta + a < delta, or nothing.
std::optional<std::vector<double>> krawczyk_delta(const ModelMatrix& am, const ModelMatrix& d,
                                                  const std::vector<double>& e_mag,
                                                  const std::vector<std::size_t>& slots,
                                                  std::size_t kept, double max_delta) {
  const std::size_t m = d.size();
  const auto space = d.front().front().space();
  const std::size_t nv = space->variables();
  // |I - A D| and |A| over the unit box, and |A e|, the error in the slots' units.
  const ModelMatrix r0 = residual(am, d, space);
  std::vector<std::vector<double>> r0_mag(m, std::vector<double>(m));
  std::vector<std::vector<double>> a_mag(m, std::vector<double>(m));
  std::vector<double> ae(m, 0.0);
  for (std::size_t i = 0; i < m; ++i) {
    Interval s(0.0);
    for (std::size_t j = 0; j < m; ++j) {
      r0_mag[i][j] = r0[i][j].bound().mag();
      a_mag[i][j] = am[i][j].bound().mag();
      s += Interval(a_mag[i][j]) * Interval(e_mag[j]);
    }
    ae[i] = s.hi();
    if (!std::isfinite(ae[i])) return std::nullopt;
  }
  // delta from a little above |A e|, raised to a little above C delta + a until it holds.
  std::vector<double> delta = ae;
  for (double& x : delta) x *= 1.0 + kDeltaMargin;
  for (int attempt = 0; attempt < kDeltaAttempts; ++attempt) {
    for (double& x : delta) x = std::max(x, 1e-300);
    for (std::size_t j = 0; j < m; ++j) {
      if (j != kept && delta[j] > max_delta) return std::nullopt;
    }
    std::vector<Interval> box(nv, Interval(-1.0, 1.0));
    for (std::size_t j = 0; j < m; ++j) {
      if (j == kept) continue;
      const double w = (Interval(1.0) + Interval(delta[j])).hi();
      box[slots[j]] = Interval(-w, w);
    }
    // |D(z) - D(xi)| for xi within delta of z in the slots: the derivatives' slopes in the
    // slots over the widened box times delta, plus twice D's rounding.
    std::vector<std::vector<Interval>> dd(m, std::vector<Interval>(m, Interval(0.0)));
    for (std::size_t k = 0; k < m; ++k) {
      for (std::size_t j = 0; j < m; ++j) {
        if (j == kept) continue;
        Interval sum = Interval(2.0) * Interval(d[k][j].remainder().mag());
        for (std::size_t l = 0; l < m; ++l) {
          if (l == kept) continue;
          sum += Interval(d[k][j].partial_over(slots[l], box).mag()) * Interval(delta[l]);
        }
        dd[k][j] = sum;
      }
    }
    // C delta + a, C = |I - A D| + |A| |D - D(xi)|, rounded up.
    Eigen::MatrixXd c(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
    std::vector<double> next(m, 0.0);
    for (std::size_t i = 0; i < m; ++i) {
      Interval s = Interval(ae[i]);
      for (std::size_t j = 0; j < m; ++j) {
        Interval cij = Interval(r0_mag[i][j]);
        for (std::size_t k = 0; k < m; ++k) cij += Interval(a_mag[i][k]) * dd[k][j];
        c(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = cij.hi();
        s += Interval(cij.hi()) * Interval(delta[j]);
      }
      next[i] = s.hi();
    }
    bool inside = true;
    for (std::size_t i = 0; i < m; ++i) inside = inside && next[i] < delta[i];
    if (inside) return delta;
    // Raise delta towards the fixed point (I - C)^-1 a of this C (C grows with delta, slowly), or
    // where that has no positive solution, to a little above C delta + a. Only raised: a margin
    // on every row each round compounds (the kept row's error, carried from step to step, would
    // grow by that margin every round).
    const Eigen::VectorXd a_vec =
        Eigen::Map<const Eigen::VectorXd>(ae.data(), static_cast<Eigen::Index>(m));
    const Eigen::VectorXd fixed =
        (Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m)) - c)
            .fullPivLu()
            .solve(a_vec);
    const bool usable = fixed.allFinite() && (fixed.array() > 0.0).all();
    for (std::size_t i = 0; i < m; ++i) {
      const double target = usable ? fixed(static_cast<Eigen::Index>(i)) : next[i];
      delta[i] = std::max(delta[i], (1.0 + kDeltaMargin) * std::max(target, next[i]));
    }
  }
  return std::nullopt;
}

// The wrap that passed with delta: p rescaled in place, p(q z_s, z_theta) with q = 1 + delta off
// the kept slot, and the new error part (p's rounding; on the kept row, its part scale c).
ShrinkWrap widened(std::vector<TaylorModel>& p, const std::vector<std::size_t>& rows,
                   const std::vector<std::size_t>& slots, std::size_t kept, double scale,
                   const std::vector<double>& delta) {
  ShrinkWrap out;
  std::vector<double> widen(p.front().space()->variables(), 1.0);
  out.delta.assign(widen.size(), 0.0);
  for (std::size_t j = 0; j < slots.size(); ++j) {
    if (j == kept) continue;
    widen[slots[j]] = (Interval(1.0) + Interval(delta[j])).hi();
    out.delta[slots[j]] = delta[j];
  }
  out.scale = widen;
  out.rest.assign(p.size(), Interval(0.0));
  for (std::size_t v = 0; v < p.size(); ++v) {
    TaylorModel q = p[v].rescaled(widen);
    // Off the rows (the constant components) a remainder stays in p: the error part is zero
    // there (taylor_model_flow_core.hpp).
    if (std::find(rows.begin(), rows.end(), v) == rows.end()) {
      p[v] = std::move(q);
      continue;
    }
    out.rest[v] = q.remainder();
    p[v] = q.polynomial();
  }
  if (kept != kNone) {
    out.rest[rows[kept]] += Interval(scale) * Interval(-delta[kept], delta[kept]);
    out.kept = kept;
  }
  out.done = true;
  return out;
}

// One attempt with A depending on the other variables (the parameters) to first order and M over
// the widened box; `kept` (an index into slots, or kNone) names a slot that is not widened: its
// column in L and M is the unit vector of its row times `scale`, an unknown c in [-delta, delta]
// whose part, scale c, stays in the error part on that row.
ShrinkWrap attempt_wrap_over_box(std::vector<TaylorModel>& p, const std::vector<Interval>& e,
                                 const std::vector<std::size_t>& rows,
                                 const std::vector<std::size_t>& slots, double max_delta,
                                 std::size_t kept) {
  ShrinkWrap out;
  const std::size_t m = rows.size();
  const MonomialSpace& space = *p.front().space();
  const std::size_t nv = space.variables();
  const auto em = static_cast<Eigen::Index>(m);
  const double scale = kept == kNone ? 0.0 : std::max(e[rows[kept]].mag(), 1e-300);
  const std::optional<Eigen::MatrixXd> l_inverse = linear_part_inverse(p, rows, slots, kept, scale);
  if (!l_inverse) return out;
  const Eigen::MatrixXd& a = *l_inverse;
  // A(z) = A0 - A0 L1(z) A0, L1(z) the slots' linear coefficients' first-order dependence on the
  // other variables (the parameters): the inverse of L(z) to first order, so that I - A M is left
  // with only what L(z) does not explain (the file's head says why A may depend on them).
  std::vector<std::size_t> others;
  for (std::size_t w = 0; w < nv; ++w) {
    if (std::find(slots.begin(), slots.end(), w) == slots.end()) others.push_back(w);
  }
  std::vector<std::vector<TaylorModel>> derivatives(m, std::vector<TaylorModel>(m));
  for (std::size_t k = 0; k < m; ++k) {
    for (std::size_t j = 0; j < m; ++j) {
      if (j != kept) derivatives[k][j] = p[rows[k]].derivative(slots[j]);
    }
  }
  const auto space_ptr = p.front().space();
  std::vector<std::vector<TaylorModel>> am(m, std::vector<TaylorModel>(m));
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t k = 0; k < m; ++k) {
      am[i][k] = TaylorModel(
          space_ptr, Interval(a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k))));
    }
  }
  for (std::size_t w : others) {
    Eigen::MatrixXd l1 = Eigen::MatrixXd::Zero(em, em);
    for (std::size_t k = 0; k < m; ++k) {
      for (std::size_t j = 0; j < m; ++j) {
        if (j != kept) {
          l1(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)) =
              derivatives[k][j].coefficient(space.variable(w));
        }
      }
    }
    if (l1.isZero(0.0)) continue;
    const Eigen::MatrixXd a1 = -(a * l1 * a);
    const TaylorModel zw = TaylorModel::variable(space_ptr, w, Interval(-1.0, 1.0));
    for (std::size_t i = 0; i < m; ++i) {
      for (std::size_t k = 0; k < m; ++k) {
        const double c = a1(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
        if (c != 0.0 && std::isfinite(c)) am[i][k] += zw * Interval(c);
      }
    }
  }
  // |A e|, the error in the slots' units, over every value of the other variables.
  std::vector<double> ae(m, 0.0);
  for (std::size_t i = 0; i < m; ++i) {
    Interval s(0.0);
    for (std::size_t k = 0; k < m; ++k) {
      s += Interval(am[i][k].bound().mag()) * Interval(e[rows[k]].mag());
    }
    ae[i] = s.hi();
    if (!std::isfinite(ae[i])) return out;
  }
  // delta from a little above |A e|, raised to a little above C delta + a until it holds.
  std::vector<double> delta = ae;
  for (double& d : delta) d *= 1.05;
  for (int attempt = 0; attempt < 12; ++attempt) {
    for (double& d : delta) d = std::max(d, 1e-300);
    for (std::size_t j = 0; j < m; ++j) {
      if (j != kept && delta[j] > max_delta) return out;
    }
    std::vector<Interval> box(nv, Interval(-1.0, 1.0));
    for (std::size_t j = 0; j < m; ++j) {
      if (j == kept) continue;
      const double w = (Interval(1.0) + Interval(delta[j])).hi();
      box[slots[j]] = Interval(-w, w);
    }
    // M: the slots' derivatives of the rows over the widened box, each row at its own point of
    // it (the slots' terms bounded into each entry's remainder), the other variables common to
    // all rows; C = |I - A M| bounded over them.
    std::vector<std::vector<TaylorModel>> mm(m, std::vector<TaylorModel>(m));
    for (std::size_t k = 0; k < m; ++k) {
      for (std::size_t j = 0; j < m; ++j) {
        mm[k][j] = j == kept ? TaylorModel(Interval(k == j ? scale : 0.0))
                             : derivatives[k][j].bounded_in(slots, box);
      }
    }
    std::vector<double> next(m, 0.0);  // C delta + a, rounded up
    for (std::size_t i = 0; i < m; ++i) {
      Interval s = Interval(ae[i]);
      for (std::size_t j = 0; j < m; ++j) {
        TaylorModel entry(i == j ? 1.0 : 0.0);
        for (std::size_t k = 0; k < m; ++k) entry -= am[i][k] * mm[k][j];
        s += Interval(entry.bound().mag()) * Interval(delta[j]);
      }
      next[i] = s.hi();
    }
    bool inside = true;
    for (std::size_t i = 0; i < m; ++i) inside = inside && next[i] < delta[i];
    if (inside) return widened(p, rows, slots, kept, scale, delta);
    for (std::size_t i = 0; i < m; ++i) delta[i] = 1.05 * std::max(next[i], delta[i]);
  }
  return out;
}

// One attempt with A depending on every variable, A(z) ~ D(z)^-1, and M - D(z) bounded by the
// derivatives' slopes times delta (the file's head says why); `kept` (an index into slots, or
// kNone) names a slot that is not widened: its column in D is the unit vector of its row times
// `scale`, an unknown c in [-delta, delta] whose part, scale c, stays in the error part on that
// row.
ShrinkWrap attempt_wrap_at_base_point(std::vector<TaylorModel>& p, const std::vector<Interval>& e,
                                      const std::vector<std::size_t>& rows,
                                      const std::vector<std::size_t>& slots, double max_delta,
                                      std::size_t kept) {
  ShrinkWrap out;
  const std::size_t m = rows.size();
  const auto space = p.front().space();
  const double scale = kept == kNone ? 0.0 : std::max(e[rows[kept]].mag(), 1e-300);
  const std::optional<Eigen::MatrixXd> a0 = linear_part_inverse(p, rows, slots, kept, scale);
  if (!a0) return out;
  // D(z): the rows' derivatives in the slots, models in every variable (the kept column constant).
  ModelMatrix d(m, std::vector<TaylorModel>(m));
  for (std::size_t k = 0; k < m; ++k) {
    for (std::size_t j = 0; j < m; ++j) {
      d[k][j] = j == kept ? TaylorModel(space, Interval(k == j ? scale : 0.0))
                          : p[rows[k]].derivative(slots[j]);
    }
  }
  std::vector<double> e_mag(m);
  for (std::size_t i = 0; i < m; ++i) e_mag[i] = e[rows[i]].mag();
  const std::optional<std::vector<double>> delta =
      krawczyk_delta(inverse_model(d, *a0, space), d, e_mag, slots, kept, max_delta);
  if (!delta) return out;
  return widened(p, rows, slots, kept, scale, *delta);
}

// The wrap at the base point where it passes (when asked), else over the box; nothing for
// arguments that do not fit (no rows, a slot per row, p on a space).
ShrinkWrap attempt_wrap(std::vector<TaylorModel>& p, const std::vector<Interval>& e,
                        const std::vector<std::size_t>& rows, const std::vector<std::size_t>& slots,
                        double max_delta, std::size_t kept, bool at_base_point) {
  if (rows.empty() || slots.size() != rows.size() || p.empty() || !p.front().space()) return {};
  if (at_base_point) {
    ShrinkWrap out = attempt_wrap_at_base_point(p, e, rows, slots, max_delta, kept);
    if (out.done) return out;
  }
  return attempt_wrap_over_box(p, e, rows, slots, max_delta, kept);
}

// The slots to leave out, best first: those whose leaving out gives an invertible L whose inverse
// needs the least widening, max over the other slots of |L^-1| |e| (a first estimate of delta).
std::vector<std::size_t> slots_to_leave_out(const std::vector<TaylorModel>& p,
                                            const std::vector<Interval>& e,
                                            const std::vector<std::size_t>& rows,
                                            const std::vector<std::size_t>& slots) {
  const std::size_t m = rows.size();
  Eigen::VectorXd e_mag(static_cast<Eigen::Index>(m));
  for (std::size_t i = 0; i < m; ++i) e_mag(static_cast<Eigen::Index>(i)) = e[rows[i]].mag();
  std::vector<std::pair<double, std::size_t>> ranked;
  for (std::size_t j = 0; j < m; ++j) {
    const double scale = std::max(e[rows[j]].mag(), 1e-300);
    const std::optional<Eigen::MatrixXd> l_inverse = linear_part_inverse(p, rows, slots, j, scale);
    if (!l_inverse) continue;
    const Eigen::VectorXd ae = l_inverse->cwiseAbs() * e_mag;
    double widening = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      if (i != j) widening = std::max(widening, ae(static_cast<Eigen::Index>(i)));
    }
    if (std::isfinite(widening)) ranked.emplace_back(widening, j);
  }
  std::sort(ranked.begin(), ranked.end());
  std::vector<std::size_t> out;
  for (const auto& [widening, j] : ranked) out.push_back(j);
  return out;
}

}  // namespace

ShrinkWrap shrink_wrap(std::vector<TaylorModel>& p, const std::vector<Interval>& e,
                       const std::vector<std::size_t>& rows, const std::vector<std::size_t>& slots,
                       double max_delta, bool leave_out_slot, bool at_base_point) {
  ShrinkWrap out = attempt_wrap(p, e, rows, slots, max_delta, kNone, at_base_point);
  if (out.done || !leave_out_slot || rows.size() < 2 || slots.size() != rows.size() || p.empty() ||
      !p.front().space()) {
    return out;
  }
  const std::vector<std::size_t> candidates = slots_to_leave_out(p, e, rows, slots);
  for (std::size_t c = 0; c < std::min<std::size_t>(candidates.size(), 2); ++c) {
    out = attempt_wrap(p, e, rows, slots, max_delta, candidates[c], at_base_point);
    if (out.done) return out;
  }
  return out;
}

}  // namespace furuta::validated::detail
