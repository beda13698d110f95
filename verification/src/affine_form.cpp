#include "affine_form.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace furuta::verification::detail {

namespace {

// Sums of non-negative doubles, rounded to nearest, fall short of the exact sum by at most
// n 2^-53 of it: every bound below is raised by this factor (n up to 2^20 terms) and by a
// quantity above any total of underflows.
constexpr double kRaise = 1.0 + 1e-9;
constexpr double kUnderflow = 1e-290;
constexpr double kUnit = std::numeric_limits<double>::epsilon() / 2;  // 2^-53

double l1(const Eigen::VectorXd& v) {
  return v.size() == 0 ? 0.0 : v.cwiseAbs().sum();
}

double l1(const AffineForm& a) {
  return a.norm >= 0 ? a.norm : l1(a.coef);
}

}  // namespace

Interval range(const AffineForm& a) {
  const double spread = (l1(a) + a.err) * kRaise + kUnderflow;
  return Interval(a.centre) + Interval(-spread, spread);
}

AffineForm Symbols::noise(const Interval& v) {
  AffineForm out;
  // An unbounded or empty quantity gives a form whose range is the whole line: the checks that
  // read it then fail, as they must, rather than the run stopping on an exception.
  if (!v.is_bounded()) {
    out.err = std::numeric_limits<double>::infinity();
    return out;
  }
  out.centre = v.mid();
  const double radius = v.rad();
  if (radius > 0) {
    out.coef = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(count_ + 1));
    out.coef(static_cast<Eigen::Index>(count_)) = radius;
    out.norm = radius;
    ++count_;
  }
  return out;
}

AffineForm Symbols::constant(double v) {
  AffineForm out;
  out.centre = v;
  return out;
}

LinearCombination& LinearCombination::add(const Interval& k, const AffineForm& a) {
  const double km = k.mid();
  const double kr = k.rad();
  const double size = (std::fabs(a.centre) + l1(a)) * kRaise;
  centre_ += km * a.centre;
  if (a.coef.size() > coef_.size()) {
    const Eigen::Index old = coef_.size();
    coef_.conservativeResize(a.coef.size());
    coef_.tail(a.coef.size() - old).setZero();
  }
  if (km != 0 && a.coef.size() > 0) coef_.head(a.coef.size()) += km * a.coef;
  // |k| <= |km| + kr multiplies a's own error; kr multiplies all of a.
  err_ += (std::fabs(km) + kr) * a.err * kRaise + kr * (size + a.err) * kRaise;
  rounded_ += std::fabs(km) * size * kRaise;
  ++terms_;
  return *this;
}

AffineForm LinearCombination::result() const {
  AffineForm out;
  out.centre = centre_;
  out.coef = coef_;
  out.norm = l1(coef_);
  // Each coefficient and the centre are sums of terms_ products, each rounded once and summed
  // with terms_ roundings: at most 2 terms_ 2^-53 (1 + ...) of the sum of |products|.
  const double gamma = 2.2 * terms_ * kUnit;
  out.err = (err_ + gamma * rounded_) * kRaise + kUnderflow;
  return out;
}

void reduce(std::vector<AffineForm>& forms, Symbols& symbols, std::size_t max_symbols,
            const CoordinateMap& to, const CoordinateMap& from,
            std::vector<std::vector<AffineForm>>* sensitivities) {
  const std::size_t n = forms.size();
  std::vector<std::vector<AffineForm>> none;
  std::vector<std::vector<AffineForm>>& sens = sensitivities ? *sensitivities : none;
  if (max_symbols < 3 * n)
    throw std::invalid_argument("reduce: max_symbols below thrice the forms");
  const std::size_t m = symbols.count();
  // Room for the n merged columns and the n error columns.
  const std::size_t keep = std::min(m, max_symbols - 2 * n);
  std::vector<std::size_t> order(m);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<double> merged(n, 0.0);
  const bool merging = m > keep;
  if (merging) {
    // `to` as a matrix (its columns from the unit vectors: linear, it is exact where its
    // coefficients are, else their hull), applied in double with the rounding bounded:
    // |sum_l t_l c_l - computed| <= n 2^-53 (1 + ...) sum_l |t_l| |c_l|, the latter in the
    // matrix's magnitudes.
    Eigen::MatrixXd t_mid(n, n);
    Eigen::MatrixXd t_mag(n, n);
    for (std::size_t l = 0; l < n; ++l) {
      std::vector<Interval> unit(n, Interval(0.0));
      unit[l] = Interval(1.0);
      const std::vector<Interval> col = to(unit);
      for (std::size_t i = 0; i < n; ++i) {
        t_mid(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(l)) = col[i].mid();
        t_mag(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(l)) = col[i].mag();
      }
    }
    const double rounding = 4.0 * static_cast<double>(n + 2) * kUnit;
    // A symbol's column in the coordinates `to` gives, each entry the largest it takes over the
    // sensitivities' factors in [-1, 1]: |base| + sum |sensitivity|.
    const auto column_mags = [&](const std::vector<AffineForm>& of, std::size_t j) {
      Eigen::VectorXd c(static_cast<Eigen::Index>(n));
      for (std::size_t i = 0; i < n; ++i) {
        const Eigen::VectorXd& coef = of[i].coef;
        c(static_cast<Eigen::Index>(i)) =
            static_cast<Eigen::Index>(j) < coef.size() ? coef(static_cast<Eigen::Index>(j)) : 0.0;
      }
      const Eigen::VectorXd mid = t_mid * c;
      // The hull of `to`'s coefficients about their midpoints, and the rounding.
      const Eigen::VectorXd spread =
          (t_mag - t_mid.cwiseAbs()) * c.cwiseAbs() + rounding * (t_mag * c.cwiseAbs());
      Eigen::VectorXd out = (mid.cwiseAbs() + spread) * kRaise;
      return out;
    };
    std::vector<std::vector<Interval>> y(m);
    std::vector<double> score(m);
    for (std::size_t j = 0; j < m; ++j) {
      Eigen::VectorXd total = column_mags(forms, j);
      for (const std::vector<AffineForm>& d : sens) total += column_mags(d, j);
      y[j].resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        y[j][i] = Interval(total(static_cast<Eigen::Index>(i)) * kRaise + kUnderflow);
      }
      double sum = 0;
      double largest = 0;
      for (const Interval& v : y[j]) {
        sum += v.mag();
        largest = std::max(largest, v.mag());
      }
      score[j] = sum - largest;
    }
    std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep), order.end(),
                     [&](std::size_t a, std::size_t b) { return score[a] > score[b]; });
    std::sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(keep));
    std::vector<Interval> box(n, Interval(0.0));
    for (std::size_t k = keep; k < m; ++k) {
      for (std::size_t i = 0; i < n; ++i) box[i] += Interval(y[order[k]][i].mag());
    }
    for (std::size_t i = 0; i < n; ++i) merged[i] = box[i].hi();
  }
  // The merged box's columns in the forms' coordinates: their midpoints as generators, their
  // radii into each form's error.
  std::vector<std::vector<double>> back(n, std::vector<double>(n, 0.0));
  std::vector<double> extra(n, 0.0);
  for (std::size_t i = 0; i < n && merging; ++i) {
    if (!(merged[i] > 0)) continue;
    std::vector<Interval> unit(n, Interval(0.0));
    unit[i] = Interval(merged[i]);
    const std::vector<Interval> w = from(unit);
    for (std::size_t r = 0; r < n; ++r) {
      back[i][r] = w[r].mid();
      extra[r] += w[r].rad() * kRaise;
    }
  }
  const std::size_t total = keep + (merging ? n : 0) + n;
  // A form's coefficients on the kept symbols, in their new places; zero after them.
  const auto kept = [&](const Eigen::VectorXd& old) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(total));
    for (std::size_t k = 0; k < keep; ++k) {
      const auto j = static_cast<Eigen::Index>(order[k]);
      if (j < old.size()) c(static_cast<Eigen::Index>(k)) = old(j);
    }
    return c;
  };
  for (std::size_t r = 0; r < n; ++r) {
    Eigen::VectorXd c = kept(forms[r].coef);
    if (merging) {
      for (std::size_t i = 0; i < n; ++i) c(static_cast<Eigen::Index>(keep + i)) = back[i][r];
    }
    c(static_cast<Eigen::Index>(keep + (merging ? n : 0) + r)) =
        (forms[r].err + extra[r]) * kRaise + (forms[r].err + extra[r] > 0 ? kUnderflow : 0.0);
    forms[r].coef = std::move(c);
    forms[r].err = 0;
    forms[r].norm = -1;
  }
  // The sensitivities keep the symbols kept; their errors, whatever their factors, join the
  // base's error symbols.
  for (std::vector<AffineForm>& d : sens) {
    for (std::size_t r = 0; r < n; ++r) {
      Eigen::VectorXd c = kept(d[r].coef);
      const auto error_column = static_cast<Eigen::Index>(keep + (merging ? n : 0) + r);
      forms[r].coef(error_column) =
          (Interval(forms[r].coef(error_column)) + Interval(d[r].err) * Interval(kRaise)).hi();
      d[r].coef = std::move(c);
      d[r].err = 0;
      d[r].norm = -1;
    }
  }
  for (AffineForm& f : forms) f.norm = l1(f.coef);
  for (std::vector<AffineForm>& d : sens) {
    for (AffineForm& f : d) f.norm = l1(f.coef);
  }
  symbols.reset(total);
}

}  // namespace furuta::verification::detail
