#include "furuta/identification/window_inversion.hpp"

#include <glpk.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>

#include "furuta/validated/taylor_model.hpp"

namespace furuta::identification {

namespace {

using interval::Box;
using interval::Interval;
using validated::FurutaDynamics;
using validated::InputPiece;
using validated::TaylorModel;

constexpr std::size_t kStateVariables = 4;  // q1, dq1, q2, dq2: the start's variables
constexpr std::size_t kVariables = FurutaDynamics::dimension;

// The time of the state a reading shows, as the flow stops there: its host time minus the lag's
// midpoint (the rest of the lag is the constraint's variable).
double state_time(const RecordingWindow& window, const AngleReading& reading) {
  return reading.t_s - window.lag_s.mid();
}

// The duty pieces with a switch at every reading's state time (the same duty on both sides), so
// that the flow ends a step exactly there.
std::vector<InputPiece> pieces_with_reading_times(const RecordingWindow& window) {
  std::vector<double> times;
  for (const InputPiece& piece : window.duty) times.push_back(piece.t_start);
  for (const AngleReading& reading : window.readings) {
    const double s = state_time(window, reading);
    if (s < window.t1_s) times.push_back(s);
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  std::vector<InputPiece> pieces;
  std::size_t current = 0;
  for (const double t : times) {
    while (current + 1 < window.duty.size() && window.duty[current + 1].t_start <= t) ++current;
    pieces.push_back({t, window.duty[current].tau});
  }
  return pieces;
}

void check_window(const RecordingWindow& window) {
  if (window.duty.empty()) throw std::invalid_argument("window: no duty pieces");
  if (!(window.t1_s > window.t0_s)) throw std::invalid_argument("window: t1_s must follow t0_s");
  if (window.start.size() != kStateVariables) {
    throw std::invalid_argument("window: the start box has 4 components (q1, dq1, q2, dq2)");
  }
  if (window.lag_s.is_empty() || !window.lag_s.is_bounded() ||
      window.pendulum_zero_rad.is_empty() || !window.pendulum_zero_rad.is_bounded()) {
    throw std::invalid_argument(
        "window: the lag and the pendulum's zero must be bounded intervals");
  }
  for (const AngleReading& reading : window.readings) {
    if (!(reading.t_s > window.t0_s + window.lag_s.hi() &&
          reading.t_s <= window.t1_s + window.lag_s.lo())) {
      throw std::invalid_argument("window: a reading at t = " + std::to_string(reading.t_s) +
                                  " s is outside (t0_s + lag_s.hi(), t1_s + lag_s.lo()]");
    }
    if (reading.joint != 0 && reading.joint != 1) {
      throw std::invalid_argument("window: a reading's joint must be 0 (arm) or 1 (pendulum)");
    }
  }
}

// The columns every reading shares beyond the flow's variables: the lag's and the pendulum's
// zero's (each over [-1, 1] at first).
constexpr std::size_t kGlobals = 2;
using Globals = std::array<Interval, kGlobals>;

// The variables of all windows as columns: the parameters' (flow variables 4..10) first, then
// the start variables of each epoch (a window's steps between shrink wraps). A wrap that leaves a
// start variable alone keeps its column; one that widens it opens a column tied to the one before
// by a link.
class Columns {
 public:
  static constexpr std::size_t kParameters = kVariables - kStateVariables;
  // The globals' columns after the parameters': the lag = mid + rad * lambda, the pendulum's zero
  // = mid + rad * zeta (lambda, zeta in [-1, 1]).
  static constexpr std::size_t kLag = kParameters;
  static constexpr std::size_t kZero = kParameters + 1;

  Columns() : values_(kParameters + 2, Interval(-1, 1)) {}

  Globals globals() const { return {values_[kLag], values_[kZero]}; }
  void set_globals(const Globals& g) {
    values_[kLag] = g[0];
    values_[kZero] = g[1];
  }

  // A window's first epoch: start variables of its own.
  std::size_t open_window() {
    std::array<std::size_t, kStateVariables> columns{};
    for (std::size_t v = 0; v < kStateVariables; ++v) columns[v] = add();
    epochs_.push_back(columns);
    return epochs_.size() - 1;
  }
  // The epoch after a wrap of epoch `before` with the step's scales and deltas.
  std::size_t wrap(std::size_t before, const std::vector<double>& scale,
                   const std::vector<double>& delta) {
    std::array<std::size_t, kStateVariables> columns = epochs_[before];
    for (std::size_t v = 0; v < kStateVariables; ++v) {
      const double q = v < scale.size() ? scale[v] : 0.0;
      const double d = v < delta.size() ? delta[v] : HUGE_VAL;
      if (q == 1.0 && d == 0.0) continue;  // left alone: the same variable
      const std::size_t after = add();
      if (q > 0.0 && std::isfinite(d)) links_.push_back({columns[v], after, q, d});
      columns[v] = after;
    }
    epochs_.push_back(columns);
    return epochs_.size() - 1;
  }

  std::size_t column(std::size_t epoch, std::size_t v) const {
    return v >= kStateVariables ? v - kStateVariables : epochs_[epoch][v];
  }
  std::vector<Interval> variables(std::size_t epoch) const {
    std::vector<Interval> z(kVariables);
    for (std::size_t v = 0; v < kVariables; ++v) z[v] = values_[column(epoch, v)];
    return z;
  }
  void set_variables(std::size_t epoch, const std::vector<Interval>& z) {
    for (std::size_t v = 0; v < kVariables; ++v) values_[column(epoch, v)] = z[v];
  }

  // scale * after - before in [-delta, delta]: each side narrowed by the other; false when one
  // empties.
  bool contract_links() {
    for (int pass = 0; pass < 2; ++pass) {
      for (std::size_t i = 0; i < links_.size(); ++i) {
        const Link& l = pass == 0 ? links_[i] : links_[links_.size() - 1 - i];
        const Interval slack(-l.delta, l.delta);
        Interval& before = values_[l.before];
        Interval& after = values_[l.after];
        after = intersect(after, (before + slack) / Interval(l.scale));
        if (after.is_empty()) return false;
        before = intersect(before, Interval(l.scale) * after - slack);
        if (before.is_empty()) return false;
      }
    }
    return true;
  }

  struct Link {
    std::size_t before, after;
    double scale, delta;
  };
  const std::vector<Link>& links() const { return links_; }
  std::vector<Interval>& values() { return values_; }
  const std::vector<Interval>& values() const { return values_; }

 private:
  std::size_t add() {
    values_.push_back(Interval(-1, 1));
    return values_.size() - 1;
  }
  std::vector<Interval> values_;
  std::vector<std::array<std::size_t, kStateVariables>> epochs_;
  std::vector<Link> links_;
};

// A reading's constraint: the read joint's model q and its velocity's dq at the state time s the
// flow stopped at, in the epoch of start variables there. The state the reading shows is at
// s - delta, delta = rad * lambda + offset (lambda the lag's column, offset the rounding of s), so
// the reading holds q(s) - delta dq(s) + delta^2 / 2 * acceleration (Taylor with the acceleration
// bounded around s). A pendulum reading is the angle less its zero, zero_mid + zero_rad * zeta
// (zeta the zero's column).
struct Constraint {
  const TaylorModel* model;
  const TaylorModel* velocity;
  Interval acceleration;
  double lag_rad;
  Interval offset;
  double zero_mid, zero_rad;
  Interval reading;
  std::size_t epoch;
  double t_s;
};

// The terms of degree 2 and above, and the remainder, over z (variables without a column, such
// as a ramped input's, range over [-1, 1]).
Interval nonlinear_part(const TaylorModel& m, const std::vector<Interval>& z) {
  Interval sum = m.remainder();
  if (!m.space()) return sum;
  const validated::MonomialSpace& space = *m.space();
  const std::vector<double>& coefficients = m.coefficients();
  for (std::size_t k = space.end_of_degree(1); k < space.size(); ++k) {
    if (coefficients[k] == 0.0) continue;
    Interval term(coefficients[k]);
    for (std::size_t v = 0; v < space.variables(); ++v) {
      const int e = space.exponent(k, v);
      if (e > 0) term = term * pow(v < z.size() ? z[v] : Interval(-1, 1), e);
    }
    sum = sum + term;
  }
  return sum;
}

// A model's range over z, less its constant.
Interval varying_part(const TaylorModel& m, const std::vector<Interval>& z) {
  Interval sum = nonlinear_part(m, z);
  if (!m.space()) return sum;
  for (std::size_t v = 0; v < m.space()->variables(); ++v) {
    const double a = m.coefficient(m.space()->variable(v));
    if (a != 0.0) sum = sum + Interval(a) * (v < z.size() ? z[v] : Interval(-1, 1));
  }
  return sum;
}

// A constraint as linear terms and the rest: the reading lies in c + sum_v a_v z_v + sum_g
// a_global[g] globals[g] + rest, with rest bounded over the current z and globals.
struct Linearised {
  Interval constant;
  std::array<double, kVariables> a{};
  std::array<double, kGlobals> a_global{};
  Interval rest;
};

Linearised linearise(const Constraint& c, const std::vector<Interval>& z, const Globals& g) {
  const TaylorModel& m = *c.model;
  Linearised l;
  l.constant = Interval(m.coefficient(0)) - Interval(c.zero_mid);
  l.a_global[1] = -c.zero_rad;
  l.rest = nonlinear_part(m, z);
  if (m.space()) {
    for (std::size_t v = 0; v < kVariables; ++v) l.a[v] = m.coefficient(m.space()->variable(v));
  }
  if (c.lag_rad == 0.0 && c.offset.lo() == 0.0 && c.offset.hi() == 0.0) return l;
  const Interval& lambda = g[0];
  const TaylorModel& dq = *c.velocity;
  const Interval dq_constant(dq.coefficient(0));
  const Interval dq_varying = varying_part(dq, z);
  const Interval delta = Interval(c.lag_rad) * lambda + c.offset;
  // -delta dq = -rad lambda dq_constant (linear) - rad lambda dq_varying - offset dq.
  l.a_global[0] = -(Interval(c.lag_rad) * dq_constant).mid();
  l.rest = l.rest - (Interval(c.lag_rad) * dq_constant + Interval(l.a_global[0])) * lambda -
           Interval(c.lag_rad) * lambda * dq_varying - c.offset * (dq_constant + dq_varying) +
           Interval(0.5) * sqr(delta) * c.acceleration;
  return l;
}

// Narrows z and the globals with one constraint; false when it proves the constraint cannot
// hold.
bool contract_with_reading(const Constraint& c, std::vector<Interval>& z, Globals& g) {
  const Linearised l = linearise(c, z, g);
  constexpr std::size_t kAll = kVariables + kGlobals;
  const auto coefficient = [&](std::size_t v) {
    return v < kVariables ? l.a[v] : l.a_global[v - kVariables];
  };
  const auto variable = [&](std::size_t v) -> Interval& {
    return v < kVariables ? z[v] : g[v - kVariables];
  };
  std::array<Interval, kAll> linear{};
  for (std::size_t v = 0; v < kAll; ++v) linear[v] = Interval(coefficient(v)) * variable(v);
  Interval all = l.constant + l.rest;
  for (const Interval& term : linear) all = all + term;
  if (intersect(all, c.reading).is_empty()) return false;
  for (std::size_t v = 0; v < kAll; ++v) {
    const double a = coefficient(v);
    if (a == 0.0) continue;
    Interval others = c.reading - l.constant - l.rest;
    for (std::size_t w = 0; w < kAll; ++w) {
      if (w != v) others = others - linear[w];
    }
    Interval& x = variable(v);
    x = intersect(x, others / Interval(a));
    if (x.is_empty()) return false;
    linear[v] = Interval(a) * x;
  }
  return true;
}

// One linear row of the joint system: sum of coefficient * column in residual.
struct SparseRow {
  std::vector<std::pair<std::size_t, double>> terms;
  Interval residual;
};

// The linear relaxation's exact hull, made rigorous: for each column i and each direction, the
// linear program min (max) z_i over the rows' slabs (A z in r) and the box gives row multipliers
// y (its duals); whatever y is, z_i = y' A z + (e_i - A' y)' z lies in y' r + (e_i - A' y)' [z],
// evaluated in interval arithmetic, so the floating-point LP only chooses y. Where many readings
// each pin a slab, their intersection (a polytope) is far narrower than what one preconditioner
// P (a weighted average of the rows, whose worst case is the sum of |P| times the rows' widths)
// can show: the slabs' hull shrinks with the count of readings, the sum does not. False when a
// column is emptied.
bool contract_by_linear_programs(const std::vector<SparseRow>& rows, std::vector<Interval>& z) {
  struct ProblemDeleter {
    void operator()(glp_prob* p) const { glp_delete_prob(p); }
  };
  const std::unique_ptr<glp_prob, ProblemDeleter> lp(glp_create_prob());
  const int m = static_cast<int>(rows.size());
  const int n = static_cast<int>(z.size());
  glp_add_rows(lp.get(), m);
  glp_add_cols(lp.get(), n);
  // Each row scaled by its width (the LP's conditioning; the multipliers are scaled back).
  std::vector<double> scale(rows.size(), 1.0);
  std::vector<int> ia{0}, ja{0};
  std::vector<double> ar{0.0};
  for (int k = 0; k < m; ++k) {
    const SparseRow& row = rows[static_cast<std::size_t>(k)];
    const double width = row.residual.width();
    if (!(width > 0.0) || !std::isfinite(width)) {
      glp_set_row_bnds(lp.get(), k + 1, GLP_FR, 0.0, 0.0);
      continue;
    }
    scale[static_cast<std::size_t>(k)] = 1.0 / width;
    const double lo = row.residual.lo() / width;
    const double hi = row.residual.hi() / width;
    glp_set_row_bnds(lp.get(), k + 1, lo < hi ? GLP_DB : GLP_FX, lo, lo < hi ? hi : lo);
    for (const auto& [j, a] : row.terms) {
      ia.push_back(k + 1);
      ja.push_back(static_cast<int>(j) + 1);
      ar.push_back(a / width);
    }
  }
  glp_load_matrix(lp.get(), static_cast<int>(ar.size()) - 1, ia.data(), ja.data(), ar.data());
  for (int j = 0; j < n; ++j) {
    const Interval& zj = z[static_cast<std::size_t>(j)];
    if (zj.lo() < zj.hi()) {
      glp_set_col_bnds(lp.get(), j + 1, GLP_DB, zj.lo(), zj.hi());
    } else {
      glp_set_col_bnds(lp.get(), j + 1, GLP_FX, zj.lo(), zj.lo());
    }
  }
  glp_smcp parameters;
  glp_init_smcp(&parameters);
  parameters.msg_lev = GLP_MSG_OFF;
  std::vector<double> y(rows.size());
  for (int i = 0; i < n; ++i) {
    for (const int direction : {GLP_MIN, GLP_MAX}) {
      for (int j = 0; j < n; ++j) glp_set_obj_coef(lp.get(), j + 1, j == i ? 1.0 : 0.0);
      glp_set_obj_dir(lp.get(), direction);
      if (glp_simplex(lp.get(), &parameters) != 0) continue;
      const int status = glp_get_status(lp.get());
      if (status == GLP_NOFEAS) {
        // The relaxation looks empty; only the rigorous bound below may say so.
      } else if (status != GLP_OPT) {
        continue;
      }
      for (int k = 0; k < m; ++k) {
        y[static_cast<std::size_t>(k)] =
            glp_get_row_dual(lp.get(), k + 1) * scale[static_cast<std::size_t>(k)];
      }
      Interval bound(0.0);
      std::vector<Interval> coupling(z.size(), Interval(0.0));  // (A' y)_j
      for (std::size_t k = 0; k < rows.size(); ++k) {
        if (y[k] == 0.0 || !std::isfinite(y[k])) continue;
        const Interval yk(y[k]);
        bound = bound + yk * rows[k].residual;
        for (const auto& [j, a] : rows[k].terms) coupling[j] = coupling[j] + yk * Interval(a);
      }
      for (std::size_t j = 0; j < z.size(); ++j) {
        const Interval c = Interval(static_cast<int>(j) == i ? 1.0 : 0.0) - coupling[j];
        if (c.lo() == 0.0 && c.hi() == 0.0) continue;
        bound = bound + c * z[j];
      }
      Interval& zi = z[static_cast<std::size_t>(i)];
      zi = direction == GLP_MIN ? intersect(zi, Interval(bound.lo(), zi.hi()))
                                : intersect(zi, Interval(zi.lo(), bound.hi()));
      if (zi.is_empty()) return false;
      if (zi.lo() < zi.hi()) {
        glp_set_col_bnds(lp.get(), i + 1, GLP_DB, zi.lo(), zi.hi());
      } else {
        glp_set_col_bnds(lp.get(), i + 1, GLP_FX, zi.lo(), zi.lo());
      }
    }
  }
  return true;
}

// Each column as an affine image of its chain's first column: z_c in factor * z_root + slack,
// from the links (after = (before + [-delta, delta]) / scale), in column order (a link's before
// column is always older than its after column).
struct RootForm {
  std::vector<std::size_t> root;
  std::vector<double> factor;
  std::vector<Interval> slack;
};

RootForm root_form(const Columns& columns) {
  const std::size_t n = columns.values().size();
  RootForm form{std::vector<std::size_t>(n), std::vector<double>(n, 1.0),
                std::vector<Interval>(n, Interval(0.0))};
  for (std::size_t c = 0; c < n; ++c) form.root[c] = c;
  std::vector<Interval> factor(n, Interval(1.0));
  for (const Columns::Link& l : columns.links()) {
    const Interval q(l.scale);
    form.root[l.after] = form.root[l.before];
    factor[l.after] = factor[l.before] / q;
    form.slack[l.after] = (form.slack[l.before] + Interval(-l.delta, l.delta)) / q;
  }
  // The factor's rounding goes into the slack, over the root's range.
  const std::vector<Interval>& z = columns.values();
  for (std::size_t c = 0; c < n; ++c) {
    form.factor[c] = factor[c].mid();
    form.slack[c] = form.slack[c] + (factor[c] - Interval(form.factor[c])) * z[form.root[c]];
  }
  return form;
}

// All readings together, each window's start columns replaced by the first epoch's through the
// links (a column whose slack is wider than its own range stays out, its term in the residual):
// with A the rows' linear coefficients in the parameters' columns and the windows' first start
// columns, A z lies in r = y - c - h - (the slack terms). For any matrix P, z = P A z + (I - P
// A) z, so z_i lies in (P r)_i + sum_j (I - P A)_ij z_j: sound whatever P is, evaluated in
// interval arithmetic. The P's tried are ridge-regularised weighted least-squares inverses, P =
// (A' W^2 A + mu I)^-1 A' W^2 with W the rows' inverse widths: with mu small P A is close to I
// but P amplifies the rows' widths; larger mu leaves more of the other variables' ranges in, with
// less amplification. Each mu gives an enclosure; all are intersected, and carried back to every
// column through its chain. False when a column is emptied.
bool contract_together(const std::vector<Constraint>& constraints, Columns& columns) {
  std::vector<Interval>& values = columns.values();
  const RootForm form = root_form(columns);
  // The reduced columns: every root, numbered.
  std::vector<std::size_t> reduced_of(values.size(), static_cast<std::size_t>(-1));
  std::vector<std::size_t> column_of_reduced;
  for (std::size_t c = 0; c < values.size(); ++c) {
    if (form.root[c] == c) {
      reduced_of[c] = column_of_reduced.size();
      column_of_reduced.push_back(c);
    }
  }
  const std::size_t n = column_of_reduced.size();
  std::vector<SparseRow> rows;
  for (const Constraint& c : constraints) {
    const TaylorModel& m = *c.model;
    if (!m.space()) return true;
    const Linearised l = linearise(c, columns.variables(c.epoch), columns.globals());
    SparseRow row;
    row.residual = c.reading - l.constant - l.rest;
    if (l.a_global[0] != 0.0) row.terms.push_back({reduced_of[Columns::kLag], l.a_global[0]});
    if (l.a_global[1] != 0.0) row.terms.push_back({reduced_of[Columns::kZero], l.a_global[1]});
    for (std::size_t v = 0; v < kVariables; ++v) {
      const double a = l.a[v];
      if (a == 0.0) continue;
      const std::size_t col = columns.column(c.epoch, v);
      const Interval through_root = Interval(a) * form.slack[col];
      const Interval own = Interval(a) * values[col];
      if (form.root[col] != col && through_root.width() >= own.width()) {
        row.residual = row.residual - own;
        continue;
      }
      row.residual = row.residual - through_root;
      const double coefficient = (Interval(a) * Interval(form.factor[col])).mid();
      row.residual =
          row.residual - (Interval(a) * Interval(form.factor[col]) - Interval(coefficient)) *
                             values[form.root[col]];
      // Each slot's chain has its own root, so a row meets a root once.
      row.terms.push_back({reduced_of[form.root[col]], coefficient});
    }
    rows.push_back(std::move(row));
  }
  if (rows.size() < 2) return true;
  std::vector<Interval> z(n);
  for (std::size_t i = 0; i < n; ++i) z[i] = values[column_of_reduced[i]];
  const auto cols = static_cast<Eigen::Index>(n);
  Eigen::SparseMatrix<double> weighted(static_cast<Eigen::Index>(rows.size()), cols);
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd weight(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double width = rows[k].residual.width();
    // A row without width (or unbounded) is left out: P may ignore any row.
    const double w = (width > 0.0 && std::isfinite(width)) ? 1.0 / width : 0.0;
    weight(static_cast<Eigen::Index>(k)) = w;
    for (const auto& [j, a] : rows[k].terms) {
      triplets.emplace_back(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j), w * a);
    }
  }
  weighted.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::MatrixXd gram = Eigen::MatrixXd(weighted.transpose() * weighted);
  const double scale = gram.diagonal().maxCoeff();
  if (!(scale > 0.0) || !std::isfinite(scale)) return true;
  const Eigen::MatrixXd weighted_t = Eigen::MatrixXd(weighted.transpose()) * weight.asDiagonal();
  for (const double relative : {1e-10, 1e-7, 1e-4, 1e-2}) {
    const Eigen::MatrixXd regularised =
        gram + relative * scale * Eigen::MatrixXd::Identity(cols, cols);
    const Eigen::MatrixXd p = regularised.ldlt().solve(weighted_t);
    if (!p.allFinite()) continue;
    for (std::size_t i = 0; i < n; ++i) {
      const auto row = static_cast<Eigen::Index>(i);
      Interval bound(0.0);
      std::vector<Interval> coupling(n, Interval(0.0));  // (P A)_ij
      for (std::size_t k = 0; k < rows.size(); ++k) {
        const double pik_value = p(row, static_cast<Eigen::Index>(k));
        if (pik_value == 0.0) continue;
        const Interval pik(pik_value);
        bound = bound + pik * rows[k].residual;
        for (const auto& [j, a] : rows[k].terms) coupling[j] = coupling[j] + pik * Interval(a);
      }
      for (std::size_t j = 0; j < n; ++j) {
        const Interval c = Interval(i == j ? 1.0 : 0.0) - coupling[j];
        if (c.lo() == 0.0 && c.hi() == 0.0) continue;
        bound = bound + c * z[j];
      }
      z[i] = intersect(z[i], bound);
      if (z[i].is_empty()) return false;
    }
  }
  if (!contract_by_linear_programs(rows, z)) return false;
  for (std::size_t i = 0; i < n; ++i) values[column_of_reduced[i]] = z[i];
  for (std::size_t c = 0; c < values.size(); ++c) {
    if (form.root[c] == c) continue;
    values[c] =
        intersect(values[c], Interval(form.factor[c]) * values[form.root[c]] + form.slack[c]);
    if (values[c].is_empty()) return false;
  }
  return true;
}

double widest_relative_width(const std::vector<Interval>& before,
                             const std::vector<Interval>& after) {
  double gain = 0.0;
  for (std::size_t v = 0; v < before.size(); ++v) {
    if (before[v].width() > 0.0) gain = std::max(gain, 1.0 - after[v].width() / before[v].width());
  }
  return gain;
}

model::Parameters<Interval> parameters_of(const Box& x) {
  return {x[FurutaDynamics::mu1], x[FurutaDynamics::mu2], x[FurutaDynamics::mu3],
          x[FurutaDynamics::mu4], x[FurutaDynamics::mug], x[FurutaDynamics::fv1],
          x[FurutaDynamics::fv2]};
}

// One pass: the flows over `parameters`, then the contraction.
// The acceleration of `joint` (0: arm, 1: pendulum) over the steps that meet [t0, t1]: the model
// over the hull of their boxes, the input over the hull of its values there. Unbounded when the
// steps do not reach t1.
Interval acceleration_around(const validated::TaylorModelFlowResult& flow,
                             const RecordingWindow& window, int joint, double t0, double t1) {
  if (flow.steps.empty() || flow.steps.back().t1 < t1) return Interval::entire();
  Box hull;
  for (const validated::TaylorModelFlowStep& step : flow.steps) {
    if (step.t1 < t0 || step.t0 > t1) continue;
    hull = hull.size() == 0 ? step.over : interval::hull(hull, step.over);
  }
  if (hull.size() == 0) return Interval::entire();
  Interval input;
  if (window.ramped) {
    input = hull[validated::FurutaRampedDynamics::input];
  } else {
    input = window.duty.front().tau;
    for (const InputPiece& piece : window.duty) input = interval::hull(input, piece.tau);
  }
  const model::Parameters<Interval> p{hull[FurutaDynamics::mu1], hull[FurutaDynamics::mu2],
                                      hull[FurutaDynamics::mu3], hull[FurutaDynamics::mu4],
                                      hull[FurutaDynamics::mug], hull[FurutaDynamics::fv1],
                                      hull[FurutaDynamics::fv2]};
  const model::JointAccelerations<Interval> a = model::accelerations(
      p, hull[FurutaDynamics::q2], hull[FurutaDynamics::dq1], hull[FurutaDynamics::dq2], input);
  return joint == 0 ? a.ddq1 : a.ddq2;
}

// One pass: the flows over `parameters` (every window's lag_s the same), then the contraction.
WindowOutcome one_pass(const std::vector<RecordingWindow>& windows,
                       const model::Parameters<Interval>& parameters,
                       const WindowOptions& options) {
  WindowOutcome out;
  out.parameters = parameters;
  out.start = windows.front().start;
  const Interval lag = windows.front().lag_s;
  out.lag_s = lag;
  const double lag_mid = lag.mid();
  const double lag_rad = (lag - Interval(lag_mid)).mag();
  const Interval zero = windows.front().pendulum_zero_rad;
  out.pendulum_zero_rad = zero;
  const double zero_mid = zero.mid();
  const double zero_rad = (zero - Interval(zero_mid)).mag();
  std::vector<Box> x0s;
  for (const RecordingWindow& window : windows) {
    x0s.push_back(window.ramped ? validated::FurutaRampedDynamics::initial_box(
                                      window.start, parameters, window.duty_start)
                                : FurutaDynamics::initial_box(window.start, parameters));
  }
  // The windows' flows are independent: run side by side (a paver calling this from its own
  // threads shares TBB's workers with it).
  std::vector<validated::TaylorModelFlowResult> results(windows.size());
  tbb::parallel_for(std::size_t{0}, windows.size(), [&](std::size_t w) {
    validated::TaylorModelFlowOptions flow = options.flow;
    flow.integrator.t_start = windows[w].t0_s;
    flow.integrator.t_end = windows[w].t1_s;
    flow.keep_end_models = true;
    const std::vector<InputPiece> pieces = pieces_with_reading_times(windows[w]);
    results[w] = windows[w].ramped
                     ? validated::integrate_taylor_models(validated::FurutaRampedDynamics(pieces),
                                                          x0s[w], flow)
                     : validated::integrate_taylor_models(FurutaDynamics(pieces), x0s[w], flow);
  });
  for (const validated::TaylorModelFlowResult& result : results) {
    out.flow_steps += result.steps.size();
    out.shrink_wraps += result.shrink_wraps;
    out.flow_seconds += result.seconds;
    if (!result.ok() && out.reason.empty()) out.reason = result.reason;
  }

  // Each reading against the step that ends at its state time (the flow ends a step at every
  // switch); each window's start variables are its own, tied across its shrink wraps; the
  // parameters' and the lag's are shared by all.
  Columns columns;
  std::vector<Constraint> constraints;
  std::vector<std::vector<std::size_t>> step_epochs(windows.size());
  for (std::size_t w = 0; w < windows.size(); ++w) {
    const RecordingWindow& window = windows[w];
    std::size_t epoch = columns.open_window();
    std::size_t next = 0;
    for (const validated::TaylorModelFlowStep& step : results[w].steps) {
      for (; next < window.readings.size() && state_time(window, window.readings[next]) <= step.t1;
           ++next) {
        const AngleReading& reading = window.readings[next];
        const double s = state_time(window, reading);
        if (std::abs(s - step.t1) > 1e-12 * std::max(1.0, std::abs(step.t1))) continue;
        const std::size_t joint = reading.joint == 0 ? FurutaDynamics::q1 : FurutaDynamics::q2;
        const std::size_t speed = reading.joint == 0 ? FurutaDynamics::dq1 : FurutaDynamics::dq2;
        // The state is at t - lag = s - (lag - lag_mid) - (t - s - lag_mid).
        const Interval offset = (Interval(reading.t_s) - Interval(step.t1)) - Interval(lag_mid);
        Interval acceleration(0.0);
        if (lag_rad > 0.0 || offset.lo() != 0.0 || offset.hi() != 0.0) {
          const double reach = lag_rad + offset.mag();
          acceleration =
              acceleration_around(results[w], window, reading.joint, s - reach, s + reach);
          if (!acceleration.is_bounded()) continue;  // the flow ended too soon to use it
        }
        const bool pendulum = reading.joint == 1;
        constraints.push_back({&step.end_models[joint], &step.end_models[speed], acceleration,
                               lag_rad, offset, pendulum ? zero_mid : 0.0,
                               pendulum ? zero_rad : 0.0, reading.angle_rad, epoch, reading.t_s});
        const double width = reading.angle_rad.width();
        if (width > 0.0) {
          out.widest_prediction =
              std::max(out.widest_prediction, step.end_models[joint].bound().width() / width);
        }
      }
      step_epochs[w].push_back(epoch);  // the epoch of this step's end models
      if (step.wrapped) epoch = columns.wrap(epoch, step.wrap_scale, step.wrap_delta);
    }
  }
  if (constraints.empty()) {
    out.verdict = WindowVerdict::flow_failed;
    if (out.reason.empty()) out.reason = "no reading within the flows' steps";
    return out;
  }

  for (out.sweeps = 0; out.sweeps < static_cast<std::size_t>(options.max_sweeps);) {
    ++out.sweeps;
    const std::vector<Interval> before = columns.values();
    for (const Constraint& c : constraints) {
      std::vector<Interval> z = columns.variables(c.epoch);
      Globals g = columns.globals();
      const bool met = contract_with_reading(c, z, g);
      columns.set_globals(g);
      if (!met) {
        out.verdict = WindowVerdict::inconsistent;
        out.reason = "the reading at t = " + std::to_string(c.t_s) + " s cannot be met";
        return out;
      }
      columns.set_variables(c.epoch, z);
    }
    if (!columns.contract_links()) {
      out.verdict = WindowVerdict::inconsistent;
      out.reason = "the readings before and after a shrink wrap cannot be met together";
      return out;
    }
    if (!contract_together(constraints, columns)) {
      out.verdict = WindowVerdict::inconsistent;
      out.reason = "the window's readings together cannot be met";
      return out;
    }
    if (widest_relative_width(before, columns.values()) < options.min_sweep_gain) break;
  }

  // Back from z to the parameters and the start: each as the flow's own variable over its part.
  const auto space = std::make_shared<validated::MonomialSpace>(kVariables, 1);
  std::vector<std::size_t> all(kVariables);
  for (std::size_t v = 0; v < kVariables; ++v) all[v] = v;
  const std::vector<Interval> z = columns.variables(0);
  const Box& x0 = x0s.front();
  Box x = x0;
  for (std::size_t v = 0; v < kVariables; ++v) {
    if (x0[v].is_point()) continue;
    const Interval part = TaylorModel::variable(space, v, x0[v]).bounded_in(all, z).bound();
    x[v] = intersect(x0[v], part);
  }
  for (std::size_t v = 0; v < kStateVariables; ++v) out.start[v] = x[v];
  out.parameters = parameters_of(x);
  out.lag_s =
      intersect(lag, Interval(lag_mid) + Interval(lag_rad) * columns.values()[Columns::kLag]);
  out.pendulum_zero_rad =
      intersect(zero, Interval(zero_mid) + Interval(zero_rad) * columns.values()[Columns::kZero]);
  out.verdict = WindowVerdict::contracted;
  // Each window's end: a step's models over their epoch's contracted variables; the last step's
  // when the flow carried the window, else the step at restart_fraction of the way to where it
  // stopped (a flow stops where its set has grown too wide to go on: not a box to start from).
  for (std::size_t w = 0; w < windows.size(); ++w) {
    const validated::TaylorModelFlowResult& result = results[w];
    Box end;
    double end_time = windows[w].t0_s;
    std::size_t chosen = result.steps.size();
    if (!result.steps.empty()) {
      chosen = result.steps.size() - 1;
      if (!result.ok()) {
        const double at =
            windows[w].t0_s + options.restart_fraction * (result.steps.back().t1 - windows[w].t0_s);
        while (chosen > 0 && result.steps[chosen].t1 > at) --chosen;
      }
    }
    if (chosen < result.steps.size() && result.steps[chosen].end_models.size() >= kStateVariables) {
      const validated::TaylorModelFlowStep& step = result.steps[chosen];
      end_time = step.t1;
      std::vector<Interval> zw = columns.variables(step_epochs[w][chosen]);
      const TaylorModel& first = step.end_models.front();
      const std::size_t n = first.space() ? first.space()->variables() : kVariables;
      zw.resize(n, Interval(-1, 1));  // a ramped input's variable has no column
      end = Box(kStateVariables);
      for (std::size_t v = 0; v < kStateVariables; ++v) {
        end[v] = intersect(step.end[v], step.end_models[v].bounded_in(all, zw).bound());
      }
    }
    out.ends.push_back(std::move(end));
    out.end_times.push_back(end_time);
    out.reached.push_back(result.steps.empty() ? windows[w].t0_s : result.steps.back().t1);
  }
  return out;
}

}  // namespace

WindowOutcome invert_windows(const std::vector<RecordingWindow>& windows,
                             const model::Parameters<Interval>& parameters,
                             const WindowOptions& options) {
  if (windows.empty()) throw std::invalid_argument("windows: none given");
  for (const RecordingWindow& window : windows) check_window(window);
  // One lag for all: the hull of the windows' (each pass narrows it).
  std::vector<RecordingWindow> common = windows;
  Interval lag = windows.front().lag_s;
  Interval zero = windows.front().pendulum_zero_rad;
  for (const RecordingWindow& window : windows) {
    lag = interval::hull(lag, window.lag_s);
    zero = interval::hull(zero, window.pendulum_zero_rad);
  }
  for (RecordingWindow& window : common) {
    window.lag_s = lag;
    window.pendulum_zero_rad = zero;
  }
  WindowOutcome out = one_pass(common, parameters, options);
  out.passes = 1;
  while (out.verdict == WindowVerdict::contracted &&
         out.passes < static_cast<std::size_t>(options.max_passes)) {
    const auto widths = [](const model::Parameters<Interval>& p) {
      return std::vector<Interval>{p.mu1, p.mu2, p.mu3, p.mu4, p.mug, p.fv1, p.fv2};
    };
    const std::vector<Interval> before = widths(parameters);
    const std::vector<Interval> now = widths(out.parameters);
    if (out.passes == 1 && widest_relative_width(before, now) < options.min_pass_gain) break;
    for (RecordingWindow& window : common) {
      window.lag_s = out.lag_s;
      window.pendulum_zero_rad = out.pendulum_zero_rad;
    }
    WindowOutcome next = one_pass(common, out.parameters, options);
    // A pass whose flows carry no reading concludes nothing: the last contraction stands.
    if (next.verdict == WindowVerdict::flow_failed) break;
    next.passes = out.passes + 1;
    next.flow_steps += out.flow_steps;
    next.shrink_wraps += out.shrink_wraps;
    next.flow_seconds += out.flow_seconds;
    const double gain = widest_relative_width(now, widths(next.parameters));
    out = std::move(next);
    if (gain < options.min_pass_gain) break;
  }
  return out;
}

}  // namespace furuta::identification

namespace furuta::identification {

WindowOptions default_window_options() {
  WindowOptions o;
  o.flow.integrator.order = 8;
  o.flow.integrator.tolerance = 1e-8;
  o.flow.integrator.max_inflation = 1.0;
  o.flow.integrator.max_width = 2 * std::numbers::pi;
  o.flow.space_order = 3;
  o.flow.wrap_without_collapsed = true;
  o.flow.wrap_at_base_point = true;
  o.flow.shrink_wrap_max_delta = 1.0;
  o.max_passes = 3;
  return o;
}

WindowOutcome invert_window(const RecordingWindow& window,
                            const model::Parameters<Interval>& parameters,
                            const WindowOptions& options) {
  return invert_windows({window}, parameters, options);
}

}  // namespace furuta::identification
