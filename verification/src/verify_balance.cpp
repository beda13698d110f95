#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "affine_form.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "furuta/verification/balance_certificate.hpp"
#include "loop_maps.hpp"
#include "loop_run.hpp"
#include "remainder_jet.hpp"

namespace furuta::verification {

namespace {

using detail::AffineForm;
using detail::IMatrix4;
using detail::IVector4;
using detail::LinearCombination;
using detail::StretchMaps;
using detail::Symbols;
using Forms4 = std::array<AffineForm, 4>;

// The law's own arithmetic (its filter's series, products and sums in double) is taken to be
// within this fraction of the magnitudes it works on: far above its rounding (some hundred
// operations of 2^-53 each), so the law's results lie in the exact ones' enclosure widened by it.
constexpr double kLawRelativeError = 1e-10;
constexpr double kLawAbsoluteError = 1e-15;

// The sensitivities carried: to mu1, mu3 and mu4 through M's inverse at upright.
// The pieces of a period that share one expansion of the remainder (its jets).
constexpr std::size_t kJetGroup = 2;
// The pairs of y's components whose products are bounded by polarisation: (e, w1), (e, w2),
// (w1, w2).
constexpr std::array<std::array<std::size_t, 2>, 3> kCrossPairs{{{0, 1}, {0, 2}, {1, 2}}};
constexpr std::size_t kSensitivities = 3;

// An enclosure that stops growing inwards is inflated by this fraction of its width per try.
constexpr double kInflation = 0.1;
constexpr int kEnclosureTries = 30;

Interval symmetric(double radius) {
  return Interval(-radius, radius);
}

AffineForm difference(const AffineForm& a, const AffineForm& b) {
  return LinearCombination().add(a).add(Interval(-1.0), b).result();
}

bool bounded(const StateBox& x) {
  return std::all_of(x.begin(), x.end(), [](const Interval& v) { return v.is_bounded(); });
}

// An error of the duty against the one switching from `old` to `new` at the nominal switch: its
// L1 norm and the instants it can fall in, [from_s, to_s] after the sample.
struct InputErrorPart {
  double l1 = 0;
  double from_s = 0;
  double to_s = 0;
  bool fixed = false;  // the same instants every period (the lag's interval): computed exactly
};

// The ramp from `old` to `new` against the step: rho = int (ramp - step) = -g |g| / (2 rate),
// g = new - old, as an affine form in g (its best linear approximation over g's range and the
// rest in a symbol of its own), so that the plant's ramp and the law's model of it are the same
// quantity and their difference cancels.
struct SharedRamp {
  AffineForm rho;
  double bound = 0;  // |rho| at most
  // |g|^3 / (6 rate^2) at most: the ramp's first moment about its start, int s |ramp - step| ds,
  // which bounds what the change of e^(a r) b over the ramp adds.
  double moment = 0;
  Interval slope;  // rho's coefficient on g (its sensitivities' too)
};
// `spread`: how far the gap's sensitivities to the parameters move it beyond its form's range.
SharedRamp shared_ramp(const AffineForm& gap, double spread, double rate, Symbols& symbols) {
  const Interval g = detail::range(gap) + symmetric(spread);
  const double a = g.lo();
  const double b = g.hi();
  // g |g| in alpha g + beta + [-err, err] over [a, b].
  Interval alpha(0.0);
  Interval beta(0.0);
  Interval err(0.0);
  if (a >= 0 || b <= 0) {
    // g^2 over [a, b] lies between its secant, (a + b) g - a b, and the tangent parallel to it,
    // (a + b) g - (a + b)^2 / 4; for b <= 0, g |g| = -g^2.
    const Interval sum = Interval(a) + Interval(b);
    const Interval upper = -(Interval(a) * Interval(b));
    const Interval lower = -(interval::sqr(sum) / Interval(4.0));
    const Interval centre = (upper + lower) / Interval(2.0);
    const Interval radius = (upper - lower) / Interval(2.0);
    const double sign = a >= 0 ? 1.0 : -1.0;
    alpha = Interval(sign) * sum;
    beta = Interval(sign) * centre;
    err = Interval(radius.mag());
  } else {
    // Odd over [-G, G]: alpha = 2 (sqrt 2 - 1) G leaves at most (3 - 2 sqrt 2) G^2.
    const double big = std::max(-a, b);
    alpha = Interval(0.8284271247461900) * Interval(big);
    err = Interval(0.1716) * interval::sqr(Interval(big));
  }
  const Interval scale = Interval(-1.0) / (Interval(2.0) * Interval(rate));
  const Interval rest = scale * (beta + Interval(-err.hi(), err.hi()));
  SharedRamp out;
  out.slope = scale * alpha;
  out.rho = LinearCombination().add(out.slope, gap).add(symbols.noise(rest)).result();
  out.bound = (interval::sqr(Interval(g.mag())) / (Interval(2.0) * Interval(rate))).hi();
  out.moment =
      (interval::pow(Interval(g.mag()), 3) / (Interval(6.0) * interval::sqr(Interval(rate)))).hi();
  return out;
}

// The board (or the law's model of it) applying `applied` at the sample: it ramps towards `old`
// until the switch (an error of at most gap^2 / 2 rate over [0, gap / rate]), then towards `new`
// from wherever it was (gap^2 / 2 rate again, from the switch on), the switch itself anywhere in
// [switch_lo, switch_hi] (the largest gap over the half-width of that interval). When the duty
// applied at the sample is `old` itself, the ramp to `new` is `ramp` (shared), over `window`.
struct InputError {
  std::vector<InputErrorPart> parts;
  const SharedRamp* ramp = nullptr;
  Interval switch_s;  // when the ramp starts
  double ramp_from_s = 0;
  double ramp_to_s = 0;
  double settle_gap = 0;  // how far from `new` the applied duty can be when it starts ramping to it
};
// `spreads`: how far the sensitivities move applied - old, applied - new and old - new beyond
// their forms' ranges.
InputError input_error(const AffineForm& applied, const AffineForm& old_duty,
                       const AffineForm& new_duty, const std::array<double, 3>& spreads,
                       double rate, const Interval& switch_s, const SharedRamp* ramp) {
  const double to_old =
      (Interval(detail::range(difference(applied, old_duty)).mag()) + Interval(spreads[0])).hi();
  const double to_new = std::max(
      (Interval(detail::range(difference(applied, new_duty)).mag()) + Interval(spreads[1])).hi(),
      (Interval(detail::range(difference(old_duty, new_duty)).mag()) + Interval(spreads[2])).hi());
  const double largest = std::max(to_old, to_new);
  const auto ramp_l1 = [&](double gap) {
    if (!(rate > 0)) return Interval(0.0);
    return interval::sqr(Interval(gap)) / (Interval(2.0) * Interval(rate));
  };
  const auto ramp_s = [&](double gap) {
    return rate > 0 ? (Interval(gap) / Interval(rate)).hi() : 0.0;
  };
  InputError out;
  out.settle_gap = to_new;
  out.parts.push_back({ramp_l1(to_old).hi(), 0.0, std::min(ramp_s(to_old), switch_s.hi())});
  const double ramp_end = (Interval(switch_s.hi()) + Interval(ramp_s(to_new))).hi();
  const Interval jitter = Interval(switch_s.rad()) * Interval(largest);
  // Settled at the sample (the applied duty is `old`, to rounding): the ramp to `new` starts
  // from `old`, the shared ramp.
  if (ramp != nullptr && rate > 0 && to_old <= 1e-12 * std::max(to_new, 1e-300)) {
    out.parts.push_back({jitter.hi(), switch_s.lo(), switch_s.hi(), true});
    out.ramp = ramp;
    out.switch_s = switch_s;
    out.ramp_from_s = switch_s.lo();
    out.ramp_to_s = ramp_end;
  } else {
    out.parts.push_back({(jitter + ramp_l1(to_new)).hi(), switch_s.lo(), ramp_end});
  }
  return out;
}

// What the input's errors add to the state over [0, s], through e^(a r) b.
IVector4 input_disturbance(const StretchMaps& m, const InputError& input) {
  IVector4 out{Interval(0.0), Interval(0.0), Interval(0.0), Interval(0.0)};
  const double s = m.length_s;
  // A shared ramp not over by s reaches the state only in part: its bound as an error.
  std::vector<InputErrorPart> parts = input.parts;
  if (input.ramp != nullptr && input.ramp_to_s > s) {
    parts.push_back({input.ramp->bound, input.ramp_from_s, input.ramp_to_s});
  }
  for (const InputErrorPart& part : parts) {
    if (!(part.l1 > 0) || part.from_s >= s) continue;
    // An error at instant tau reaches the state at s through e^(a (s - tau)) b.
    const IVector4 effect = part.fixed && part.to_s <= s
                                ? m.effect_at(s - part.to_s, s - part.from_s)
                                : m.input_effect(std::max(0.0, s - part.to_s), s - part.from_s);
    for (std::size_t i = 0; i < 4; ++i) out[i] += effect[i] * symmetric(part.l1);
  }
  return out;
}

// |inverse row| times momenta of magnitudes p1 and p2 at most: what they move the rates inverse p.
double rates_of_momenta(const detail::MomentumPlant& plant, Eigen::Index row, double p1,
                        double p2) {
  return (Interval(std::fabs(plant.inverse(row, 0))) * Interval(p1) +
          Interval(std::fabs(plant.inverse(row, 1))) * Interval(p2))
      .hi();
}

// What the plant's distance from its linearisation adds to the state at an instant s of the
// period, to first order in the period's start: x_part x + old_part old + new_part new + constant,
// and beyond it anything in `fresh`.
struct FirstOrder {
  IMatrix4 x_part;
  IVector4 old_part;
  IVector4 new_part;
  IVector4 constant;
  IVector4 fresh;
};

FirstOrder no_first_order() {
  FirstOrder out;
  out.x_part.fill(Interval(0.0));
  for (IVector4* v : {&out.old_part, &out.new_part, &out.constant, &out.fresh}) {
    v->fill(Interval(0.0));
  }
  return out;
}

// The state at s from the sample, the duty `old` held before the switch and `new` after it:
// the exact linear maps, plus the remainder's first-order part, plus what the model adds beyond
// them (`added`, an interval vector carried by fresh symbols).
Forms4 carried(const StretchMaps& m, const Forms4& x, const AffineForm& old_duty,
               const AffineForm& new_duty, const FirstOrder& first, IVector4 added,
               const InputError& input, Symbols& symbols) {
  for (std::size_t i = 0; i < 4; ++i) added[i] += first.fresh[i];
  // The shared ramp, when over by s: it reaches the state at s through e^(a (s - tau)) b, tau
  // over the ramp; that is e^(a (s - switch)) b rho, plus at most |a e^(a r) b| times the ramp's
  // first moment (the change of e^(a r) b over the ramp, by the mean value theorem). Its
  // midpoint carries the ramp's form, the rest is an error.
  const bool ramp = input.ramp != nullptr && input.ramp_to_s <= m.length_s;
  IVector4 effect{Interval(0.0), Interval(0.0), Interval(0.0), Interval(0.0)};
  if (ramp) {
    const double s = m.length_s;
    effect = m.effect_at(s - input.switch_s.hi(), s - input.switch_s.lo());
    const IVector4 slope = m.slope_at(std::max(0.0, s - input.ramp_to_s), s - input.switch_s.lo());
    for (std::size_t i = 0; i < 4; ++i) {
      added[i] += (effect[i] - effect[i].mid()) * symmetric(input.ramp->bound) +
                  Interval(slope[i].mag()) * symmetric(input.ramp->moment);
    }
  }
  Forms4 out;
  for (std::size_t i = 0; i < 4; ++i) {
    LinearCombination row;
    for (std::size_t j = 0; j < 4; ++j) row.add(m.phi[i * 4 + j] + first.x_part[i * 4 + j], x[j]);
    row.add(m.gamma_old[i] + first.old_part[i], old_duty)
        .add(m.gamma_new[i] + first.new_part[i], new_duty)
        .add(first.constant[i], Symbols::constant(1.0));
    if (ramp) row.add(Interval(effect[i].mid()), input.ramp->rho);
    if (!(added[i].lo() == 0 && added[i].hi() == 0)) row.add(symbols.noise(added[i]));
    out[i] = row.result();
  }
  return out;
}

// Whether the duty applied at the period's end is `new` for certain: the ramp to it starts by
// switch_s from a gap of at most `gap`.
bool settled(double switch_s, double gap, double rate, double period_s) {
  if (!(rate > 0)) return true;
  return (Interval(switch_s) + Interval(gap) / Interval(rate)).hi() <= period_s;
}

std::optional<Failure> outside(FailureKind kind, double t_s, const Interval& value, double limit) {
  if (!value.is_bounded() || !(value.mag() < limit)) return Failure{kind, t_s, value, limit};
  return std::nullopt;
}

// A piece of the period's linear reach: its forms' centres and ranges in the state's coordinates
// and in the rates inverse p.
struct PieceReach {
  std::array<double, 4> centre;
  StateBox range;
  std::array<double, 2> rate_centre;
  std::array<Interval, 2> rates;
  // |lambda y_k +- y_l / lambda| over the symbols for the pairs (e, w1), (e, w2), (w1, w2),
  // lambda balancing their sizes: the products' ranges by polarisation (correlation kept).
  std::array<std::array<double, 2>, 3> pair_sizes;
  std::array<double, 3> pair_lambda;
};

// The remainder over a piece of the period, to first order in its start: gradient_z (x - centre)
// carried, constant and fresh (at every instant of the piece) beside it.
struct PieceRemainder {
  IMatrix4 gradient_z;  // g in the state's coordinates
  IVector4 constant;    // n(y_c) - g y_c, the midpoints
  IVector4 fresh;       // the rest, at every instant of the piece
};

// The remainder over each piece of the period (see run_loop): for each pair of pieces, its value
// and gradient at the pair's centre, carried; the rest bounded by the smallest of a mean value
// form, its range and Taylor forms of second and third order.
std::vector<PieceRemainder> remainders_over_pieces(const detail::MomentumPlant& plant,
                                                   const LoopModel& loop,
                                                   const std::vector<PieceReach>& piece_reach,
                                                   const std::array<Interval, 3>& beyond_y,
                                                   const Interval& drive_spread,
                                                   const IVector4& rounding) {
  const auto v = [&](Eigen::Index i, Eigen::Index j) { return Interval(plant.inverse(i, j)); };
  std::vector<PieceRemainder> piece_remainders;
  piece_remainders.reserve(piece_reach.size());
  // The jets per group of kJetGroup pieces: the group's middle piece's centre, the hull of the
  // group's ranges, the largest of its pieces' polarised sizes about that centre.
  for (std::size_t first = 0; first < piece_reach.size(); first += kJetGroup) {
    const std::size_t last = std::min(first + kJetGroup, piece_reach.size());
    PieceReach piece = piece_reach[(first + last) / 2];
    const std::array<double, 3> yc{piece.centre[1], piece.rate_centre[0], piece.rate_centre[1]};
    piece.pair_lambda = piece_reach[first].pair_lambda;
    piece.pair_sizes = {};
    for (std::size_t j = first; j < last; ++j) {
      const PieceReach& other = piece_reach[j];
      piece.range[1] = hull(piece.range[1], other.range[1]);
      for (std::size_t i = 0; i < 2; ++i) piece.rates[i] = hull(piece.rates[i], other.rates[i]);
      const std::array<double, 3> offset{other.centre[1] - yc[0], other.rate_centre[0] - yc[1],
                                         other.rate_centre[1] - yc[2]};
      for (std::size_t q = 0; q < 3; ++q) {
        const double l = piece.pair_lambda[q];
        const Interval a = Interval(l) * Interval(offset[kCrossPairs[q][0]]);
        const Interval b = Interval(offset[kCrossPairs[q][1]]) / Interval(l);
        piece.pair_sizes[q][0] =
            std::max(piece.pair_sizes[q][0],
                     (Interval(other.pair_sizes[q][0]) + Interval((a + b).mag())).hi());
        piece.pair_sizes[q][1] =
            std::max(piece.pair_sizes[q][1],
                     (Interval(other.pair_sizes[q][1]) + Interval((a - b).mag())).hi());
      }
    }
    const std::array<Interval, 3> ybox{piece.range[1] + beyond_y[0], piece.rates[0] + beyond_y[1],
                                       piece.rates[1] + beyond_y[2]};
    const detail::RemainderJet at_centre =
        detail::remainder_jet(plant, loop.parameters, loop.back_emf_nm_s,
                              {Interval(yc[0]), Interval(yc[1]), Interval(yc[2])}, false);
    const detail::RemainderJet over_box =
        detail::remainder_jet(plant, loop.parameters, loop.back_emf_nm_s, ybox);
    // How far y strays from y_c over the piece: the reach's form and what lies beyond it.
    std::array<double, 3> reach_size;
    for (std::size_t k = 0; k < 3; ++k) {
      const Interval& v = k == 0 ? piece.range[1] : piece.rates[k - 1];
      reach_size[k] = (Interval(std::max(v.hi() - yc[k], yc[k] - v.lo())) * Interval(1.0 + 1e-15) +
                       Interval(beyond_y[k].mag()))
                          .hi();
    }
    // The deviations' products: y_k^2 in [0, size^2]; y_k y_l = ((l y_k + y_l / l)^2 -
    // (l y_k - y_l / l)^2) / 4, each deviation the form's plus what lies beyond it, which keeps
    // the forms' correlation.
    std::array<Interval, 6> products;
    for (std::size_t pair = 0; pair < 6; ++pair) {
      const std::size_t a = detail::kPairs[pair][0];
      const std::size_t b = detail::kPairs[pair][1];
      const Interval box_product = Interval(reach_size[a]) * Interval(reach_size[b]);
      if (a == b) {
        products[pair] = Interval(0.0, box_product.hi());
        continue;
      }
      const std::size_t q = a == 0 ? b - 1 : 2;
      const double l = piece.pair_lambda[q];
      const Interval extra =
          Interval(l) * Interval(beyond_y[a].mag()) + Interval(beyond_y[b].mag()) / Interval(l);
      const Interval plus = Interval(piece.pair_sizes[q][0]) + extra;
      const Interval minus = Interval(piece.pair_sizes[q][1]) + extra;
      products[pair] = interval::intersect(Interval(-(interval::sqr(minus) / Interval(4.0)).hi(),
                                                    (interval::sqr(plus) / Interval(4.0)).hi()),
                                           symmetric(box_product.hi()));
    }
    // y_k y_l y_m / 6 times the number of its orderings: 1/6 for k = l = m, 1/2 for two alike,
    // 1 for three distinct.
    std::array<Interval, 10> triple_bounds;
    for (std::size_t triple = 0; triple < 10; ++triple) {
      const auto& t = detail::kTriples[triple];
      const Interval size =
          Interval(reach_size[t[0]]) * Interval(reach_size[t[1]]) * Interval(reach_size[t[2]]);
      const double weight = t[0] == t[2] ? 1.0 / 6.0 : (t[0] == t[1] || t[1] == t[2] ? 0.5 : 1.0);
      triple_bounds[triple] = Interval(weight) * symmetric(size.hi());
    }
    PieceRemainder r;
    for (std::size_t i = 0; i < 4; ++i) {
      std::array<double, 3> g;
      for (std::size_t k = 0; k < 3; ++k) g[k] = at_centre.gradient[i][k].mid();
      r.gradient_z[i * 4 + 0] = Interval(0.0);
      r.gradient_z[i * 4 + 1] = Interval(g[0]);
      r.gradient_z[i * 4 + 2] = Interval(g[1]) * v(0, 0) + Interval(g[2]) * v(1, 0);
      r.gradient_z[i * 4 + 3] = Interval(g[1]) * v(0, 1) + Interval(g[2]) * v(1, 1);
      const double mid = at_centre.value[i].mid();
      Interval constant(mid);
      // Two enclosures of the rest, intersected: the mean value form, and n over the box less
      // the carried part over the reach (tighter where g is small, as about upright).
      Interval mean_value = at_centre.value[i] - mid;
      Interval direct = over_box.value[i] - mid;
      const std::array<Interval, 3> reach_y{piece.range[1], piece.rates[0], piece.rates[1]};
      for (std::size_t k = 0; k < 3; ++k) {
        constant -= Interval(g[k]) * Interval(yc[k]);
        mean_value += Interval(g[k]) * beyond_y[k] +
                      (over_box.gradient[i][k] - Interval(g[k])) * (ybox[k] - Interval(yc[k]));
        direct -= Interval(g[k]) * (reach_y[k] - Interval(yc[k]));
      }
      // Taylor forms: (grad n(y_c) - g) (y - y_c) + g beyond, then to the second order with the
      // Hessian over the box, or to the third with the Hessian at y_c and the third
      // derivatives over the box.
      Interval first = at_centre.value[i] - mid;
      for (std::size_t k = 0; k < 3; ++k) {
        first += (at_centre.gradient[i][k] - Interval(g[k])) * symmetric(reach_size[k]) +
                 Interval(g[k]) * beyond_y[k];
      }
      Interval second = first;
      Interval third = first;
      for (std::size_t pair = 0; pair < 6; ++pair) {
        const Interval half =
            detail::kPairs[pair][0] == detail::kPairs[pair][1] ? Interval(0.5) : Interval(1.0);
        second += half * over_box.hessian[i][pair] * products[pair];
        third += half * at_centre.hessian[i][pair] * products[pair];
      }
      for (std::size_t triple = 0; triple < 10; ++triple) {
        third += over_box.third[i][triple] * triple_bounds[triple];
      }
      Interval fresh = interval::intersect(interval::intersect(mean_value, direct),
                                           interval::intersect(second, third));
      // Its midpoint is a constant over the piece.
      const double fresh_mid = fresh.mid();
      constant += Interval(fresh_mid);
      fresh = fresh - Interval(fresh_mid);
      if (i == 2) fresh += drive_spread;
      fresh += rounding[i];
      r.constant[i] = constant;
      r.fresh[i] = fresh;
    }
    for (std::size_t j = first; j < last; ++j) piece_remainders.push_back(r);
  }
  return piece_remainders;
}

// The remainders' part at an instant s of the period, from the pieces' integrals towards it.
FirstOrder first_order_over(const detail::PieceIntegrals& integrals,
                            const std::vector<PieceRemainder>& piece_remainders,
                            const StretchMaps& plant_period) {
  FirstOrder out = no_first_order();
  for (std::size_t j = 0; j < piece_remainders.size(); ++j) {
    const IMatrix4& psi = integrals.psi[j];
    const PieceRemainder& r = piece_remainders[j];
    const StretchMaps::Piece& maps = plant_period.pieces[j];
    IMatrix4 psi_g;  // psi g
    for (std::size_t i = 0; i < 4; ++i) {
      for (std::size_t k = 0; k < 4; ++k) {
        Interval sum(0.0);
        for (std::size_t l = 0; l < 4; ++l) sum += psi[i * 4 + l] * r.gradient_z[l * 4 + k];
        psi_g[i * 4 + k] = sum;
      }
    }
    for (std::size_t i = 0; i < 4; ++i) {
      for (std::size_t k = 0; k < 4; ++k) {
        Interval sum(0.0);
        for (std::size_t l = 0; l < 4; ++l) sum += psi_g[i * 4 + l] * maps.phi[l * 4 + k];
        out.x_part[i * 4 + k] += sum;
      }
      Interval fresh(0.0);
      for (std::size_t l = 0; l < 4; ++l) {
        out.old_part[i] += psi_g[i * 4 + l] * maps.gamma_old[l];
        out.new_part[i] += psi_g[i * 4 + l] * maps.gamma_new[l];
        out.constant[i] += psi[i * 4 + l] * r.constant[l];
        fresh += Interval(integrals.abs[j][i * 4 + l]) * Interval(r.fresh[l].mag());
      }
      out.fresh[i] += symmetric(fresh.hi());
    }
  }
  return out;
}

// The sensitivities' maps (see run_loop): a's change per radius of mu1, mu3, mu4 (direction k),
// what each adds to the state at the period's end and at the readings' instant on the base's
// linear reach, sum_k |direction_k| and what v's rest adds at most, entrywise.
struct SensitivityMaps {
  std::array<detail::SourceMaps, kSensitivities> source_period;
  std::array<detail::SourceMaps, kSensitivities> source_reading;
  std::array<double, 16> direction_abs{};
  std::array<double, 16> rest_abs{};
};

SensitivityMaps sensitivity_maps(const detail::UprightInverse& upright,
                                 const detail::MomentumPlant& plant, double board_switch,
                                 double period, double reading_s) {
  const model::Parameters<double>& centre = plant.centre;
  const double damping_centre = plant.kw + centre.fv1;
  SensitivityMaps out;
  std::array<Eigen::Matrix4d, kSensitivities> direction;
  for (std::size_t e = 0; e < 3; ++e) {
    const Eigen::Matrix4d d = detail::inverse_direction(e, damping_centre, centre.fv2);
    for (std::size_t i = 0; i < 16; ++i) {
      out.rest_abs[i] =
          (Interval(out.rest_abs[i]) +
           Interval(upright.rest[e]) * Interval(std::fabs(d(static_cast<Eigen::Index>(i / 4),
                                                            static_cast<Eigen::Index>(i % 4)))))
              .hi();
    }
  }
  for (std::size_t k = 0; k < kSensitivities; ++k) {
    direction[k] = detail::a_direction(upright.per_parameter[k], damping_centre, centre.fv2);
    out.source_period[k] =
        detail::source_maps(plant.a, plant.b, direction[k], board_switch, period);
    out.source_reading[k] =
        detail::source_maps(plant.a, plant.b, direction[k], board_switch, reading_s);
    for (std::size_t e = 0; e < 16; ++e) {
      const double v = std::fabs(
          direction[k](static_cast<Eigen::Index>(e / 4), static_cast<Eigen::Index>(e % 4)));
      out.direction_abs[e] =
          (Interval(out.direction_abs[e]) + Interval(v) * Interval(1.0 + 1e-15)).hi();
    }
  }
  return out;
}

// The linearisation's momentum rows are rounded products (-(kw + fv1) v, -fv2 v): within 1e-15 of
// each entry, relative, of the exact ones the remainder's algebra assumes; over the state's box
// `z` that is at most this, per row.
IVector4 linearisation_rounding(const Eigen::Matrix4d& a, const StateBox& z) {
  IVector4 out;
  for (std::size_t i = 0; i < 4; ++i) {
    Interval sum(0.0);
    for (std::size_t j = 0; j < 4; ++j) {
      sum += Interval(std::fabs(a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)))) *
             Interval(z[j].mag());
    }
    out[i] = symmetric((Interval(1e-15) * sum).hi());
  }
  return out;
}

void check_arguments(const control::BalanceControllerSpec& law, const LoopModel& loop,
                     const std::variant<LoopStart, detail::LoopStateBox>& from,
                     const VerifyOptions& options) {
  const auto fail = [](const std::string& what) {
    throw std::invalid_argument("verify_balance: " + what);
  };
  const double t = law.period_s;
  if (law.delayed > 1) fail("the law carries more than one duty on its way (lag beyond a period)");
  if (!(law.duty_path.lag_s <= t)) fail("the law's lag exceeds its period");
  if (!loop.lag_s.is_bounded() || loop.lag_s.lo() < 0 || loop.lag_s.hi() > t) {
    fail("the board's lag must be an interval within [0, period]");
  }
  if (!(loop.reading_age_s >= 0 && loop.reading_age_s <= t)) {
    fail("the reading age must be within [0, period]");
  }
  if (!(loop.arm_count_rad > 0) || !(loop.pendulum_count_rad > 0)) {
    fail("the encoders' counts must be > 0");
  }
  if (!(loop.ramp_duty_per_s >= 0) || !std::isfinite(loop.ramp_duty_per_s)) {
    fail("the board's ramp must be a finite rate >= 0");
  }
  for (const Interval& v : {loop.duty_torque_nm, loop.back_emf_nm_s}) {
    if (!v.is_bounded()) fail("the drive's constants must be bounded intervals");
  }
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const Interval& v = loop.parameters[k];
    if (!v.is_bounded() || v.lo() < 0 || (k < 5 && !(v.lo() > 0))) {
      fail(std::string("parameter ") + model::kParameterNames[k] +
           " must be a bounded interval > 0 (>= 0 for a friction)");
    }
  }
  if (const LoopStart* start = std::get_if<LoopStart>(&from)) {
    for (const StateBox* box : {&start->state, &start->estimate_error}) {
      if (!bounded(*box)) fail("the start boxes must be bounded");
    }
  } else {
    const detail::LoopStateBox& box = std::get<detail::LoopStateBox>(from);
    if (!std::all_of(box.begin(), box.end(), [](const Interval& v) { return v.is_bounded(); })) {
      fail("the start boxes must be bounded");
    }
  }
  if (!(options.horizon_s > 0) || !std::isfinite(options.horizon_s)) {
    fail("the horizon must be a finite number > 0 s");
  }
}

}  // namespace

namespace detail {

LoopRun run_loop(const control::BalanceControllerSpec& law, const LoopModel& loop,
                 const std::variant<LoopStart, LoopStateBox>& from, const LoopLimits& limits,
                 const VerifyOptions& options, const std::vector<std::size_t>& checkpoints) {
  check_arguments(law, loop, from, options);
  const auto began = std::chrono::steady_clock::now();
  const double period = law.period_s;
  const double reading_s = period - loop.reading_age_s;

  // The plant in momentum coordinates, linearised at the boxes' midpoints; the remainder covers
  // the rest.
  const model::Parameters<double> centre =
      loop.parameters.map([](const Interval& v) { return v.mid(); });
  // Linearised with M's inverse at upright at the box's midpoint; its change with mu1, mu3, mu4
  // (v = centre + sum_k eta_k per_parameter_k + rest, eta_k in [-1, 1], the same all along) is
  // carried in sensitivities, a(v) being linear in v; the rest is a fresh error.
  const detail::UprightInverse upright = detail::upright_inverse(loop.parameters);
  const detail::MomentumPlant plant = detail::momentum_plant(
      centre, loop.duty_torque_nm.mid(), loop.back_emf_nm_s.mid(), upright.centre);
  const double board_switch = loop.lag_s.mid();
  const SensitivityMaps sensitivity =
      sensitivity_maps(upright, plant, board_switch, period, reading_s);
  const std::array<detail::SourceMaps, kSensitivities>& source_period = sensitivity.source_period;
  const std::array<detail::SourceMaps, kSensitivities>& source_reading = sensitivity.source_reading;
  const std::array<double, 16>& direction_abs = sensitivity.direction_abs;
  const std::array<double, 16>& rest_abs = sensitivity.rest_abs;
  const StretchMaps plant_period = detail::stretch_maps(plant.a, plant.b, board_switch, period);
  const StretchMaps plant_reading = detail::stretch_maps(plant.a, plant.b, board_switch, reading_s);
  const detail::PieceIntegrals period_pieces = detail::piece_integrals(plant.a, period, period);
  const detail::PieceIntegrals reading_pieces = detail::piece_integrals(plant.a, period, reading_s);
  const FirstOrder no_first = no_first_order();

  // The law's model, as it carries its estimate.
  Eigen::Matrix4d law_a;
  Eigen::Vector4d law_b;
  for (Eigen::Index i = 0; i < 4; ++i) {
    law_b(i) = law.b_continuous[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j < 4; ++j)
      law_a(i, j) = law.a_continuous[static_cast<std::size_t>(i * 4 + j)];
  }
  const double law_switch = law.duty_path.lag_s;
  const double law_rate = law.duty_path.ramp_duty_per_s;
  const StretchMaps law_period = detail::stretch_maps(law_a, law_b, law_switch, period);
  const StretchMaps law_reading = detail::stretch_maps(law_a, law_b, law_switch, reading_s);

  const double max_steps = std::floor(law.max_duty / law.duty_step + 1e-9);
  const double duty_bound = max_steps * law.duty_step;
  const double law_limit = std::min(law.region.fall_rad, law.region.release_rad);

  LoopRun run;
  BalanceCertificate& out = run.certificate;
  out.horizon_s = options.horizon_s;
  Symbols symbols;
  Forms4 x;  // the plant's [q1, q2 - pi, p1, p2]
  Forms4 h;
  if (const LoopStart* start = std::get_if<LoopStart>(&from)) {
    Forms4 start_state;
    for (std::size_t i = 0; i < 4; ++i) start_state[i] = symbols.noise(start->state[i]);
    for (std::size_t i = 0; i < 4; ++i) {
      h[i] = LinearCombination()
                 .add(start_state[i])
                 .add(symbols.noise(start->estimate_error[i]))
                 .result();
    }
    // p = M(q2) dq: the upright M exactly, its change over the start's angles as an interval.
    const std::array<Interval, 4> excess =
        detail::mass_excess(plant, loop.parameters, start->state[1]);
    x[0] = start_state[0];
    x[1] = start_state[1];
    for (std::size_t i = 0; i < 2; ++i) {
      const Interval extra = excess[i * 2] * start->state[2] + excess[i * 2 + 1] * start->state[3];
      x[2 + i] = LinearCombination()
                     .add(Interval(plant.mass(static_cast<Eigen::Index>(i), 0)), start_state[2])
                     .add(Interval(plant.mass(static_cast<Eigen::Index>(i), 1)), start_state[3])
                     .add(symbols.noise(extra))
                     .result();
    }
  }
  // The rates from momentum coordinates: dq = M^-1 p, the upright inverse on the forms (exact),
  // what the pendulum's angle and the parameters change in it on their ranges.
  const auto linear_rates = [&](const Forms4& z) {
    std::array<Interval, 2> out;
    for (std::size_t i = 0; i < 2; ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      out[i] = detail::range(LinearCombination()
                                 .add(Interval(plant.inverse(r, 0)), z[2])
                                 .add(Interval(plant.inverse(r, 1)), z[3])
                                 .result());
    }
    return out;
  };
  const auto with_rates = [&](StateBox box, const std::array<Interval, 2>& linear) {
    const std::array<Interval, 2> excess =
        detail::rate_excess(plant, loop.parameters, box[1], linear);
    box[2] = linear[0] + excess[0];
    box[3] = linear[1] + excess[1];
    return box;
  };
  // The reduction's coordinates: the plant's state, the filter's error against it (its angles,
  // and its rates against the plant's upright M^-1 p), the duty sent before, the rounding in the
  // duty sent now, and each applied duty against the one sent before: directions the loop
  // contracts on their own.
  const auto law_duty_of = [&](const std::vector<Interval>& z, std::size_t estimate,
                               std::size_t on_way) {
    Interval sum(0.0);
    for (std::size_t i = 0; i < 4; ++i) sum -= Interval(law.gain[i]) * z[estimate + i];
    if (law.delayed == 1) sum -= Interval(law.gain[4]) * z[on_way];
    return sum;
  };
  const auto plant_as_estimate = [&](const std::vector<Interval>& z, std::size_t i) {
    if (i < 2) return z[i];
    const auto row = static_cast<Eigen::Index>(i - 2);
    return Interval(plant.inverse(row, 0)) * z[2] + Interval(plant.inverse(row, 1)) * z[3];
  };
  const detail::CoordinateMap to_error_coordinates = [&](const std::vector<Interval>& z) {
    std::vector<Interval> y = z;
    for (std::size_t i = 0; i < 4; ++i) y[4 + i] = z[4 + i] - plant_as_estimate(z, i);
    y[9] = z[9] - law_duty_of(z, 4, 8);
    y[10] = z[10] - z[8];
    y[11] = z[11] - z[8];
    return y;
  };
  const detail::CoordinateMap from_error_coordinates = [&](const std::vector<Interval>& y) {
    std::vector<Interval> z = y;
    for (std::size_t i = 0; i < 4; ++i) z[4 + i] = y[4 + i] + plant_as_estimate(y, i);
    z[9] = y[9] + law_duty_of(z, 4, 8);
    z[10] = y[10] + y[8];
    z[11] = y[11] + y[8];
    return z;
  };
  const AffineForm zero = Symbols::constant(0.0);
  // The law's duty for the estimate `estimate` with `on_way` on its way; nothing when it may reach
  // the limit.
  const auto law_duty = [&](const Forms4& estimate, const AffineForm& on_way, double t_s,
                            double sens_spread) -> std::optional<AffineForm> {
    LinearCombination raw;
    double size = 0;
    for (std::size_t i = 0; i < 4; ++i) {
      raw.add(Interval(-law.gain[i]), estimate[i]);
      size = std::max(size, detail::range(estimate[i]).mag());
    }
    if (law.delayed == 1) raw.add(Interval(-law.gain[4]), on_way);
    const AffineForm duty = raw.result();
    const Interval duty_range = detail::range(duty);
    if (auto failure = outside(FailureKind::duty_limit, t_s, duty_range + symmetric(sens_spread),
                               duty_bound)) {
      out.failure = failure;
      return std::nullopt;
    }
    // Rounded to a whole number of steps, and the law's own rounding.
    const double slack = kLawRelativeError * std::max(size, duty_range.mag()) + kLawAbsoluteError;
    return LinearCombination()
        .add(duty)
        .add(symbols.noise(symmetric(0.5 * law.duty_step + slack)))
        .result();
  };

  // The error coordinates of the loop's state (to_error_coordinates on the forms).
  const auto plant_form_as_estimate = [&](const Forms4& z, std::size_t i) {
    if (i < 2) return z[i];
    const auto row = static_cast<Eigen::Index>(i - 2);
    return LinearCombination()
        .add(Interval(plant.inverse(row, 0)), z[2])
        .add(Interval(plant.inverse(row, 1)), z[3])
        .result();
  };
  const auto law_duty_form = [&](const Forms4& estimate, const AffineForm& on_way) {
    LinearCombination sum;
    for (std::size_t i = 0; i < 4; ++i) sum.add(Interval(-law.gain[i]), estimate[i]);
    if (law.delayed == 1) sum.add(Interval(-law.gain[4]), on_way);
    return sum.result();
  };

  AffineForm old_duty = zero;  // sent at the last sample but one: the board's target until the lag
  AffineForm board = zero;     // the duty the board applies at the sample
  AffineForm law_applied = zero;
  AffineForm new_duty = zero;  // sent at the sample, on its way
  // The sensitivities to v's spread: each quantity is its form + sum_k eta_k its sens[k] form.
  struct Sensitivity {
    Forms4 x;
    Forms4 h;
    AffineForm old_duty;
    AffineForm new_duty;
    AffineForm board;
    AffineForm law_applied;
  };
  std::array<Sensitivity, kSensitivities> sens;
  for (Sensitivity& d : sens) {
    d.x.fill(zero);
    d.h.fill(zero);
    d.old_duty = d.new_duty = d.board = d.law_applied = zero;
  }
  // How far the sensitivities move a quantity beyond its form's range: sum_k |its sens[k]|.
  const auto spread = [&](auto&& quantity) {
    Interval sum(0.0);
    for (const Sensitivity& d : sens) sum += Interval(detail::range(quantity(d)).mag());
    return sum.hi();
  };
  const auto widened = [&](const AffineForm& base, auto&& quantity) {
    return detail::range(base) + symmetric(spread(quantity));
  };
  if (const LoopStateBox* box = std::get_if<LoopStateBox>(&from)) {
    for (std::size_t i = 0; i < 4; ++i) x[i] = symbols.noise((*box)[i]);
    for (std::size_t i = 0; i < 4; ++i) {
      h[i] = LinearCombination()
                 .add(plant_form_as_estimate(x, i))
                 .add(symbols.noise((*box)[4 + i]))
                 .result();
    }
    old_duty = symbols.noise((*box)[8]);
    new_duty =
        LinearCombination().add(law_duty_form(h, old_duty)).add(symbols.noise((*box)[9])).result();
    board = LinearCombination().add(old_duty).add(symbols.noise((*box)[10])).result();
    law_applied = LinearCombination().add(old_duty).add(symbols.noise((*box)[11])).result();
    if (auto failure = outside(FailureKind::duty_limit, 0.0, detail::range(new_duty), duty_bound)) {
      out.failure = failure;
    }
  } else {
    std::optional<AffineForm> first = law_duty(h, zero, 0.0, 0.0);
    if (first) new_duty = *first;
  }
  const auto error_box = [&]() {
    LoopStateBox y;
    for (std::size_t i = 0; i < 4; ++i) {
      y[i] = widened(x[i], [&](const Sensitivity& d) { return d.x[i]; });
      y[4 + i] = widened(difference(h[i], plant_form_as_estimate(x, i)), [&](const Sensitivity& d) {
        return difference(d.h[i], plant_form_as_estimate(d.x, i));
      });
    }
    y[8] = widened(old_duty, [](const Sensitivity& d) { return d.old_duty; });
    y[9] = widened(difference(new_duty, law_duty_form(h, old_duty)), [&](const Sensitivity& d) {
      return difference(d.new_duty, law_duty_form(d.h, d.old_duty));
    });
    y[10] = widened(difference(board, old_duty),
                    [](const Sensitivity& d) { return difference(d.board, d.old_duty); });
    y[11] = widened(difference(law_applied, old_duty),
                    [](const Sensitivity& d) { return difference(d.law_applied, d.old_duty); });
    return y;
  };
  if (out.failure) {
    out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    return run;
  }

  const auto periods = static_cast<std::size_t>(std::ceil(options.horizon_s / period - 1e-9));
  const Interval zero_interval(0.0);
  for (std::size_t k = 0; k < periods; ++k) {
    const double t0 = static_cast<double>(k) * period;
    const double t1 = static_cast<double>(k + 1) * period;
    const Interval duty_range =
        hull(hull(widened(board, [](const Sensitivity& d) { return d.board; }),
                  widened(old_duty, [](const Sensitivity& d) { return d.old_duty; })),
             widened(new_duty, [](const Sensitivity& d) { return d.new_duty; }));
    // The ramp to the new duty, one quantity for the board and for the law's model of it when
    // both ramp at the same rate.
    const AffineForm gap = difference(new_duty, old_duty);
    const double gap_spread =
        spread([](const Sensitivity& d) { return difference(d.new_duty, d.old_duty); });
    std::optional<SharedRamp> board_ramp;
    std::optional<SharedRamp> law_ramp;
    if (loop.ramp_duty_per_s > 0) {
      board_ramp = shared_ramp(gap, gap_spread, loop.ramp_duty_per_s, symbols);
    }
    if (law_rate > 0) {
      law_ramp = law_rate == loop.ramp_duty_per_s ? board_ramp
                                                  : shared_ramp(gap, gap_spread, law_rate, symbols);
    }
    const auto applied_spreads = [&](auto&& applied) {
      return std::array<double, 3>{
          spread([&](const Sensitivity& d) { return difference(applied(d), d.old_duty); }),
          spread([&](const Sensitivity& d) { return difference(applied(d), d.new_duty); }),
          gap_spread};
    };
    const InputError board_error = input_error(
        board, old_duty, new_duty, applied_spreads([](const Sensitivity& d) { return d.board; }),
        loop.ramp_duty_per_s, loop.lag_s, board_ramp ? &*board_ramp : nullptr);
    const InputError law_error =
        input_error(law_applied, old_duty, new_duty,
                    applied_spreads([](const Sensitivity& d) { return d.law_applied; }), law_rate,
                    Interval(law_switch), law_ramp ? &*law_ramp : nullptr);

    // The plant over the period: the linear model's reach from the affine forms (the hull of
    // its maps to each piece of the period), plus what the field's distance from it and the
    // input's errors add, an enclosure E such that, while the state is in E, that distance keeps
    // it inside E's interior (then it never leaves E).
    StateBox reach;
    reach.fill(Interval::empty());
    std::array<Interval, 2> reach_rates{Interval::empty(), Interval::empty()};
    std::vector<PieceReach> piece_reach;
    piece_reach.reserve(plant_period.pieces.size());
    for (const StretchMaps::Piece& piece : plant_period.pieces) {
      Forms4 at;
      PieceReach here;
      std::array<AffineForm, 2> rate_forms;
      for (std::size_t i = 0; i < 4; ++i) {
        LinearCombination row;
        for (std::size_t j = 0; j < 4; ++j) row.add(piece.phi[i * 4 + j], x[j]);
        row.add(piece.gamma_old[i], old_duty).add(piece.gamma_new[i], new_duty);
        at[i] = row.result();
        here.centre[i] = at[i].centre;
        here.range[i] = detail::range(at[i]);
        reach[i] = hull(reach[i], here.range[i]);
      }
      // The rates inverse p, from the forms (p1 and p2 move together).
      for (std::size_t i = 0; i < 2; ++i) {
        const auto r = static_cast<Eigen::Index>(i);
        const AffineForm rate = LinearCombination()
                                    .add(Interval(plant.inverse(r, 0)), at[2])
                                    .add(Interval(plant.inverse(r, 1)), at[3])
                                    .result();
        here.rate_centre[i] = rate.centre;
        here.rates[i] = detail::range(rate);
        reach_rates[i] = hull(reach_rates[i], here.rates[i]);
        rate_forms[i] = rate;
      }
      const std::array<const AffineForm*, 3> y_forms{&at[1], &rate_forms[0], &rate_forms[1]};
      for (std::size_t q = 0; q < 3; ++q) {
        const AffineForm& a = *y_forms[kCrossPairs[q][0]];
        const AffineForm& b = *y_forms[kCrossPairs[q][1]];
        // One lambda per group of pieces (the first's), so that the group's sizes combine.
        double lambda = 0;
        if (piece_reach.size() % kJetGroup == 0) {
          const double ra = detail::range(a).rad();
          const double rb = detail::range(b).rad();
          lambda = ra > 0 && rb > 0 ? std::sqrt(rb / ra) : 1.0;
        } else {
          lambda = piece_reach[piece_reach.size() - piece_reach.size() % kJetGroup].pair_lambda[q];
        }
        here.pair_lambda[q] = lambda;
        for (std::size_t sign = 0; sign < 2; ++sign) {
          const double t = sign == 0 ? 1.0 / lambda : -1.0 / lambda;
          here.pair_sizes[q][sign] =
              detail::range(
                  LinearCombination().add(Interval(lambda), a).add(Interval(t), b).result())
                  .rad();
        }
      }
      piece_reach.push_back(here);
    }
    // What the sensitivities add over the period (their linear motion; their sources, v's spread
    // times the state, are in the remainder the enclosure bounds): e^(a r) over [0, T] on their
    // states, int |e^(a r) b| on their duties.
    std::array<double, 4> sens_size{};
    for (const Sensitivity& d : sens) {
      const double duty =
          std::max(detail::range(d.old_duty).mag(), detail::range(d.new_duty).mag());
      for (std::size_t i = 0; i < 4; ++i) {
        Interval sum =
            Interval(sens_size[i]) + Interval(plant_period.abs_integral_b[i]) * Interval(duty);
        for (std::size_t j = 0; j < 4; ++j) {
          sum +=
              Interval(plant_period.over[i * 4 + j].mag()) * Interval(detail::range(d.x[j]).mag());
        }
        sens_size[i] = sum.hi();
      }
    }
    for (std::size_t i = 0; i < 4; ++i) reach[i] = reach[i] + symmetric(sens_size[i]);
    for (std::size_t i = 0; i < 2; ++i) {
      const auto r = static_cast<Eigen::Index>(i);
      reach_rates[i] =
          reach_rates[i] + symmetric(rates_of_momenta(plant, r, sens_size[2], sens_size[3]));
    }
    // The rates over the enclosure `box`: the reach's, plus what its excess over the reach adds.
    // (box contains the reach: the interval that, added to the reach, gives the box).
    const auto rates_in = [&](const StateBox& box) {
      std::array<Interval, 2> excess;
      for (std::size_t j = 0; j < 2; ++j) {
        const Interval& b = box[2 + j];
        const Interval& a = reach[2 + j];
        excess[j] = Interval((Interval(b.lo()) - Interval(a.lo())).lo(),
                             (Interval(b.hi()) - Interval(a.hi())).hi());
      }
      std::array<Interval, 2> out;
      for (std::size_t i = 0; i < 2; ++i) {
        const auto r = static_cast<Eigen::Index>(i);
        out[i] = reach_rates[i] + Interval(plant.inverse(r, 0)) * excess[0] +
                 Interval(plant.inverse(r, 1)) * excess[1];
      }
      return out;
    };
    IVector4 input_spread{zero_interval, zero_interval, zero_interval, zero_interval};
    for (const InputErrorPart& part : board_error.parts) {
      for (std::size_t i = 0; i < 4; ++i)
        input_spread[i] += plant_period.over_b[i] * symmetric(part.l1);
    }
    if (board_error.ramp != nullptr) {
      for (std::size_t i = 0; i < 4; ++i) {
        input_spread[i] += plant_period.over_b[i] * symmetric(board_error.ramp->bound);
      }
    }
    StateBox over = reach;
    IVector4 remainder{zero_interval, zero_interval, zero_interval, zero_interval};
    bool enclosed = false;
    for (int attempt = 0; attempt < kEnclosureTries && !enclosed; ++attempt) {
      remainder = detail::momentum_remainder(plant, loop.parameters, loop.duty_torque_nm,
                                             loop.back_emf_nm_s, over, rates_in(over), duty_range);
      const IVector4 rounding = linearisation_rounding(plant.a, over);
      for (std::size_t i = 0; i < 4; ++i) remainder[i] += rounding[i];
      StateBox next;
      bool inside = true;
      for (std::size_t i = 0; i < 4; ++i) {
        Interval added = input_spread[i];
        for (std::size_t j = 0; j < 4; ++j) {
          const double mid = remainder[j].mid();
          added += plant_period.psi_over[i * 4 + j] * Interval(mid) +
                   symmetric((Interval(plant_period.abs_integral[i * 4 + j]) *
                              Interval((remainder[j] - mid).mag()))
                                 .hi());
        }
        next[i] = reach[i] + added;
        inside = inside && next[i].is_bounded() && next[i].is_interior_subset(over[i]);
      }
      if (inside) {
        over = next;
        enclosed = true;
      } else {
        // Epsilon-inflation: try the image, widened, next (a fixed point of the map if any).
        for (std::size_t i = 0; i < 4; ++i) {
          if (!next[i].is_bounded()) break;
          const double grow = kInflation * next[i].width() + 1e-12;
          over[i] = hull(reach[i], next[i] + symmetric(grow));
        }
      }
    }
    if (!enclosed || !bounded(over)) {
      out.failure = Failure{FailureKind::no_enclosure, t0, over[1], limits.upright_rad};
      break;
    }
    if (auto f = outside(FailureKind::pendulum_limit, t0, over[1], limits.upright_rad)) {
      out.failure = f;
      break;
    }
    if (auto f = outside(FailureKind::arm_limit, t0, over[0], limits.arm_rad)) {
      out.failure = f;
      break;
    }

    // The remainder over each piece j of the period, in y = (e, w = inverse p): with y_c the
    // piece's reach's centre, n(y) = n(y_c) + g (y - y_c) + (J(xi) - g) (y - y_c), g the gradient
    // at y_c and xi in the piece's box Y (the mean value form). y - y_c is the reach's form less
    // its centre plus what lies beyond the reach (`beyond`); g times the form is carried in the
    // symbols, the rest is fresh. Integrated over the pieces towards an instant s.
    StateBox beyond;
    for (std::size_t i = 0; i < 4; ++i) {
      beyond[i] = Interval((Interval(over[i].lo()) - Interval(reach[i].lo())).lo(),
                           (Interval(over[i].hi()) - Interval(reach[i].hi())).hi());
    }
    const auto v = [&](Eigen::Index i, Eigen::Index j) { return Interval(plant.inverse(i, j)); };
    // y beyond the base's forms: what the enclosure adds, the sensitivities' part, and w's own
    // spread (v - centre) p.
    std::array<double, 3> v_spread = upright.rest;  // |v - centre| at most, entries 11, 12, 22
    for (std::size_t e = 0; e < 3; ++e) {
      for (std::size_t k = 0; k < kSensitivities; ++k) {
        v_spread[e] =
            (Interval(v_spread[e]) + Interval(std::fabs(upright.per_parameter[k][e]))).hi();
      }
    }
    const std::array<double, 3> v_spread_p{(Interval(v_spread[0]) * Interval(over[2].mag()) +
                                            Interval(v_spread[1]) * Interval(over[3].mag()))
                                               .hi(),
                                           (Interval(v_spread[1]) * Interval(over[2].mag()) +
                                            Interval(v_spread[2]) * Interval(over[3].mag()))
                                               .hi(),
                                           0.0};
    const auto sens_w = [&](Eigen::Index row) {
      return (Interval(rates_of_momenta(plant, row, sens_size[2], sens_size[3])) +
              Interval(v_spread_p[static_cast<std::size_t>(row)]))
          .hi();
    };
    const std::array<Interval, 3> beyond_y{
        beyond[1] + symmetric(sens_size[1]),
        v(0, 0) * beyond[2] + v(0, 1) * beyond[3] + symmetric(sens_w(0)),
        v(1, 0) * beyond[2] + v(1, 1) * beyond[3] + symmetric(sens_w(1))};
    const Interval drive_spread = (loop.duty_torque_nm - Interval(plant.kd)) * duty_range;
    const std::vector<PieceRemainder> piece_remainders = remainders_over_pieces(
        plant, loop, piece_reach, beyond_y, drive_spread, linearisation_rounding(plant.a, over));
    const auto first_order = [&](const detail::PieceIntegrals& integrals) {
      return first_order_over(integrals, piece_remainders, plant_period);
    };

    // The plant at the readings' instant and at the next sample. Beyond the base's carried parts:
    // v's spread times what the state holds beyond the sensitivities' sources (the linear reach):
    // the base's excess over it and the sensitivities themselves (second order in eta).
    std::array<double, 4> beyond_reach{};
    {
      std::array<double, 4> source{};  // int |e^(a r)| |sum_k radius_k e_k| |reach|
      std::array<double, 4> pushed{};
      for (std::size_t i = 0; i < 4; ++i) {
        Interval sum(0.0);
        for (std::size_t j = 0; j < 4; ++j) {
          sum += Interval(direction_abs[i * 4 + j]) * Interval(reach[j].mag());
        }
        pushed[i] = sum.hi();
      }
      for (std::size_t i = 0; i < 4; ++i) {
        Interval sum(0.0);
        for (std::size_t j = 0; j < 4; ++j) {
          sum += Interval(plant_period.abs_integral[i * 4 + j]) * Interval(pushed[j]);
        }
        source[i] = sum.hi();
      }
      for (std::size_t i = 0; i < 4; ++i) {
        beyond_reach[i] = (Interval(beyond[i].mag()) + Interval(2.0) * Interval(source[i]) +
                           Interval(sens_size[i]) + Interval(1e-15) * Interval(over[i].mag()))
                              .hi();
      }
    }
    const auto second_order = [&](const StretchMaps& m) {
      IVector4 out;
      for (std::size_t i = 0; i < 4; ++i) {
        Interval sum(0.0);
        for (std::size_t j = 0; j < 4; ++j) {
          Interval pushed(0.0);
          for (std::size_t l = 0; l < 4; ++l) {
            pushed += Interval(direction_abs[j * 4 + l]) * Interval(beyond_reach[l]) +
                      Interval(rest_abs[j * 4 + l]) * Interval(over[l].mag());
          }
          sum += Interval(m.abs_integral[i * 4 + j]) * pushed;
        }
        out[i] = symmetric(sum.hi());
      }
      return out;
    };
    const auto with_second_order = [&](IVector4 added, const StretchMaps& m) {
      const IVector4 more = second_order(m);
      for (std::size_t i = 0; i < 4; ++i) added[i] += more[i];
      return added;
    };
    const Forms4 x_read =
        carried(plant_reading, x, old_duty, new_duty, first_order(reading_pieces),
                with_second_order(input_disturbance(plant_reading, board_error), plant_reading),
                board_error, symbols);
    const Forms4 x_next =
        carried(plant_period, x, old_duty, new_duty, first_order(period_pieces),
                with_second_order(input_disturbance(plant_period, board_error), plant_period),
                board_error, symbols);
    // The sensitivities through the same maps, their ramps (the ramp's slope on their gaps) and,
    // for the plant, their sources: radius_k e_k on the base's linear reach.
    const auto ramp_effect = [&](const StretchMaps& m, const InputError& input) {
      std::optional<IVector4> out;
      if (input.ramp != nullptr && input.ramp_to_s <= m.length_s) {
        const double s_end = m.length_s;
        out = m.effect_at(s_end - input.switch_s.hi(), s_end - input.switch_s.lo());
      }
      return out;
    };
    const auto carried_sensitivity = [&](const StretchMaps& m, const Forms4& z,
                                         const Sensitivity& d, const std::optional<IVector4>& ramp,
                                         const SharedRamp* ramp_of,
                                         const detail::SourceMaps* source) {
      Forms4 out;
      AffineForm rho = zero;
      if (ramp && ramp_of != nullptr) {
        rho = LinearCombination().add(ramp_of->slope, difference(d.new_duty, d.old_duty)).result();
      }
      for (std::size_t i = 0; i < 4; ++i) {
        LinearCombination row;
        for (std::size_t j = 0; j < 4; ++j) row.add(m.phi[i * 4 + j], z[j]);
        row.add(m.gamma_old[i], d.old_duty).add(m.gamma_new[i], d.new_duty);
        if (ramp && ramp_of != nullptr) row.add(Interval((*ramp)[i].mid()), rho);
        if (source != nullptr) {
          for (std::size_t j = 0; j < 4; ++j) row.add(source->x_part[i * 4 + j], x[j]);
          row.add(source->old_part[i], old_duty).add(source->new_part[i], new_duty);
        }
        out[i] = row.result();
      }
      return out;
    };
    const std::optional<IVector4> board_ramp_reading = ramp_effect(plant_reading, board_error);
    const std::optional<IVector4> board_ramp_period = ramp_effect(plant_period, board_error);
    const std::optional<IVector4> law_ramp_reading = ramp_effect(law_reading, law_error);
    const std::optional<IVector4> law_ramp_period = ramp_effect(law_period, law_error);
    std::array<Sensitivity, kSensitivities> next_sens;
    std::array<Forms4, kSensitivities> read_sens;
    for (std::size_t k = 0; k < kSensitivities; ++k) {
      const Sensitivity& d = sens[k];
      read_sens[k] = carried_sensitivity(plant_reading, d.x, d, board_ramp_reading,
                                         board_error.ramp, &source_reading[k]);
      next_sens[k].x = carried_sensitivity(plant_period, d.x, d, board_ramp_period,
                                           board_error.ramp, &source_period[k]);
    }
    // The readings, within half a count.
    const AffineForm arm_reading = LinearCombination()
                                       .add(x_read[0])
                                       .add(symbols.noise(symmetric(0.5 * loop.arm_count_rad)))
                                       .result();
    const AffineForm pendulum_reading =
        LinearCombination()
            .add(x_read[1])
            .add(symbols.noise(symmetric(0.5 * loop.pendulum_count_rad)))
            .result();
    Interval read_spread(0.0);
    for (const Forms4& r : read_sens) read_spread += Interval(detail::range(r[1]).mag());
    if (auto f =
            outside(FailureKind::law_mode, t1,
                    detail::range(pendulum_reading) + symmetric(read_spread.hi()), law_limit)) {
      out.failure = f;
      break;
    }

    // The law: its estimate carried to the readings' instant, corrected by them, carried to the
    // sample; its ramp as an input error of its own.
    const Forms4 predicted = carried(law_reading, h, old_duty, new_duty, no_first,
                                     input_disturbance(law_reading, law_error), law_error, symbols);
    const AffineForm arm_innovation = difference(arm_reading, predicted[0]);
    const AffineForm pendulum_innovation = difference(pendulum_reading, predicted[1]);
    Forms4 corrected;
    for (std::size_t i = 0; i < 4; ++i) {
      corrected[i] = LinearCombination()
                         .add(h[i])
                         .add(Interval(law.observer_gain[i * 2]), arm_innovation)
                         .add(Interval(law.observer_gain[i * 2 + 1]), pendulum_innovation)
                         .result();
    }
    Forms4 h_next = carried(law_period, corrected, old_duty, new_duty, no_first,
                            input_disturbance(law_period, law_error), law_error, symbols);
    for (std::size_t i = 0; i < 4; ++i) {
      const double size =
          std::max(detail::range(corrected[i]).mag(), detail::range(h_next[i]).mag());
      h_next[i] = LinearCombination()
                      .add(h_next[i])
                      .add(symbols.noise(symmetric(kLawRelativeError * size + kLawAbsoluteError)))
                      .result();
    }
    // The law's sensitivities: its model's maps, its ramp, the readings' sensitivities.
    std::array<AffineForm, kSensitivities> next_duty_sens;
    Interval duty_spread(0.0);
    for (std::size_t k = 0; k < kSensitivities; ++k) {
      const Sensitivity& d = sens[k];
      const Forms4 predicted_k =
          carried_sensitivity(law_reading, d.h, d, law_ramp_reading, law_error.ramp, nullptr);
      const AffineForm arm_k = difference(read_sens[k][0], predicted_k[0]);
      const AffineForm pendulum_k = difference(read_sens[k][1], predicted_k[1]);
      Forms4 corrected_k;
      for (std::size_t i = 0; i < 4; ++i) {
        corrected_k[i] = LinearCombination()
                             .add(d.h[i])
                             .add(Interval(law.observer_gain[i * 2]), arm_k)
                             .add(Interval(law.observer_gain[i * 2 + 1]), pendulum_k)
                             .result();
      }
      next_sens[k].h =
          carried_sensitivity(law_period, corrected_k, d, law_ramp_period, law_error.ramp, nullptr);
      next_duty_sens[k] = law_duty_form(next_sens[k].h, d.new_duty);
      duty_spread += Interval(detail::range(next_duty_sens[k]).mag());
    }
    std::optional<AffineForm> next_duty = law_duty(h_next, new_duty, t1, duty_spread.hi());
    if (!next_duty) break;

    // The duty applied at the next sample: the new one, unless its ramp may still be on.
    const auto applied_next = [&](double switch_s, const InputError& error, double rate) {
      if (settled(switch_s, error.settle_gap, rate, period)) return new_duty;
      return LinearCombination()
          .add(new_duty)
          .add(symbols.noise(symmetric(error.settle_gap)))
          .result();
    };
    AffineForm board_next = applied_next(loop.lag_s.hi(), board_error, loop.ramp_duty_per_s);
    AffineForm law_next = applied_next(law_switch, law_error, law_rate);

    for (std::size_t k = 0; k < kSensitivities; ++k) {
      next_sens[k].old_duty = sens[k].new_duty;
      next_sens[k].new_duty = next_duty_sens[k];
      next_sens[k].board = sens[k].new_duty;
      next_sens[k].law_applied = sens[k].new_duty;
    }

    // The boxes: the forms' ranges widened by the sensitivities'.
    const auto widened_box = [&](const Forms4& base, auto&& part) {
      StateBox box;
      for (std::size_t i = 0; i < 4; ++i) {
        Interval sum(0.0);
        for (const Sensitivity& d : next_sens) sum += Interval(detail::range(part(d)[i]).mag());
        box[i] = detail::range(base[i]) + symmetric(sum.hi());
      }
      return box;
    };
    const StateBox x_next_box =
        widened_box(x_next, [](const Sensitivity& d) -> const Forms4& { return d.x; });
    // The linear rates inverse p from the forms, widened by the sensitivities' momenta.
    std::array<Interval, 2> x_next_rates = linear_rates(x_next);
    {
      std::array<double, 2> p_spread{};
      for (const Sensitivity& d : next_sens) {
        for (std::size_t j = 0; j < 2; ++j) {
          p_spread[j] = (Interval(p_spread[j]) + Interval(detail::range(d.x[2 + j]).mag())).hi();
        }
      }
      for (std::size_t i = 0; i < 2; ++i) {
        const auto r = static_cast<Eigen::Index>(i);
        x_next_rates[i] =
            x_next_rates[i] + symmetric(rates_of_momenta(plant, r, p_spread[0], p_spread[1]));
      }
    }
    LoopStepBox step;
    step.t0_s = t0;
    step.t1_s = t1;
    step.over = with_rates(over, rates_in(over));
    step.at_end = with_rates(x_next_box, x_next_rates);
    step.estimate = widened_box(h_next, [](const Sensitivity& d) -> const Forms4& { return d.h; });
    step.duty = detail::range(*next_duty) + symmetric(duty_spread.hi());
    out.steps.push_back(step);

    std::vector<AffineForm> state{x_next[0], x_next[1],  x_next[2],  x_next[3],
                                  h_next[0], h_next[1],  h_next[2],  h_next[3],
                                  new_duty,  *next_duty, board_next, law_next};
    std::vector<std::vector<AffineForm>> state_sens;
    for (const Sensitivity& d : next_sens) {
      state_sens.push_back({d.x[0], d.x[1], d.x[2], d.x[3], d.h[0], d.h[1], d.h[2], d.h[3],
                            d.old_duty, d.new_duty, d.board, d.law_applied});
    }
    out.largest_symbol_count = std::max(out.largest_symbol_count, symbols.count());
    detail::reduce(state, symbols, options.max_symbols, to_error_coordinates,
                   from_error_coordinates, &state_sens);
    for (std::size_t i = 0; i < 4; ++i) {
      x[i] = state[i];
      h[i] = state[4 + i];
    }
    old_duty = state[8];
    new_duty = state[9];
    board = state[10];
    law_applied = state[11];
    for (std::size_t k = 0; k < kSensitivities; ++k) {
      const std::vector<AffineForm>& f = state_sens[k];
      Sensitivity& d = sens[k];
      for (std::size_t i = 0; i < 4; ++i) {
        d.x[i] = f[i];
        d.h[i] = f[4 + i];
      }
      d.old_duty = f[8];
      d.new_duty = f[9];
      d.board = f[10];
      d.law_applied = f[11];
    }
    if (run.at_checkpoints.size() < checkpoints.size() &&
        checkpoints[run.at_checkpoints.size()] == k + 1) {
      run.at_checkpoints.push_back(error_box());
    }
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  return run;
}

}  // namespace detail

BalanceCertificate verify_balance(const control::BalanceControllerSpec& law, const LoopModel& loop,
                                  const LoopStart& start, const LoopLimits& limits,
                                  const VerifyOptions& options) {
  return detail::run_loop(law, loop, start, limits, options).certificate;
}

StartRegion largest_start(const control::BalanceControllerSpec& law, const LoopModel& loop,
                          const LoopStart& start, const LoopLimits& limits,
                          const VerifyOptions& options, const SplitOptions& split, double max_scale,
                          int steps) {
  const auto scaled = [&](double scale) {
    LoopStart s = start;
    // The plant's start only: the filter's error is the filter's, whatever the start.
    for (Interval& v : s.state) {
      const double mid = v.mid();
      v = Interval(mid) + Interval(scale) * (v - mid);
    }
    return s;
  };
  StartRegion out;
  double lo = 0;
  double hi = max_scale;
  BalanceCertificate last;
  const auto attempt = [&](double scale) {
    ++out.verifications;
    last = verify_balance_split(law, loop, scaled(scale), limits, options, split);
    if (last.certified()) {
      out.scale = scale;
      out.start = scaled(scale);
      out.certificate = last;
    }
    return last.certified();
  };
  if (attempt(hi)) return out;
  for (int i = 0; i < steps; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (attempt(mid)) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  if (out.scale == 0) {
    out.start = scaled(0);
    out.certificate = last;
  }
  return out;
}

}  // namespace furuta::verification
