#pragma once
// Point simulations in long double (classical RK4 with small steps) and the soundness check of a
// tube against them: every sampled solution must be inside the tight enclosure at every step end,
// inside the step's enclosure over [t0, t1] at every substep, and inside enclosure_at() at the
// middle of every step.

#include <array>
#include <cmath>
#include <cstddef>
#include <random>
#include <span>
#include <vector>

#include "furuta/validated/integrator.hpp"

namespace furuta::validated::testing {

template <std::size_t N>
using Point = std::array<long double, N>;

// sin and cos in long double with the argument first reduced by pi/2 (Cody-Waite, pi/2 split in
// three parts, the first two of 40 bits so that k * part is exact for |k| < 2^20): glibc's sinl
// and cosl are then only called on |r| <= pi/4, their fast path (about 50 ns instead of up to
// 1 us). The reduction's error is a few units of 2^-64 relative to r.
// sin (cosine = false) or cos of x.
inline long double sin_or_cos_ld(long double x, bool cosine) {
  constexpr long double kTwoOverPi = 0x517cc1b727220a95p-63L;
  constexpr long double kP1 = 0xc90fdaa221p-39L;
  constexpr long double kP2 = 0xd18469898dp-80L;
  constexpr long double kP3 = -0x75d1fc8f8cbb5bf7p-145L;
  // x 2/pi rounded to an integer (adding and removing 1.5 2^63 rounds in the 64-bit mantissa;
  // nearbyintl is much slower).
  constexpr long double kRound = 0x1.8p63L;
  const long double k = (x * kTwoOverPi + kRound) - kRound;
  const long double r = ((x - k * kP1) - k * kP2) - k * kP3;
  // sin(r + q pi/2) for q = k (sin) or k + 1 (cos).
  switch ((static_cast<long long>(k) + (cosine ? 1 : 0)) & 3) {
    case 0:
      return std::sin(r);
    case 1:
      return std::cos(r);
    case 2:
      return -std::sin(r);
    default:
      return -std::cos(r);
  }
}

// The reference simulations' scalar: long double, with the fast sin and cos above. Interval
// constants (a torque piece) become their midpoint.
struct Real {
  long double v = 0;
  Real() = default;
  Real(long double x) : v(x) {}                      // NOLINT
  Real(double x) : v(x) {}                           // NOLINT
  Real(const interval::Interval& x) : v(x.mid()) {}  // NOLINT
  friend Real operator+(Real a, Real b) { return a.v + b.v; }
  friend Real operator-(Real a, Real b) { return a.v - b.v; }
  friend Real operator*(Real a, Real b) { return a.v * b.v; }
  friend Real operator/(Real a, Real b) { return a.v / b.v; }
  friend Real operator-(Real a) { return -a.v; }
  friend Real sin(Real a) { return sin_or_cos_ld(a.v, false); }
  friend Real cos(Real a) { return sin_or_cos_ld(a.v, true); }
};

// One RK4 step of dt on the field of `piece`.
template <class System, std::size_t N>
Point<N> rk4(const System& system, std::size_t piece, const Point<N>& x, long double dt) {
  auto f = [&](const Point<N>& y) {
    std::array<Real, N> yr;
    std::array<Real, N> dr;
    for (std::size_t i = 0; i < N; ++i) yr[i] = y[i];
    evaluate_field(system, piece, std::span<const Real>(yr), std::span<Real>(dr));
    Point<N> d;
    for (std::size_t i = 0; i < N; ++i) d[i] = dr[i].v;
    return d;
  };
  auto axpy = [](const Point<N>& y, const Point<N>& d, long double h) {
    Point<N> out;
    for (std::size_t i = 0; i < N; ++i) out[i] = y[i] + h * d[i];
    return out;
  };
  const Point<N> k1 = f(x);
  const Point<N> k2 = f(axpy(x, k1, dt / 2));
  const Point<N> k3 = f(axpy(x, k2, dt / 2));
  const Point<N> k4 = f(axpy(x, k3, dt));
  Point<N> out;
  for (std::size_t i = 0; i < N; ++i)
    out[i] = x[i] + dt / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
  return out;
}

// x(t_end) from x(t_start), RK4 with at most max_dt per step, the field's pieces respected.
template <class System, std::size_t N>
Point<N> simulate(const System& system, Point<N> x, double t_start, double t_end, double max_dt) {
  const std::vector<double> switches = switch_times(system);
  double t = t_start;
  while (t < t_end) {
    const std::size_t piece = piece_at(switches, t);
    const double stop = piece < switches.size() ? std::min(t_end, switches[piece]) : t_end;
    const long double span = static_cast<long double>(stop) - t;
    const auto n = static_cast<long>(std::ceil(static_cast<double>(span) / max_dt));
    for (long i = 0; i < n; ++i) x = rk4(system, piece, x, span / n);
    t = stop;
  }
  return x;
}

template <std::size_t N>
bool inside(const Point<N>& x, const interval::Box& box) {
  for (std::size_t i = 0; i < N; ++i) {
    if (!(x[i] >= box[i].lo() && x[i] <= box[i].hi())) return false;
  }
  return true;
}

struct SoundnessCount {
  std::size_t points = 0;      // solutions simulated
  std::size_t checks = 0;      // containment checks
  std::size_t violations = 0;  // checks failed
};

// Simulates each initial point along the tube's steps (substeps RK4 substeps per step, an even
// number so the step's middle is a substep time) and counts the containment checks.
template <class System, std::size_t N>
SoundnessCount check_tube(const System& system, const Tube& tube,
                          const std::vector<Point<N>>& initial_points, int substeps) {
  const std::vector<double> switches = switch_times(system);
  // enclosure_at() at the middle of every step, shared by all points.
  std::vector<interval::Box> middle;
  std::vector<long double> middle_time;
  for (const TubeStep& s : tube.steps) {
    const long double tm =
        static_cast<long double>(s.t0) + (static_cast<long double>(s.t1) - s.t0) / 2;
    middle_time.push_back(tm);
    middle.push_back(tube.enclosure_at(static_cast<double>(tm)));
  }
  SoundnessCount count;
  for (const Point<N>& x0 : initial_points) {
    ++count.points;
    Point<N> x = x0;
    ++count.checks;
    count.violations += !inside(x, tube.initial);
    for (std::size_t j = 0; j < tube.steps.size(); ++j) {
      const TubeStep& s = tube.steps[j];
      const std::size_t piece = piece_at(switches, s.t0);
      const long double h = static_cast<long double>(s.t1) - s.t0;
      for (int i = 1; i <= substeps; ++i) {
        x = rk4(system, piece, x, h / substeps);
        ++count.checks;
        if (i == substeps) {
          count.violations += !inside(x, s.end);
        } else {
          count.violations += !inside(x, s.over);
          if (2 * i == substeps && static_cast<double>(middle_time[j]) > s.t0 &&
              static_cast<double>(middle_time[j]) < s.t1) {
            // the middle substep time differs from the query time by rounding only
            ++count.checks;
            count.violations += !inside(x, middle[j]);
          }
        }
      }
    }
  }
  return count;
}

// count random points in the box, plus its corners (all 2^N of them when N <= 4, else none).
template <std::size_t N>
std::vector<Point<N>> sample_box(const interval::Box& box, std::size_t count,
                                 std::mt19937_64& rng) {
  std::vector<Point<N>> points;
  if (N <= 4) {
    for (std::size_t mask = 0; mask < (std::size_t{1} << N); ++mask) {
      Point<N> p;
      for (std::size_t i = 0; i < N; ++i) p[i] = (mask >> i) & 1U ? box[i].hi() : box[i].lo();
      points.push_back(p);
    }
  }
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t k = 0; k < count; ++k) {
    Point<N> p;
    for (std::size_t i = 0; i < N; ++i) {
      // a quarter of the draws on a face of the box (the extremes come from its boundary)
      const double r = u(rng);
      double v = box[i].lo() + r * (box[i].hi() - box[i].lo());
      if (k % 4 == 0 && i == k / 4 % N) v = r < 0.5 ? box[i].lo() : box[i].hi();
      p[i] = std::min(std::max(v, box[i].lo()), box[i].hi());
    }
    points.push_back(p);
  }
  return points;
}

// The start of the paper's scenario (a) as the tests take it: [0, 0, -100 deg, 0] +- 1e-3
// (q2 +- 1.6e-3, the pendulum's encoder).
inline interval::Box scenario_a_state() {
  const double q2 = -100.0 * 3.14159265358979323846 / 180.0;
  return interval::Box{interval::Interval(-1e-3, 1e-3), interval::Interval(-1e-3, 1e-3),
                       interval::Interval(q2 - 1.6e-3, q2 + 1.6e-3),
                       interval::Interval(-1e-3, 1e-3)};
}

// The integrator's options for the Furuta model in these tests: the QR frame (the damped arm), a
// remainder tolerance of 1e-10, to t_end.
inline IntegratorOptions furuta_test_options(double t_end) {
  IntegratorOptions options;
  options.t_end = t_end;
  options.tolerance = 1e-10;
  options.max_inflation = 1.0;
  return options;
}

}  // namespace furuta::validated::testing
