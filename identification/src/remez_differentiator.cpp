// Parks-McClellan design of an antisymmetric (type III / IV) FIR differentiator, and its centred
// application. This project's own code: Debian's liquid-dsp 1.5.0 firdespm rejects the
// differentiator type ("filter configuration not yet supported").
//
// The amplitude of an antisymmetric filter, about its centre, is A(w) = Q(w) P(cos w), with
// Q(w) = sin w (odd length) or sin(w / 2) (even length) and P a cosine polynomial of degree
// M - 1, M = floor(N / 2). Minimising max W(w) |A(w) - D(w)| is then the classic cosine problem for
// P with desired D / Q and weight W Q, which the Remez exchange solves on a dense grid; each
// extremal is then polished on the continuous axis, so the levelled error is the true minimax one
// and not only the grid's. P is kept in barycentric form on x = cos w throughout; the taps come
// from its values at Chebyshev angles at the end. Long filters start from the extremals of the
// half-length solution ("reference scaling"), since an even start levels their error below
// rounding; lengths whose optimum is below rounding altogether fall back to the longest shorter
// design that works.

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <limits>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "furuta/identification/filters.hpp"

namespace furuta::identification {
namespace {

constexpr double kPi = std::numbers::pi;

// Grid points per extremal; the continuous polishing makes the result insensitive to it, it only
// has to separate neighbouring extrema.
constexpr int kGridDensity = 16;
constexpr int kMaxIterations = 100;
// The exchange stops when |error| at the extremals is level to this, relatively...
constexpr double kLevelTolerance = 1e-9;
// ... or absolutely. The weighted error is dimensionless (a relative slope error), P is of order 1,
// and rounding in evaluating it leaves an error near machine precision: designs with errors below
// 1e-4 (long filters, wide transition bands) stop at this floor before the relative level.
constexpr double kLevelFloor = 1e-13;
// When rounding scrambles the alternation before either (optimal errors near 1e-13 and below), the
// best design met is kept if its error is below this: a slope error no use here can notice.
constexpr double kNegligibleError = 1e-9;
constexpr int kGoldenSteps = 64;
// Up to this many cosine coefficients the exchange starts from evenly spread extremals.
constexpr std::size_t kEvenStartLimit = 24;
constexpr int kMaxTaps = 1025;

// Stop-band weight. The stop-band gain is weighed as a fraction of the gain at the pass-band edge,
// 2 pi f_pass, and counts a tenth as much as the pass-band relative error: the achieved stop-band
// gain is then 10 x (pass-band relative error) x 2 pi f_pass. Pass-band slope accuracy is what the
// identification sees (it scales velocities and accelerations directly), while the stop band only
// sees what the Butterworth ahead of it lets through (-106 dB at 10 Hz for an 8th-order 5 Hz
// low-pass applied twice at 62.5 Hz). Against equal weights this buys a much smaller slope error
// for a somewhat larger stop-band gain (docs/measurements/identification.md, "Filters, in full").
constexpr double kStopbandRelativeWeight = 0.1;

void require(bool ok, const char* parameter, const std::string& why) {
  if (!ok) throw std::invalid_argument(std::string(parameter) + ": " + why);
}

struct Band {
  double lo, hi;  // rad / sample
  bool pass;
};

// The design problem after factoring out Q(w); frequencies in rad / sample.
struct Problem {
  bool odd_length;
  std::size_t m;       // number of cosine coefficients of P
  double stop_weight;  // absolute weight on |A| in the stop band

  double q(double w) const { return odd_length ? std::sin(w) : std::sin(w / 2); }
  // w / Q(w) and its reciprocal, with their limits at w = 0 (1 for sin w, 2 for sin(w / 2)).
  double w_over_q(double w) const {
    if (w < 1e-12) return odd_length ? 1.0 : 2.0;
    return w / q(w);
  }
  // Desired amplitude and weight of the cosine problem: D / Q, W Q.
  double desired(double w, bool pass) const { return pass ? w_over_q(w) : 0.0; }
  double weight(double w, bool pass) const {
    // In the pass band W = 1 / w (relative error), so W Q = Q / w.
    return pass ? 1.0 / w_over_q(w) : stop_weight * q(w);
  }
};

// cos a - cos b, without the cancellation of the direct difference: node spacings near w = 0, where
// the pass band's relative error is measured, would otherwise lose half their digits.
double cos_difference(double a, double b) {
  return -2 * std::sin((a + b) / 2) * std::sin((a - b) / 2);
}

// The polynomial P through the current extremals with the levelled error delta, in barycentric form
// on x = cos w (well conditioned where the monomial or linear-system forms are not).
struct LevelledInterpolant {
  std::vector<double> value, bary;
  // sin and cos of half of each node's angle t: cos w - cos t = -2 sin((w+t)/2) sin((w-t)/2) then
  // costs a few products per node instead of two sines, and keeps cos_difference's accuracy (the
  // products' rounding is relative to the half-angle sines, however small).
  std::vector<double> half_sin, half_cos;
  double delta = 0;

  void set_nodes(std::span<const double> angle) {
    half_sin.resize(angle.size());
    half_cos.resize(angle.size());
    for (std::size_t i = 0; i < angle.size(); ++i) {
      half_sin[i] = std::sin(angle[i] / 2);
      half_cos[i] = std::cos(angle[i] / 2);
    }
  }

  double operator()(double w) const {
    const double sw = std::sin(w / 2), cw = std::cos(w / 2);
    double num = 0, den = 0;
    for (std::size_t i = 0; i < value.size(); ++i) {
      const double sum = sw * half_cos[i] + cw * half_sin[i];   // sin((w + t) / 2)
      const double diff = sw * half_cos[i] - cw * half_sin[i];  // sin((w - t) / 2)
      const double d = -2 * sum * diff;
      if (d == 0.0) return value[i];
      const double t = bary[i] / d;
      num += t * value[i];
      den += t;
    }
    return num / den;
  }
};

// Barycentric weights 1 / prod_{j != i} (x_i - x_j), up to a common factor (which cancels
// everywhere they are used); computed through logarithms so that long filters neither overflow nor
// underflow.
std::vector<double> barycentric_weights(std::span<const double> angle) {
  const std::size_t n = angle.size();
  std::vector<double> log_mag(n, 0.0);
  std::vector<double> sign(n, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i) continue;
      const double d = cos_difference(angle[i], angle[j]);
      log_mag[i] -= std::log(std::abs(d));
      if (d < 0) sign[i] = -sign[i];
    }
  }
  const double top = n > 0 ? *std::max_element(log_mag.begin(), log_mag.end()) : 0.0;
  std::vector<double> w(n);
  for (std::size_t i = 0; i < n; ++i) w[i] = sign[i] * std::exp(log_mag[i] - top);
  return w;
}

struct Point {
  double w;
  const Band* band;
  // A current extremal: |error| = |delta| there in exact arithmetic, so it is a candidate whatever
  // rounding does to it (when delta is tiny, early on, rounding is a sizeable part of it).
  bool extremal = false;
};

// Points closer than this (rad / sample) are one point: far below any grid step (pi / (16 * 513)),
// far above rounding.
constexpr double kSamePoint = 1e-9;

LevelledInterpolant level(const Problem& problem, std::span<const Point> extremals) {
  const std::size_t n = extremals.size();  // m + 1
  std::vector<double> angle(n), d(n), wt(n);
  for (std::size_t i = 0; i < n; ++i) {
    angle[i] = extremals[i].w;
    d[i] = problem.desired(extremals[i].w, extremals[i].band->pass);
    wt[i] = problem.weight(extremals[i].w, extremals[i].band->pass);
  }
  const std::vector<double> gamma = barycentric_weights(angle);
  double num = 0, den = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double alt = (i % 2 == 0) ? 1.0 : -1.0;
    num += gamma[i] * d[i];
    den += alt * gamma[i] / wt[i];
  }
  LevelledInterpolant p;
  p.delta = num / den;
  // P interpolates D - (-1)^i delta / W at every extremal. m of them would determine it, but the
  // formula over all m + 1 (whose degree-m term vanishes by the choice of delta) never
  // extrapolates: through m nodes, the one left out can sit across a band gap, where rounding grows
  // by 1e10.
  p.set_nodes(angle);
  p.value.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double alt = (i % 2 == 0) ? 1.0 : -1.0;
    p.value[i] = d[i] - alt * p.delta / wt[i];
  }
  p.bary = gamma;
  return p;
}

double weighted_error(const Problem& problem, const LevelledInterpolant& p, double w, bool pass) {
  return problem.weight(w, pass) * (p(w) - problem.desired(w, pass));
}

// Golden-section search for the extremum of sign `sign` of the error within [lo, hi].
double polish(const Problem& problem, const LevelledInterpolant& p, bool pass, double sign,
              double lo, double hi) {
  const double ratio = (std::sqrt(5.0) - 1) / 2;
  auto f = [&](double w) { return sign * weighted_error(problem, p, w, pass); };
  double a = lo, b = hi;
  double c = b - ratio * (b - a), d = a + ratio * (b - a);
  double fc = f(c), fd = f(d);
  for (int step = 0; step < kGoldenSteps && b - a > 1e-14; ++step) {
    if (fc >= fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - ratio * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + ratio * (b - a);
      fd = f(d);
    }
  }
  // The ends are candidates too: an extremum at a band edge is common.
  double best = (a + b) / 2, best_value = f(best);
  for (double w : {lo, hi}) {
    if (f(w) > best_value) {
      best = w;
      best_value = f(w);
    }
  }
  return best;
}

struct Candidate {
  std::size_t index;  // into the evaluated points
  double error;
};

struct Exchange {
  std::vector<Point> next;  // empty when rounding has scrambled the alternation
  double max_error = 0;     // of the current P over the grid and extremals
};

// The next set of m + 1 alternating extremals of the current error, from the grid and the current
// extremals (at which |error| = |delta| exactly, so there are always enough), each polished on the
// continuous axis.
Exchange exchange(const Problem& problem, const LevelledInterpolant& p, std::span<const Point> grid,
                  std::span<const Point> current) {
  std::vector<Point> points(current.begin(), current.end());
  for (Point& pt : points) pt.extremal = true;
  points.insert(points.end(), grid.begin(), grid.end());
  // Stable, so that of a grid point and an extremal at the same place the extremal is kept.
  std::stable_sort(points.begin(), points.end(),
                   [](const Point& a, const Point& b) { return a.w < b.w; });
  points.erase(std::unique(points.begin(), points.end(),
                           [](const Point& a, const Point& b) { return b.w - a.w < kSamePoint; }),
               points.end());

  Exchange result;
  std::vector<double> e(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    e[i] = weighted_error(problem, p, points[i].w, points[i].band->pass);
    result.max_error = std::max(result.max_error, std::abs(e[i]));
  }
  if (!std::isfinite(result.max_error)) return result;
  const double threshold = std::abs(p.delta) * (1 - 1e-6);

  std::vector<Candidate> found;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].extremal && std::abs(e[i]) < threshold) continue;
    const double s = e[i] > 0 ? 1.0 : -1.0;
    const bool left_ok = i == 0 || points[i - 1].band != points[i].band || s * e[i] >= s * e[i - 1];
    const bool right_ok =
        i + 1 == points.size() || points[i + 1].band != points[i].band || s * e[i] >= s * e[i + 1];
    if (!left_ok || !right_ok) continue;
    // Neighbouring extrema of one sign (a flat top, or a wiggle): keep the larger.
    if (!found.empty() && (found.back().error > 0) == (e[i] > 0)) {
      if (std::abs(e[i]) > std::abs(found.back().error)) found.back() = {i, e[i]};
      continue;
    }
    found.push_back({i, e[i]});
  }

  const std::size_t wanted = problem.m + 1;
  // Too many: drop the smallest, keeping alternation (an interior one takes a neighbour with it,
  // the larger of its two same-sign neighbours survives).
  while (found.size() > wanted) {
    std::size_t k = 0;
    for (std::size_t i = 1; i < found.size(); ++i) {
      if (std::abs(found[i].error) < std::abs(found[k].error)) k = i;
    }
    const bool end = k == 0 || k + 1 == found.size();
    if (!end && found.size() - wanted == 1) {
      k = std::abs(found.front().error) < std::abs(found.back().error) ? 0 : found.size() - 1;
    }
    if (k == 0 || k + 1 == found.size()) {
      found.erase(found.begin() + static_cast<std::ptrdiff_t>(k));
      continue;
    }
    const std::size_t drop =
        std::abs(found[k - 1].error) < std::abs(found[k + 1].error) ? k - 1 : k + 1;
    const std::size_t first = std::min(k, drop);
    found.erase(found.begin() + static_cast<std::ptrdiff_t>(first),
                found.begin() + static_cast<std::ptrdiff_t>(first + 2));
  }
  if (found.size() < wanted) return result;

  std::vector<Point> next(wanted);
  for (std::size_t k = 0; k < wanted; ++k) {
    const std::size_t i = found[k].index;
    const Band* band = points[i].band;
    // Search between the neighbouring evaluated points, never past the band or a neighbouring
    // extremal's half-way mark, so the polished extremals stay ordered.
    double lo = i > 0 && points[i - 1].band == band ? points[i - 1].w : points[i].w;
    double hi = i + 1 < points.size() && points[i + 1].band == band ? points[i + 1].w : points[i].w;
    if (k > 0) lo = std::max(lo, (points[found[k - 1].index].w + points[i].w) / 2);
    if (k + 1 < wanted) hi = std::min(hi, (points[found[k + 1].index].w + points[i].w) / 2);
    const double sign = found[k].error > 0 ? 1.0 : -1.0;
    next[k] = {polish(problem, p, band->pass, sign, lo, hi), band};
  }
  // Two polished extremals may meet at a shared half-way mark; the unpolished ones are distinct.
  for (std::size_t k = 1; k < wanted; ++k) {
    if (next[k].w - next[k - 1].w < kSamePoint) {
      next[k - 1].w = points[found[k - 1].index].w;
      next[k].w = points[found[k].index].w;
    }
  }
  result.next = std::move(next);
  return result;
}

std::vector<Point> make_grid(const Problem& problem, std::span<const Band> bands) {
  // For odd length A(pi) = 0 whatever the taps, and the weight W Q vanishes there: the grid stops
  // one step short of pi.
  const std::size_t grid_size = static_cast<std::size_t>(kGridDensity) * (problem.m + 1);
  double span = 0;
  for (const Band& band : bands) span += band.hi - band.lo;
  std::vector<Point> grid;
  for (const Band& band : bands) {
    const auto count =
        std::max<std::size_t>(8, static_cast<std::size_t>(std::ceil(static_cast<double>(grid_size) *
                                                                    (band.hi - band.lo) / span)));
    const double step = (band.hi - band.lo) / static_cast<double>(count - 1);
    const std::size_t last = (!band.pass && problem.odd_length) ? count - 1 : count;
    for (std::size_t i = 0; i < last; ++i) {
      grid.push_back({band.lo + step * static_cast<double>(i), &band});
    }
  }
  return grid;
}

// The classic start: m + 1 points spread evenly over the grid. Good for short filters; for long
// ones it levels the error at 1e-15 or below, where rounding scrambles its signs.
std::vector<Point> even_start(std::span<const Point> grid, std::size_t m) {
  std::vector<Point> start(m + 1);
  for (std::size_t i = 0; i <= m; ++i) start[i] = grid[i * (grid.size() - 1) / m];
  return start;
}

// A start for m from the extremals of a smaller problem: each band keeps its share of extremals,
// laid out like the smaller solution's (piecewise linearly in their index). The optimal extremals'
// distribution changes little with the length, so this starts close to the answer.
std::vector<Point> scaled_start(std::span<const Point> smaller, std::size_t m,
                                std::span<const Band> bands) {
  std::vector<std::vector<double>> old(bands.size());
  for (const Point& pt : smaller) {
    old[static_cast<std::size_t>(pt.band - bands.data())].push_back(pt.w);
  }
  std::vector<std::size_t> count(bands.size());
  std::size_t assigned = 0;
  for (std::size_t b = 0; b + 1 < bands.size(); ++b) {
    count[b] = static_cast<std::size_t>(
        std::lround(static_cast<double>(old[b].size()) * static_cast<double>(m + 1) /
                    static_cast<double>(smaller.size())));
    count[b] = std::min(count[b], m + 1 - assigned);
    assigned += count[b];
  }
  count.back() = m + 1 - assigned;

  std::vector<Point> start;
  for (std::size_t b = 0; b < bands.size(); ++b) {
    const std::vector<double>& w = old[b];
    for (std::size_t k = 0; k < count[b]; ++k) {
      double at = 0;
      if (w.empty()) {
        at = bands[b].lo + (bands[b].hi - bands[b].lo) * (static_cast<double>(k) + 0.5) /
                               static_cast<double>(count[b]);
      } else if (count[b] == 1 || w.size() == 1) {
        at = w[w.size() / 2];
      } else {
        const double u = static_cast<double>(k) * static_cast<double>(w.size() - 1) /
                         static_cast<double>(count[b] - 1);
        const auto i = std::min(static_cast<std::size_t>(u), w.size() - 2);
        at = w[i] + (u - static_cast<double>(i)) * (w[i + 1] - w[i]);
      }
      start.push_back({at, &bands[b]});
    }
  }
  return start;
}

struct Stage {
  LevelledInterpolant p;
  std::vector<Point> extremals;
  int iterations = 0;
  bool converged = false;
  double max_error = 0;
  std::string failure;
};

// The exchange from `start` until the error is level, or, when rounding stops it first, the best
// design it met.
Stage run_exchange(const Problem& problem, std::span<const Point> grid, std::vector<Point> start) {
  Stage best;
  best.max_error = std::numeric_limits<double>::infinity();
  std::vector<Point> extremals = std::move(start);
  for (int iteration = 1;; ++iteration) {
    const LevelledInterpolant p = level(problem, extremals);
    const Exchange step = exchange(problem, p, grid, extremals);
    best.iterations = iteration;
    if (std::isfinite(p.delta) && step.max_error < best.max_error) {
      best.p = p;
      best.extremals = extremals;
      best.max_error = step.max_error;
    }
    if (!step.next.empty()) {
      double lo = std::numeric_limits<double>::infinity(), hi = 0;
      for (const Point& pt : step.next) {
        const double e = std::abs(weighted_error(problem, p, pt.w, pt.band->pass));
        lo = std::min(lo, e);
        hi = std::max(hi, e);
      }
      if (hi - lo <= std::max(kLevelTolerance * hi, kLevelFloor)) {
        best.p = p;
        best.extremals = step.next;
        best.max_error = hi;
        best.converged = true;
        return best;
      }
      extremals = step.next;
    }
    if (step.next.empty() || iteration == kMaxIterations) {
      // Rounding, not the design, stopped the exchange: the best design is still good if its error
      // is far below anything a differentiator here needs.
      best.converged = best.max_error <= kNegligibleError;
      best.failure = std::string(step.next.empty() ? "alternation lost" : "iteration limit") +
                     " after " + std::to_string(iteration) + " iterations, max weighted error " +
                     std::to_string(best.max_error);
      return best;
    }
  }
}

// The design for problem.m cosine coefficients. Long filters start from the solution for half their
// length, recursively, down to one short enough for the even start ("reference scaling").
Stage solve(const Problem& problem, std::span<const Band> bands) {
  std::vector<std::size_t> sizes{problem.m};
  while (sizes.back() > kEvenStartLimit) sizes.push_back(sizes.back() / 2);
  std::reverse(sizes.begin(), sizes.end());
  Stage stage;
  int iterations = 0;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    Problem sub = problem;
    sub.m = sizes[i];
    const std::vector<Point> grid = make_grid(sub, bands);
    std::vector<Point> start =
        i == 0 ? even_start(grid, sub.m) : scaled_start(stage.extremals, sub.m, bands);
    // A smaller problem that stopped short still gives a usable start; only the last one counts.
    stage = run_exchange(sub, grid, std::move(start));
    iterations += stage.iterations;
  }
  stage.iterations = iterations;
  return stage;
}

// Cosine coefficients of P from its values at the Chebyshev angles (a discrete cosine transform).
std::vector<double> cosine_coefficients(const LevelledInterpolant& p, std::size_t m) {
  std::vector<double> values(m);
  for (std::size_t j = 0; j < m; ++j) {
    values[j] = p(kPi * (static_cast<double>(j) + 0.5) / static_cast<double>(m));
  }
  std::vector<double> coefficients(m);
  for (std::size_t k = 0; k < m; ++k) {
    double sum = 0;
    for (std::size_t j = 0; j < m; ++j) {
      sum += values[j] * std::cos(kPi * static_cast<double>(k) * (static_cast<double>(j) + 0.5) /
                                  static_cast<double>(m));
    }
    coefficients[k] = sum * (k == 0 ? 1.0 : 2.0) / static_cast<double>(m);
  }
  return coefficients;
}

// Taps (per sample) from P's cosine coefficients, through the product-to-sum identities
// sin(w) cos(kw) = (sin((k+1)w) - sin((k-1)w)) / 2 and the same for sin(w/2).
std::vector<double> taps_from_cosines(std::span<const double> p, bool odd_length) {
  const std::size_t m = p.size();
  // s[k], k = 1..m: coefficient of sin(k w) (odd length) or sin((k - 1/2) w) (even length).
  std::vector<double> s(m + 2, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    if (k == 0) {
      s[1] += p[0];
      continue;
    }
    s[k + 1] += p[k] / 2;
    // sin((k-1) w) for odd length; sin((k - 1/2) w) is basis function k for even length.
    s[odd_length ? k - 1 : k] -= p[k] / 2;
  }
  const std::size_t n = odd_length ? 2 * m + 1 : 2 * m;
  std::vector<double> taps(n, 0.0);
  for (std::size_t k = 1; k <= m; ++k) {
    // About the centre c = (n - 1) / 2: A(w) = sum_j h[j] sin(w (c - j)), so the tap k (or k - 1/2)
    // samples before the centre carries half the sine coefficient, its mirror the negated half.
    taps[m - k] = s[k] / 2;
    taps[n - 1 - (m - k)] = -s[k] / 2;
  }
  return taps;
}

// A(w) of per-sample taps about their centre.
double amplitude(std::span<const double> taps, double w) {
  const double centre = (static_cast<double>(taps.size()) - 1) / 2;
  double a = 0;
  for (std::size_t j = 0; j < taps.size(); ++j) {
    a += taps[j] * std::sin(w * (centre - static_cast<double>(j)));
  }
  return a;
}

// One design of problem.m cosine coefficients, as taps (per sample) of the requested length, with
// the errors the taps achieve.
struct Attempt {
  std::vector<double> taps;
  bool converged = false;
  std::string failure;
  int iterations = 0;
  double level = 0;     // the exchange's levelled weighted error
  double achieved = 0;  // the taps' maximum weighted error
  double max_passband_relative_error = 0;
  double max_stopband_gain_per_sample = 0;

  // The taps achieve the level the exchange found (up to evaluation on another grid): the design is
  // the optimum for its length.
  bool delivers_level() const { return converged && achieved <= level * (1 + 1e-6) + 1e-12; }
};

Attempt attempt(const Problem& problem, std::span<const Band> bands, int num_taps) {
  Attempt a;
  Stage stage = solve(problem, bands);
  a.converged = stage.converged;
  a.failure = stage.failure;
  a.iterations = stage.iterations;
  a.level = stage.max_error;
  if (!a.converged) return a;

  a.taps.assign(static_cast<std::size_t>(num_taps), 0.0);
  const std::vector<double> core =
      taps_from_cosines(cosine_coefficients(stage.p, problem.m), problem.odd_length);
  std::copy(core.begin(), core.end(),
            a.taps.begin() + static_cast<std::ptrdiff_t>((a.taps.size() - core.size()) / 2));

  // Achieved errors from the taps themselves (an independent check of the conversion), on a fine
  // grid plus the polished extremals, where the maxima are.
  const double wp = bands[0].hi, ws = bands[1].lo;
  const std::size_t fine = 16 * static_cast<std::size_t>(num_taps);
  std::vector<double> pass_points, stop_points;
  for (std::size_t i = 1; i <= fine; ++i) {
    pass_points.push_back(wp * static_cast<double>(i) / static_cast<double>(fine));
    stop_points.push_back(ws +
                          (kPi - ws) * static_cast<double>(i - 1) / static_cast<double>(fine - 1));
  }
  for (const Point& pt : stage.extremals) {
    (pt.band->pass ? pass_points : stop_points).push_back(pt.w);
  }
  for (double w : pass_points) {
    if (w <= 0) continue;
    a.max_passband_relative_error =
        std::max(a.max_passband_relative_error, std::abs(amplitude(a.taps, w) - w) / w);
  }
  for (double w : stop_points) {
    a.max_stopband_gain_per_sample =
        std::max(a.max_stopband_gain_per_sample, std::abs(amplitude(a.taps, w)));
  }
  a.achieved =
      std::max(a.max_passband_relative_error, problem.stop_weight * a.max_stopband_gain_per_sample);
  return a;
}

}  // namespace

std::complex<double> FirDifferentiator::response(double frequency_hz) const {
  const double w = 2 * kPi * frequency_hz / sample_rate_hz;
  const double centre = (static_cast<double>(taps.size()) - 1) / 2;
  std::complex<double> h = 0;
  for (std::size_t j = 0; j < taps.size(); ++j) {
    h += taps[j] * std::polar(1.0, -w * (static_cast<double>(j) - centre));
  }
  return h;
}

FirDifferentiator design_fir_differentiator(int num_taps, double passband_hz, double stopband_hz,
                                            double sample_rate_hz) {
  require(num_taps >= 2 && num_taps <= kMaxTaps, "num_taps",
          "must be in [2, " + std::to_string(kMaxTaps) + "], got " + std::to_string(num_taps));
  require(std::isfinite(sample_rate_hz) && sample_rate_hz > 0, "sample_rate_hz",
          "must be finite and positive");
  require(std::isfinite(passband_hz) && passband_hz > 0 && passband_hz < sample_rate_hz / 2,
          "passband_hz", "must be in (0, sample_rate_hz / 2)");
  require(
      std::isfinite(stopband_hz) && stopband_hz > passband_hz && stopband_hz < sample_rate_hz / 2,
      "stopband_hz", "must be in (passband_hz, sample_rate_hz / 2)");

  const bool odd_length = num_taps % 2 == 1;
  const double wp = 2 * kPi * passband_hz / sample_rate_hz;
  const double ws = 2 * kPi * stopband_hz / sample_rate_hz;
  const Problem problem{odd_length, static_cast<std::size_t>(num_taps / 2),
                        kStopbandRelativeWeight / wp};
  const Band bands[2] = {{0.0, wp, true}, {ws, kPi, false}};

  Attempt best = attempt(problem, bands, num_taps);
  int iterations = best.iterations;
  if (!best.delivers_level()) {
    // A length far beyond what the band edges need puts the optimal error below rounding: the
    // exchange cannot level it, or the taps cannot hold it (they grow large and cancel). The
    // longest shorter design that still delivers its own level (found by bisection) is as good as
    // double precision allows; padded with zero taps at both ends it is a filter of the requested
    // length. Of it and the full-length attempt, the one whose taps do better is kept.
    const std::string failure =
        best.converged
            ? "the taps lose the levelled error to rounding: " + std::to_string(best.achieved) +
                  " for " + std::to_string(best.level)
            : best.failure;
    std::size_t bad = problem.m, good = 0;
    Attempt kept;
    for (std::size_t trial = problem.m / 2; trial >= 1 && good + 1 < bad;) {
      Problem shorter = problem;
      shorter.m = trial;
      Attempt a = attempt(shorter, bands, num_taps);
      iterations += a.iterations;
      if (a.delivers_level()) {
        good = trial;
        kept = std::move(a);
      } else {
        bad = trial;
      }
      trial = good == 0 ? trial / 2 : (good + bad) / 2;
    }
    if (good == 0 && !best.converged) {
      throw std::runtime_error("design_fir_differentiator: the Remez exchange did not converge (" +
                               failure + "); fewer taps or a narrower transition band would help");
    }
    if (good != 0 && (!best.converged || kept.achieved < best.achieved)) best = std::move(kept);
  }

  FirDifferentiator filter;
  filter.taps = std::move(best.taps);
  for (double& t : filter.taps) t *= sample_rate_hz;
  filter.sample_rate_hz = sample_rate_hz;
  filter.passband_hz = passband_hz;
  filter.stopband_hz = stopband_hz;
  filter.max_passband_relative_error = best.max_passband_relative_error;
  filter.max_stopband_gain = best.max_stopband_gain_per_sample * sample_rate_hz;
  filter.iterations = iterations;
  return filter;
}

std::vector<double> differentiate(const FirDifferentiator& filter, std::span<const double> signal) {
  const std::size_t taps = filter.taps.size();
  // An even-length (type IV) filter is centred half-way between samples: its output belongs at
  // t + T/2. Shifting it back would need an interpolator with its own error, so differentiate takes
  // odd lengths only; the designer still makes type IV filters for anyone who wants them.
  require(
      taps % 2 == 1, "filter",
      "differentiate needs an odd number of taps (an even-length filter has a half-sample delay), "
      "got " +
          std::to_string(taps));
  require(std::isfinite(filter.sample_rate_hz) && filter.sample_rate_hz > 0, "filter",
          "sample_rate_hz must be finite and positive");
  const auto n = static_cast<std::ptrdiff_t>(signal.size());
  if (n == 0) return {};
  // One sample says nothing about the slope.
  if (n == 1) return {0.0};

  // Odd reflection about the end values, repeated when the filter is longer than the signal: a
  // straight line extends as itself, so a ramp differentiates exactly at every sample.
  auto extended = [&](std::ptrdiff_t i) {
    double offset = 0, sign = 1;
    while (i < 0 || i >= n) {
      if (i < 0) {
        offset += sign * 2 * signal[0];
        i = -i;
      } else {
        offset += sign * 2 * signal[static_cast<std::size_t>(n - 1)];
        i = 2 * (n - 1) - i;
      }
      sign = -sign;
    }
    return offset + sign * signal[static_cast<std::size_t>(i)];
  };

  const auto half = static_cast<std::ptrdiff_t>(taps / 2);
  std::vector<double> out(static_cast<std::size_t>(n));
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const bool inside = i - half >= 0 && i + half < n;
    double sum = 0;
    for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(taps); ++j) {
      const std::ptrdiff_t at = i + half - j;
      sum += filter.taps[static_cast<std::size_t>(j)] *
             (inside ? signal[static_cast<std::size_t>(at)] : extended(at));
    }
    out[static_cast<std::size_t>(i)] = sum;
  }
  return out;
}

}  // namespace furuta::identification
