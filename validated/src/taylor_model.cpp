// Taylor models (see taylor_model.hpp). Every coefficient is computed as an interval and split into
// its midpoint and the rest over its monomial's range, which goes into the remainder: the models'
// soundness rests on the interval core's outward rounding alone.

#include "furuta/validated/taylor_model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace furuta::validated {

namespace {

const Interval kUnit(-1.0, 1.0);
const Interval kHalfUnit(0.0, 1.0);

const std::shared_ptr<const MonomialSpace>& common_space(const TaylorModel& a,
                                                         const TaylorModel& b) {
  if (a.space() && b.space() && a.space() != b.space()) {
    throw std::invalid_argument("TaylorModel: operands in different monomial spaces");
  }
  return a.space() ? a.space() : b.space();
}

}  // namespace

MonomialSpace::MonomialSpace(std::size_t variables, int order)
    : variables_(variables), order_(order) {
  if (variables == 0 || variables > 16)
    throw std::invalid_argument("MonomialSpace: 1..16 variables");
  if (order < 0 || order > 12) throw std::invalid_argument("MonomialSpace: order 0..12");
  // Graded: all exponent vectors of degree d, for d = 0..order, in lexicographic order.
  std::vector<std::uint8_t> e(variables, 0);
  for (int d = 0; d <= order; ++d) {
    // Compositions of d into `variables` parts, lexicographically from (d, 0, ..., 0).
    std::fill(e.begin(), e.end(), 0);
    e[0] = static_cast<std::uint8_t>(d);
    for (;;) {
      exponents_.insert(exponents_.end(), e.begin(), e.end());
      degrees_.push_back(d);
      // Next composition: move one unit from the last nonzero part before the end rightwards.
      std::size_t last = variables;
      for (std::size_t v = variables - 1; v-- > 0;) {
        if (e[v] > 0) {
          last = v;
          break;
        }
      }
      if (last == variables) break;
      const std::uint8_t tail = e[variables - 1];
      e[variables - 1] = 0;
      --e[last];
      e[last + 1] = static_cast<std::uint8_t>(tail + 1);
    }
  }
  const std::size_t n = size();
  // The product table is size()^2 entries: 11 variables of order 4 are 1,365 monomials (15 MB).
  if (n > 2048) throw std::invalid_argument("MonomialSpace: more than 2048 monomials");
  ends_.assign(static_cast<std::size_t>(order) + 1, 0);
  for (std::size_t m = 0; m < n; ++m) ends_[static_cast<std::size_t>(degrees_[m])] = m + 1;
  ranges_.resize(n);
  for (std::size_t m = 0; m < n; ++m) {
    bool all_even = true;
    for (std::size_t v = 0; v < variables; ++v) all_even = all_even && exponent(m, v) % 2 == 0;
    ranges_[m] = degrees_[m] == 0 ? Interval(1.0) : (all_even ? kHalfUnit : kUnit);
  }
  // Products: look each up by its exponent vector.
  std::vector<std::size_t> offset(static_cast<std::size_t>(order) + 2, 0);
  for (std::size_t m = 0; m < n; ++m) offset[static_cast<std::size_t>(degrees_[m]) + 1] = m + 1;
  products_.assign(n * n, npos);
  std::vector<std::uint8_t> sum(variables);
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = 0; b < n; ++b) {
      const int d = degrees_[a] + degrees_[b];
      if (d > order) continue;
      for (std::size_t v = 0; v < variables; ++v) {
        sum[v] = static_cast<std::uint8_t>(exponents_[a * variables + v] +
                                           exponents_[b * variables + v]);
      }
      const std::size_t first = d == 0 ? 0 : offset[static_cast<std::size_t>(d)];
      for (std::size_t m = first; m < n && degrees_[m] == d; ++m) {
        if (std::equal(sum.begin(), sum.end(),
                       exponents_.begin() + static_cast<std::ptrdiff_t>(m * variables))) {
          products_[a * n + b] = m;
          break;
        }
      }
    }
  }
}

Interval MonomialSpace::product_range(std::size_t a, std::size_t b) const {
  if (degrees_[a] + degrees_[b] == 0) return Interval(1.0);
  for (std::size_t v = 0; v < variables_; ++v) {
    if ((exponent(a, v) + exponent(b, v)) % 2 != 0) return kUnit;
  }
  return kHalfUnit;
}

TaylorModel::TaylorModel(std::shared_ptr<const MonomialSpace> space, const Interval& value)
    : space_(std::move(space)), remainder_(0.0) {
  if (!space_) {
    remainder_ = value;
    return;
  }
  coefficients_.assign(space_->size(), 0.0);
  if (!value.is_bounded()) {
    remainder_ = value;
    return;
  }
  coefficients_[0] = value.mid();
  remainder_ = value - Interval(coefficients_[0]);
}

TaylorModel TaylorModel::variable(std::shared_ptr<const MonomialSpace> space, std::size_t v,
                                  const Interval& range) {
  if (!space || v >= space->variables()) throw std::invalid_argument("TaylorModel::variable");
  std::vector<Interval> c(space->size(), Interval(0.0));
  const double mid = range.mid();
  c[0] = Interval(mid);
  // z in [-1, 1] maps onto [mid - rad, mid + rad], rad >= both distances from mid: holds range.
  c[space->variable(v)] = Interval(range.rad());
  return from_intervals(std::move(space), c, Interval(0.0));
}

double TaylorModel::coefficient(std::size_t m) const {
  return m < coefficients_.size() ? coefficients_[m] : 0.0;
}

TaylorModel TaylorModel::from_intervals(std::shared_ptr<const MonomialSpace> space,
                                        const std::vector<Interval>& coefficients,
                                        Interval remainder) {
  TaylorModel out;
  out.space_ = std::move(space);
  out.coefficients_.assign(coefficients.size(), 0.0);
  for (std::size_t m = 0; m < coefficients.size(); ++m) {
    const Interval& c = coefficients[m];
    if (!c.is_bounded()) {
      out.remainder_ = Interval::entire();
      return out;
    }
    out.coefficients_[m] = c.mid();
    if (!c.is_point()) remainder += (c - Interval(out.coefficients_[m])) * out.space_->range(m);
  }
  out.remainder_ = remainder;
  return out;
}

Interval TaylorModel::polynomial_bound() const {
  if (!space_) return Interval(0.0);
  const MonomialSpace& s = *space_;
  Interval sum(coefficients_[0]);
  // Per variable, its linear and pure square terms as one quadratic a z + b z^2 over [-1, 1]:
  // the hull of the ends and, when it may lie inside, the vertex.
  std::vector<bool> done(s.size(), false);
  done[0] = true;
  for (std::size_t v = 0; v < s.variables(); ++v) {
    const std::size_t lin = s.variable(v);
    const std::size_t sq = s.order() >= 2 ? s.product(lin, lin) : MonomialSpace::npos;
    const Interval a(coefficients_[lin]);
    done[lin] = true;
    if (sq == MonomialSpace::npos || coefficients_[sq] == 0.0) {
      sum += a * kUnit;
      continue;
    }
    done[sq] = true;
    const Interval b(coefficients_[sq]);
    Interval range = hull(b + a, b - a);
    if (std::abs(coefficients_[lin]) <= 2.0 * std::abs(coefficients_[sq]) * (1.0 + 1e-12)) {
      range = hull(range, -sqr(a) / (Interval(4.0) * b));
    }
    sum += range;
  }
  for (std::size_t m = 0; m < s.size(); ++m) {
    if (!done[m] && coefficients_[m] != 0.0) sum += Interval(coefficients_[m]) * s.range(m);
  }
  return sum;
}

namespace {

// z^e of monomial m over the box z, with one power of variable `less` taken off (npos: none).
Interval powers_over(const MonomialSpace& s, std::size_t m, const std::vector<Interval>& z,
                     std::size_t less = MonomialSpace::npos) {
  Interval product(1.0);
  for (std::size_t v = 0; v < s.variables(); ++v) {
    const int e = s.exponent(m, v) - (v == less ? 1 : 0);
    if (e > 0) product = product * pow(z[v], e);
  }
  return product;
}

// The terms of degree >= 2 over the box z (each a product of interval powers), and the constant and
// linear terms over it.
Interval nonlinear_over(const std::vector<double>& c, const MonomialSpace& s,
                        const std::vector<Interval>& z) {
  Interval sum(0.0);
  for (std::size_t m = 1 + s.variables(); m < s.size(); ++m) {
    if (c[m] != 0.0) sum += Interval(c[m]) * powers_over(s, m, z);
  }
  return sum;
}

// A lower bound of the polynomial over [-1, 1]^n by the linear-dominated bounder (Makino and
// Berz): a minimiser z* lies, in each variable v, within (nu - nl) / |a_v| of the end where the
// linear term a_v z_v is least ([nl, nu] the rest's range over the current box): farther away
// the linear part alone rises by more than the rest can fall, above p at that corner, which is at
// most the linear minimum plus nu. So the box shrinks towards that corner, and the bound over
// the shrunk box (term by term) bounds the minimum. Every step rounds outwards or upwards.
double linear_dominated_lower(const std::vector<double>& c, const MonomialSpace& s) {
  const std::size_t n = s.variables();
  std::vector<Interval> z(n, kUnit);
  double best = -HUGE_VAL;
  for (int iteration = 0; iteration < 4; ++iteration) {
    const Interval rest = nonlinear_over(c, s, z);
    Interval linear(c[0]);
    for (std::size_t v = 0; v < n; ++v) linear += Interval(c[s.variable(v)]) * z[v];
    best = std::max(best, (linear + rest).lo());
    if (!rest.is_bounded()) break;
    const Interval spread = Interval(rest.hi()) - Interval(rest.lo());
    bool shrunk = false;
    for (std::size_t v = 0; v < n; ++v) {
      const double a = c[s.variable(v)];
      if (a == 0.0) continue;
      const double d = (spread / Interval(std::abs(a))).hi();
      if (!(d < z[v].width())) continue;
      z[v] = a > 0.0 ? Interval(z[v].lo(), (Interval(z[v].lo()) + Interval(d)).hi())
                     : Interval((Interval(z[v].hi()) - Interval(d)).lo(), z[v].hi());
      shrunk = true;
    }
    if (!shrunk) break;
  }
  return best;
}

}  // namespace

Interval TaylorModel::bound() const {
  if (!space_) return remainder_;
  // The quadratic-per-variable bound, cut by the linear-dominated bounds from below and above.
  std::vector<double> negated(coefficients_.size());
  for (std::size_t m = 0; m < negated.size(); ++m) negated[m] = -coefficients_[m];
  const Interval linear_dominated(linear_dominated_lower(coefficients_, *space_),
                                  -linear_dominated_lower(negated, *space_));
  return intersect(polynomial_bound(), linear_dominated) + remainder_;
}

Interval TaylorModel::evaluate(const std::vector<double>& z) const {
  if (!space_) return remainder_;
  const MonomialSpace& s = *space_;
  if (z.size() != s.variables()) throw std::invalid_argument("TaylorModel::evaluate: dimension");
  Interval sum = remainder_;
  for (std::size_t m = 0; m < s.size(); ++m) {
    if (coefficients_[m] == 0.0) continue;
    Interval term(coefficients_[m]);
    for (std::size_t v = 0; v < s.variables(); ++v) {
      for (int p = 0; p < s.exponent(m, v); ++p) term = term * Interval(z[v]);
    }
    sum += term;
  }
  return sum;
}

TaylorModel TaylorModel::reduced_to(std::shared_ptr<const MonomialSpace> lower) const {
  if (!lower) throw std::invalid_argument("TaylorModel::reduced_to: no space");
  if (!space_) return *this;
  if (lower->variables() != space_->variables() || lower->order() > space_->order()) {
    throw std::invalid_argument("TaylorModel::reduced_to: not a lower order of the same variables");
  }
  // Graded monomials: the lower space's are a prefix of this one's, in the same order.
  const std::size_t kept = lower->size();
  TaylorModel high = *this;
  std::fill(high.coefficients_.begin(), high.coefficients_.begin() + static_cast<long>(kept), 0.0);
  TaylorModel out;
  out.space_ = std::move(lower);
  out.coefficients_.assign(coefficients_.begin(), coefficients_.begin() + static_cast<long>(kept));
  out.remainder_ = remainder_ + high.polynomial_bound();
  return out;
}

TaylorModel TaylorModel::rescaled(const std::vector<double>& s) const {
  if (!space_) return *this;
  const MonomialSpace& sp = *space_;
  if (s.size() != sp.variables()) throw std::invalid_argument("TaylorModel::rescaled: dimension");
  const std::vector<Interval> scale(s.begin(), s.end());
  std::vector<Interval> c(sp.size(), Interval(0.0));
  for (std::size_t m = 0; m < sp.size(); ++m) {
    if (coefficients_[m] != 0.0) c[m] = Interval(coefficients_[m]) * powers_over(sp, m, scale);
  }
  return from_intervals(space_, c, remainder_);
}

TaylorModel TaylorModel::restricted(std::size_t v, double centre, double scale) const {
  if (!space_) return *this;
  const MonomialSpace& sp = *space_;
  if (v >= sp.variables()) throw std::invalid_argument("TaylorModel::restricted: variable");
  if (!(std::abs(centre) + std::abs(scale) <= 1.0)) {
    throw std::invalid_argument("TaylorModel::restricted: centre, scale reach outside [-1, 1]");
  }
  // lower[m]: the monomial m / z_v (npos when z_v does not divide m).
  std::vector<std::size_t> lower(sp.size(), MonomialSpace::npos);
  for (std::size_t m = 0; m < sp.size(); ++m) {
    const std::size_t up = sp.product(m, sp.variable(v));
    if (up != MonomialSpace::npos) lower[up] = m;
  }
  // a z^e z_v^k = a z^e (c + s z_v)^k = a z^e sum_j binom(k, j) c^(k-j) s^j z_v^j: the term j
  // lands on m divided k - j times by z_v.
  const Interval c(centre);
  const Interval s(scale);
  std::vector<Interval> out(sp.size(), Interval(0.0));
  for (std::size_t m = 0; m < sp.size(); ++m) {
    if (coefficients_[m] == 0.0) continue;
    const int k = sp.exponent(m, v);
    std::size_t target = m;
    Interval binomial(1.0);
    for (int j = k; j >= 0; --j) {
      out[target] += Interval(coefficients_[m]) * binomial * pow(c, k - j) * pow(s, j);
      if (j > 0) {
        binomial =
            binomial * Interval(static_cast<double>(j)) / Interval(static_cast<double>(k - j + 1));
        target = lower[target];
      }
    }
  }
  return from_intervals(space_, out, remainder_);
}

TaylorModel TaylorModel::derivative(std::size_t v) const {
  if (!space_) return TaylorModel(0.0);
  const MonomialSpace& sp = *space_;
  if (v >= sp.variables()) throw std::invalid_argument("TaylorModel::derivative: variable");
  std::vector<Interval> out(sp.size(), Interval(0.0));
  for (std::size_t m = 0; m < sp.size(); ++m) {
    const std::size_t up = sp.product(m, sp.variable(v));
    if (up == MonomialSpace::npos || coefficients_[up] == 0.0) continue;
    out[m] = Interval(coefficients_[up]) * Interval(static_cast<double>(sp.exponent(up, v)));
  }
  return from_intervals(space_, out, Interval(0.0));
}

TaylorModel TaylorModel::bounded_in(const std::vector<std::size_t>& vars,
                                    const std::vector<Interval>& ranges) const {
  if (!space_) return *this;
  const MonomialSpace& sp = *space_;
  if (ranges.size() != sp.variables()) throw std::invalid_argument("TaylorModel::bounded_in");
  std::vector<Interval> box(sp.variables(), kUnit);
  for (std::size_t w : vars) {
    if (w >= sp.variables()) throw std::invalid_argument("TaylorModel::bounded_in: variable");
    box[w] = ranges[w];
  }
  TaylorModel out = *this;
  for (std::size_t m = 0; m < sp.size(); ++m) {
    if (coefficients_[m] == 0.0) continue;
    const bool in_vars =
        std::any_of(vars.begin(), vars.end(), [&](std::size_t w) { return sp.exponent(m, w) > 0; });
    if (!in_vars) continue;
    out.remainder_ += Interval(coefficients_[m]) * powers_over(sp, m, box);
    out.coefficients_[m] = 0.0;
  }
  return out;
}

Interval TaylorModel::partial_over(std::size_t v, const std::vector<Interval>& box) const {
  if (!space_) return Interval(0.0);
  const MonomialSpace& sp = *space_;
  if (box.size() != sp.variables() || v >= sp.variables()) {
    throw std::invalid_argument("TaylorModel::partial_over: dimension");
  }
  Interval sum(0.0);
  for (std::size_t m = 0; m < sp.size(); ++m) {
    const int ev = sp.exponent(m, v);
    if (coefficients_[m] == 0.0 || ev == 0) continue;
    sum +=
        Interval(coefficients_[m]) * Interval(static_cast<double>(ev)) * powers_over(sp, m, box, v);
  }
  return sum;
}

TaylorModel& TaylorModel::add_to_remainder(const Interval& extra) {
  remainder_ += extra;
  return *this;
}

TaylorModel& TaylorModel::operator+=(const TaylorModel& y) {
  return *this = *this + y;
}
TaylorModel& TaylorModel::operator-=(const TaylorModel& y) {
  return *this = *this - y;
}

TaylorModel operator+(const TaylorModel& a, const TaylorModel& b) {
  const auto& space = common_space(a, b);
  if (!space) return TaylorModel(a.remainder_ + b.remainder_);
  // A constant operand goes into the constant coefficient (its midpoint), not the remainder: the
  // constant coefficient is the centre that sin, cos and 1/x expand about.
  if (!a.space_) return TaylorModel(space, a.remainder_) + b;
  if (!b.space_) return a + TaylorModel(space, b.remainder_);
  std::vector<Interval> c(space->size(), Interval(0.0));
  for (std::size_t m = 0; m < c.size(); ++m)
    c[m] = Interval(a.coefficients_[m]) + Interval(b.coefficients_[m]);
  return TaylorModel::from_intervals(space, c, a.remainder_ + b.remainder_);
}

TaylorModel operator-(const TaylorModel& a, const TaylorModel& b) {
  return a + (-b);
}

TaylorModel operator-(const TaylorModel& a) {
  TaylorModel out = a;
  for (double& c : out.coefficients_) c = -c;  // exact
  out.remainder_ = -a.remainder_;
  return out;
}

TaylorModel operator*(const TaylorModel& a, const Interval& k) {
  // An exact zero (the derivatives a gradient starts with) stays a constant: p 0 + R 0 = 0.
  if (!a.space_ || (k.lo() == 0.0 && k.hi() == 0.0)) return TaylorModel(a.remainder_ * k);
  std::vector<Interval> c(a.coefficients_.size(), Interval(0.0));
  for (std::size_t m = 0; m < c.size(); ++m) c[m] = Interval(a.coefficients_[m]) * k;
  return TaylorModel::from_intervals(a.space_, c, a.remainder_ * k);
}

TaylorModel operator/(const TaylorModel& a, const Interval& k) {
  if (!a.space_) return TaylorModel(a.remainder_ / k);
  std::vector<Interval> c(a.coefficients_.size(), Interval(0.0));
  for (std::size_t m = 0; m < c.size(); ++m) c[m] = Interval(a.coefficients_[m]) / k;
  return TaylorModel::from_intervals(a.space_, c, a.remainder_ / k);
}

TaylorModel operator*(const TaylorModel& a, const TaylorModel& b) {
  if (!b.space_) return a * b.remainder_;
  if (!a.space_) return b * a.remainder_;
  const auto& space = common_space(a, b);
  const MonomialSpace& s = *space;
  std::vector<Interval> c(s.size(), Interval(0.0));
  // (pa + Ra)(pb + Rb) = pa pb + pa Rb + pb Ra + Ra Rb. Only the pairs of degree <= k are
  // multiplied out (the monomials are graded, so b's partners of a_i are a prefix); the rest of
  // pa pb is bounded by sum_i |a_i| (sum of |b_j| over deg j > k - deg i) over [-1, 1].
  const int k = s.order();
  std::vector<Interval> b_tail(static_cast<std::size_t>(k) + 2, Interval(0.0));  // by degree
  for (std::size_t j = s.size(); j-- > 0;) {
    if (b.coefficients_[j] != 0.0)
      b_tail[static_cast<std::size_t>(s.degree(j))] += Interval(std::abs(b.coefficients_[j]));
  }
  for (int d = k; d-- > 0;)
    b_tail[static_cast<std::size_t>(d)] += b_tail[static_cast<std::size_t>(d) + 1];
  Interval high_magnitude(0.0);
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (a.coefficients_[i] == 0.0) continue;
    const Interval ai(a.coefficients_[i]);
    const int room = k - s.degree(i);
    const std::size_t end = s.end_of_degree(room);
    for (std::size_t j = 0; j < end; ++j) {
      if (b.coefficients_[j] == 0.0) continue;
      c[s.product(i, j)] += ai * Interval(b.coefficients_[j]);
    }
    high_magnitude +=
        Interval(std::abs(a.coefficients_[i])) * b_tail[static_cast<std::size_t>(room) + 1];
  }
  const Interval high = Interval(-high_magnitude.hi(), high_magnitude.hi());
  const Interval remainder = high + a.polynomial_bound() * b.remainder_ +
                             b.polynomial_bound() * a.remainder_ + a.remainder_ * b.remainder_;
  return TaylorModel::from_intervals(space, c, remainder);
}

TaylorModel sqr(const TaylorModel& a) {
  return a * a;
}

TaylorModel TaylorModel::compose(const TaylorModel& a, const Expand& expand) {
  // q = a - c, c its constant coefficient: q's polynomial has no constant term. xi of the
  // Lagrange term lies between c and the value: in the hull of c and c + q's range.
  TaylorModel q = a;
  q.coefficients_[0] = 0.0;
  const Interval q_range = q.bound();
  const double c = a.coefficients_[0];
  const int k = a.space_->order();
  const std::optional<Expansion> e = expand(c, hull(Interval(c) + q_range, Interval(c)), k);
  if (!e) {
    TaylorModel out(a.space_, Interval(0.0));
    out.remainder_ = Interval::entire();
    return out;
  }
  // Horner: (((d_k q + d_(k-1)) q + ...) q + d_0.
  TaylorModel sum(a.space_, e->d[static_cast<std::size_t>(k)]);
  for (int i = k - 1; i >= 0; --i)
    sum = sum * q + TaylorModel(a.space_, e->d[static_cast<std::size_t>(i)]);
  return sum.add_to_remainder(e->lagrange * pow(q_range, k + 1));
}

TaylorModel reciprocal(const TaylorModel& a) {
  if (!a.space_) return TaylorModel(Interval(1.0) / a.remainder_);
  // 1/x about c: d_i = (-1)^i / c^(i+1), and the rest of the geometric series exactly,
  // 1/x - sum_{i<=k} (c - x)^i / c^(i+1) = (c - x)^(k+1) / (c^(k+1) x), x in range. The Lagrange
  // form, (c - x)^(k+1) / xi^(k+2), would take the smallest |xi| k + 1 times more: far wider on a
  // range that comes near 0, as the Furuta model's determinant does over a wide set
  // (docs/measurements/taylor-model-flow.md, "Taylor models VI").
  return TaylorModel::compose(
      a, [](double c, const Interval& range, int k) -> std::optional<TaylorModel::Expansion> {
        if (range.contains_zero() || !range.is_bounded()) return std::nullopt;
        TaylorModel::Expansion e{std::vector<Interval>(static_cast<std::size_t>(k) + 1), {}};
        const Interval inv = Interval(1.0) / Interval(c);
        Interval power = inv;
        for (int i = 0; i <= k; ++i) {
          e.d[static_cast<std::size_t>(i)] = i % 2 == 0 ? power : -power;
          power = power * inv;
        }
        // power is now c^-(k+2); the tail needs c^-(k+1) / x.
        const Interval tail = power * Interval(c) / range;
        e.lagrange = (k + 1) % 2 == 0 ? tail : -tail;
        return e;
      });
}

TaylorModel operator/(const TaylorModel& a, const TaylorModel& b) {
  if (!b.space_) return a / b.remainder_;
  return a * reciprocal(b);
}

namespace {

// f^(i)(c) / i! for f = sin (shift 0) or cos (shift 1), i = 0..k, and the Lagrange factor
// f^(k+1)(range) / (k+1)!.
TaylorModel::Expand sin_cos_expansion(int shift) {
  return [shift](double c, const Interval& range, int k) -> std::optional<TaylorModel::Expansion> {
    // The derivatives cycle: sin, cos, -sin, -cos.
    auto derivative = [&](const Interval& x, int i) {
      switch ((i + shift) % 4) {
        case 0:
          return interval::sin(x);
        case 1:
          return interval::cos(x);
        case 2:
          return -interval::sin(x);
        default:
          return -interval::cos(x);
      }
    };
    TaylorModel::Expansion e{std::vector<Interval>(static_cast<std::size_t>(k) + 1), {}};
    Interval factorial(1.0);
    for (int i = 0; i <= k; ++i) {
      if (i > 0) factorial = factorial * Interval(static_cast<double>(i));
      e.d[static_cast<std::size_t>(i)] = derivative(Interval(c), i) / factorial;
    }
    factorial = factorial * Interval(static_cast<double>(k + 1));
    e.lagrange = derivative(range, k + 1) / factorial;
    return e;
  };
}

}  // namespace

TaylorModel sin(const TaylorModel& a) {
  if (!a.space_) return TaylorModel(interval::sin(a.remainder_));
  return TaylorModel::compose(a, sin_cos_expansion(0));
}

TaylorModel cos(const TaylorModel& a) {
  if (!a.space_) return TaylorModel(interval::cos(a.remainder_));
  return TaylorModel::compose(a, sin_cos_expansion(1));
}

}  // namespace furuta::validated
