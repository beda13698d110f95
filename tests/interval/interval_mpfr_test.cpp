// Soundness of every interval operation against MPFR at 200 bits: random operand intervals (all
// magnitudes, zero-crossing, points, unbounded, wide and narrow sin/cos arguments), random points
// inside them (endpoints included), the exact value of the operation at those points computed in
// MPFR, and the check, done in MPFR, that it lies in the enclosure. Zero violations allowed.
//
// MPFR rounds to nearest and returns the direction of its rounding (the ternary value), so the
// exact value is known to lie between the MPFR result and its 200-bit neighbour on that side; the
// check uses that neighbour, so it never passes an exact value that is outside.
//
// FURUTA_LONG_TESTS=1 multiplies every count by 10.
#include <gtest/gtest.h>
#include <mpfr.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "furuta/interval/interval.hpp"
#include "mpfr_oracle.hpp"

namespace furuta::interval::interval_mpfr_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMax = std::numeric_limits<double>::max();

int scale() {
  const char* v = std::getenv("FURUTA_LONG_TESTS");
  return (v != nullptr && std::string(v) == "1") ? 10 : 1;
}

// ---- MPFR helpers -------------------------------------------------------------------------------

using furuta::testing::d_str;
using furuta::testing::Mp;

// The oracle's numbers in the reports of a violation.
std::string mp_str(mpfr_srcptr v) {
  return furuta::testing::mp_str(v, 64);
}

// Signed distance in ulps from a to b (b >= a), through zero and subnormals.
std::int64_t ulps_between(double a, double b) {
  auto ordered = [](double x) {
    std::int64_t i;
    std::memcpy(&i, &x, sizeof i);
    return i < 0 ? std::numeric_limits<std::int64_t>::min() - i : i;
  };
  return ordered(b) - ordered(a);
}

// ---- Counting -----------------------------------------------------------------------------------

struct Totals {
  std::atomic<std::uint64_t> checks{0};
  std::atomic<std::uint64_t> violations{0};
  std::atomic<std::int64_t> micros{0};
};
Totals& totals() {
  static Totals t;
  return t;
}

class MeasuredEnvironment : public ::testing::Environment {
 public:
  void TearDown() override {
    const Totals& t = totals();
    if (t.checks == 0) return;
    std::printf(
        "[ measured ] %llu point checks, %llu violations, %.2f s (all MPFR property tests)\n",
        static_cast<unsigned long long>(t.checks.load()),
        static_cast<unsigned long long>(t.violations.load()), t.micros.load() * 1e-6);
  }
};
[[maybe_unused]] const auto* const kEnvironment =
    ::testing::AddGlobalTestEnvironment(new MeasuredEnvironment);

// One property test's checks: counts, times, reports the first violations in full.
class Checker {
 public:
  explicit Checker(std::string name)
      : name_(std::move(name)), start_(std::chrono::steady_clock::now()) {}
  Checker(const Checker&) = delete;
  Checker& operator=(const Checker&) = delete;
  ~Checker() {
    const auto us = std::chrono::duration_cast<std::chrono::microseconds>(
                        std::chrono::steady_clock::now() - start_)
                        .count();
    totals().checks += checks_;
    totals().violations += violations_;
    totals().micros += us;
    std::printf("[ measured ] %s: %llu point checks, %llu violations, %.2f s\n", name_.c_str(),
                static_cast<unsigned long long>(checks_),
                static_cast<unsigned long long>(violations_), us * 1e-6);
    EXPECT_EQ(violations_, 0U) << name_;
  }

  // The exact value v (rounded by MPFR with ternary t) must lie in r.
  template <class What>
  void check(const Interval& r, mpfr_srcptr v, int t, const What& what) {
    ++checks_;
    if (encloses(r, v, t)) return;
    fail(what() + " exact " + mp_str(v) + " (ternary " + std::to_string(t) + ") not in " +
         to_string(r));
  }

  // The exact value lies within slack of v (v and slack computed in MPFR): [v - slack, v + slack]
  // must lie in r.
  template <class What>
  void check_slack(const Interval& r, mpfr_srcptr v, mpfr_srcptr slack, const What& what) {
    ++checks_;
    mpfr_sub(tmp_.get(), v, slack, MPFR_RNDD);
    const bool lo_ok = r.lo() == -kInf || mpfr_cmp_d(tmp_.get(), r.lo()) >= 0;
    mpfr_add(tmp_.get(), v, slack, MPFR_RNDU);
    const bool hi_ok = r.hi() == kInf || mpfr_cmp_d(tmp_.get(), r.hi()) <= 0;
    if (lo_ok && hi_ok && !r.is_empty()) return;
    fail(what() + " value " + mp_str(v) + " +- " + mp_str(slack) + " not in " + to_string(r));
  }

  // A point inside an argument box must survive a backward operator.
  template <class What>
  void check_kept(const Interval& x, double p, const What& what) {
    ++checks_;
    if (x.contains(p)) return;
    fail(what() + " point " + d_str(p) + " removed: " + to_string(x));
  }

  void fail(const std::string& message) {
    ++violations_;
    if (violations_ <= 10) ADD_FAILURE() << name_ << ": " << message;
  }

  std::uint64_t checks() const { return checks_; }

 private:
  static std::string to_string(const Interval& x) {
    std::ostringstream s;
    s << x;
    return s.str();
  }

  bool encloses(const Interval& r, mpfr_srcptr v, int t) {
    if (r.is_empty()) return false;
    bool lo_ok = true;
    bool hi_ok = true;
    if (r.lo() != -kInf) {
      if (t > 0) {  // v above the exact value: compare its lower neighbour
        mpfr_set(tmp_.get(), v, MPFR_RNDN);
        mpfr_nextbelow(tmp_.get());
        lo_ok = mpfr_cmp_d(tmp_.get(), r.lo()) >= 0;
      } else {
        lo_ok = mpfr_cmp_d(v, r.lo()) >= 0;
      }
    }
    if (r.hi() != kInf) {
      if (t < 0) {
        mpfr_set(tmp_.get(), v, MPFR_RNDN);
        mpfr_nextabove(tmp_.get());
        hi_ok = mpfr_cmp_d(tmp_.get(), r.hi()) <= 0;
      } else {
        hi_ok = mpfr_cmp_d(v, r.hi()) <= 0;
      }
    }
    return lo_ok && hi_ok;
  }

  std::string name_;
  std::chrono::steady_clock::time_point start_;
  std::uint64_t checks_ = 0;
  std::uint64_t violations_ = 0;
  Mp tmp_;
};

// ---- Random operands ----------------------------------------------------------------------------

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed) {}

  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }
  bool coin(double p) { return uniform(0, 1) < p; }
  double sign() { return coin(0.5) ? 1.0 : -1.0; }
  double magnitude(double e_lo, double e_hi) { return std::pow(10.0, uniform(e_lo, e_hi)); }

  double any_finite() {
    for (;;) {
      const std::uint64_t bits = rng_();
      double d;
      std::memcpy(&d, &bits, sizeof d);
      if (std::isfinite(d)) return d;
    }
  }

  static constexpr int kScalarKinds = 10;
  // A scalar of the given magnitude class.
  //
  // At most one draw per expression, here and in every caller: the order in which the operands of
  // one expression (a * b, f(a, b)) are evaluated is unspecified, and GCC picks other orders on
  // aarch64 than on x86-64, which gave the two architectures other operands from the same seed
  // (docs/arm64.md: the check counts must agree).
  double scalar(int kind) {
    const double s = sign();
    switch (kind) {
      case 0:
        return s * magnitude(-3, 3);
      case 1:
        return s * magnitude(250, 308.2);  // huge; products and sums overflow
      case 2:
        return s * magnitude(-323.5, -290);  // tiny, subnormals, underflow
      case 3:
        return 0.0;
      case 4:
        return any_finite();  // every exponent
      case 5:
        return static_cast<double>(pick(41) - 20);  // small integers: exact results
      case 6:
        return s * (1.0 + std::ldexp(static_cast<double>(pick(8)), -52));  // near 1
      case 7:
        return s * kMax * uniform(0.2, 1);  // sums overflow
      case 8:  // around the smallest normal, sums and differences land on subnormals
        return s * std::numeric_limits<double>::min() * uniform(0, 4);
      default:
        return s * magnitude(-30, 30);
    }
  }
  double scalar() { return scalar(pick(kScalarKinds)); }

  // An operand interval of one of many shapes.
  Interval operand() {
    const int shape = pick(100);
    if (shape < 12) return Interval(scalar());  // point
    if (shape < 32) {
      const double a = scalar();
      return sorted(a, scalar());
    }
    if (shape < 52) {
      const int kind = pick(kScalarKinds);
      const double a = scalar(kind);
      return sorted(a, scalar(kind));
    }
    if (shape < 67) {  // crosses zero
      const double lo = -std::fabs(scalar());
      return Interval(lo, std::fabs(scalar()));
    }
    if (shape < 77) {
      const double v = std::fabs(scalar());
      return coin(0.5) ? Interval(0.0, v) : Interval(-v, 0.0);
    }
    if (shape < 92) return narrow(scalar());
    if (shape < 98) {
      const double v = scalar();
      return coin(0.5) ? Interval(v, kInf) : Interval(-kInf, v);
    }
    return Interval::entire();
  }

  // An interval a few ulps to a relative 1e-6 wide, starting at v.
  Interval narrow(double v) {
    double hi;
    if (coin(0.5)) {
      hi = v;
      for (int i = pick(4) + 1; i > 0; --i) hi = std::nextafter(hi, kInf);
    } else {
      hi = v + std::fabs(v) * magnitude(-16, -6);
    }
    if (!(hi > v)) hi = std::nextafter(v, kInf);
    return Interval(v, std::min(hi, kMax));
  }

  // A finite point of x: its bounds for which 0 and 1, else a random point of several kinds.
  double point_in(const Interval& x, int which) {
    if (which == 0 && std::isfinite(x.lo())) return x.lo();
    if (which == 1 && std::isfinite(x.hi())) return x.hi();
    for (int attempt = 0; attempt < 8; ++attempt) {
      double p = 0;
      switch (pick(4)) {
        case 0:
          p = linear(x);
          break;
        case 1:
          p = scalar();
          break;
        case 2: {  // a few ulps inside a bound
          const bool from_lo = coin(0.5) ? std::isfinite(x.lo()) : !std::isfinite(x.hi());
          p = from_lo ? x.lo() : x.hi();
          for (int i = pick(3) + 1; i > 0; --i) p = std::nextafter(p, from_lo ? kInf : -kInf);
          break;
        }
        default:  // log-uniform between the bounds' magnitudes
          p = log_between(x);
          break;
      }
      if (x.contains(p)) return p;
    }
    return x.mid();
  }

  std::mt19937_64& rng() { return rng_; }

 private:
  static Interval sorted(double a, double b) { return Interval(std::min(a, b), std::max(a, b)); }

  double linear(const Interval& x) {
    const double t = uniform(0, 1);
    if (x.is_entire()) return scalar();
    if (x.lo() == -kInf) return x.hi() - magnitude(-3, 300);
    if (x.hi() == kInf) return x.lo() + magnitude(-3, 300);
    double p = x.lo() + t * (x.hi() - x.lo());
    if (!std::isfinite(p)) p = x.lo() * (1 - t) + x.hi() * t;
    return std::clamp(p, x.lo(), x.hi());
  }

  double log_between(const Interval& x) {
    const double a = std::max(std::fabs(x.mig()), 1e-320);
    const double b = std::min(x.mag(), kMax);
    if (!(a < b)) return linear(x);
    const double e = uniform(std::log10(a), std::log10(b));
    const double m = std::pow(10.0, e);
    if (x.lo() >= 0) return m;
    if (x.hi() <= 0) return -m;
    return sign() * m;
  }

  std::mt19937_64 rng_;
};

auto describe(const Interval& x, double px) {
  return [x, px] {
    std::ostringstream s;
    s << "x = " << x << " at " << d_str(px) << ":";
    return s.str();
  };
}

auto describe(const Interval& x, const Interval& y, double px, double py) {
  return [x, y, px, py] {
    std::ostringstream s;
    s << "x = " << x << ", y = " << y << " at (" << d_str(px) << ", " << d_str(py) << "):";
    return s.str();
  };
}

// ---- Binary operations --------------------------------------------------------------------------

using MpfrBinary = int (*)(mpfr_ptr, mpfr_srcptr, mpfr_srcptr, mpfr_rnd_t);

void binary_property(const char* name, std::uint64_t seed, int pairs,
                     Interval (*op)(const Interval&, const Interval&), MpfrBinary mop,
                     bool is_division) {
  Checker checker(name);
  Draw draw(seed);
  Mp mx, my, v;
  for (int n = 0; n < pairs; ++n) {
    const Interval x = draw.operand();
    const Interval y = draw.operand();
    const Interval r = op(x, y);
    // Tightness for points: exact, or the two doubles around the exact value.
    if (x.is_point() && y.is_point() && r.is_bounded() && !(is_division && y.lo() == 0)) {
      EXPECT_LE(ulps_between(r.lo(), r.hi()), 1) << name << " " << x << " " << y << " " << r;
    }
    for (int k = 0; k < 8; ++k) {
      const double px = draw.point_in(x, k < 4 ? k % 2 : 2);
      const double py = draw.point_in(y, k < 4 ? k / 2 : 2);
      if (is_division && py == 0) continue;
      mpfr_set_d(mx.get(), px, MPFR_RNDN);
      mpfr_set_d(my.get(), py, MPFR_RNDN);
      const int t = mop(v.get(), mx.get(), my.get(), MPFR_RNDN);
      checker.check(r, v.get(), t, describe(x, y, px, py));
    }
  }
}

Interval add_op(const Interval& x, const Interval& y) {
  return x + y;
}
Interval sub_op(const Interval& x, const Interval& y) {
  return x - y;
}
Interval mul_op(const Interval& x, const Interval& y) {
  return x * y;
}
Interval div_op(const Interval& x, const Interval& y) {
  return x / y;
}

constexpr int kBinaryPairs = 40'000;

TEST(IntervalMpfr, AdditionEnclosesExactSums) {
  binary_property("add", 11, kBinaryPairs * scale(), add_op, mpfr_add, false);
}

TEST(IntervalMpfr, SubtractionEnclosesExactDifferences) {
  binary_property("sub", 12, kBinaryPairs * scale(), sub_op, mpfr_sub, false);
}

TEST(IntervalMpfr, MultiplicationEnclosesExactProducts) {
  binary_property("mul", 13, kBinaryPairs * scale(), mul_op, mpfr_mul, false);
}

TEST(IntervalMpfr, DivisionEnclosesExactQuotients) {
  binary_property("div", 14, kBinaryPairs * scale(), div_op, mpfr_div, true);
}

// ---- Unary operations ---------------------------------------------------------------------------

// mop computes the exact operation at a point (returns the ternary value); max_ulps bounds the
// enclosure's width for point operands (negative: not checked).
void unary_property(const char* name, std::uint64_t seed, int count,
                    const std::function<Interval(Draw&)>& operand,
                    const std::function<Interval(const Interval&)>& op,
                    const std::function<int(mpfr_ptr, mpfr_srcptr)>& mop, int max_ulps,
                    const std::function<bool(double)>& in_domain = nullptr,
                    double tight_limit = kInf) {
  Checker checker(name);
  Draw draw(seed);
  Mp mx, v;
  for (int n = 0; n < count; ++n) {
    const Interval x = operand(draw);
    const Interval r = op(x);
    if (max_ulps >= 0 && x.is_point() && r.is_bounded() && (!in_domain || in_domain(x.lo())) &&
        std::fabs(x.lo()) <= tight_limit) {
      EXPECT_LE(ulps_between(r.lo(), r.hi()), max_ulps) << name << " " << x << " -> " << r;
    }
    for (int k = 0; k < 6; ++k) {
      const double px = draw.point_in(x, k);
      if (in_domain && !in_domain(px)) continue;
      mpfr_set_d(mx.get(), px, MPFR_RNDN);
      const int t = mop(v.get(), mx.get());
      checker.check(r, v.get(), t, describe(x, px));
    }
  }
}

constexpr int kUnaryCount = 12'000;

Interval general_operand(Draw& d) {
  return d.operand();
}

TEST(IntervalMpfr, SqrEnclosesExactSquares) {
  unary_property(
      "sqr", 21, kUnaryCount * scale(), general_operand, [](const Interval& x) { return sqr(x); },
      [](mpfr_ptr v, mpfr_srcptr x) { return mpfr_sqr(v, x, MPFR_RNDN); }, 1);
}

TEST(IntervalMpfr, SqrtEnclosesExactRoots) {
  unary_property(
      "sqrt", 22, kUnaryCount * scale(), general_operand, [](const Interval& x) { return sqrt(x); },
      [](mpfr_ptr v, mpfr_srcptr x) { return mpfr_sqrt(v, x, MPFR_RNDN); }, 1,
      [](double p) { return p >= 0; });
}

TEST(IntervalMpfr, AbsEnclosesExactAbsoluteValues) {
  unary_property(
      "abs", 23, kUnaryCount * scale(), general_operand, [](const Interval& x) { return abs(x); },
      [](mpfr_ptr v, mpfr_srcptr x) { return mpfr_abs(v, x, MPFR_RNDN); }, 0);
}

TEST(IntervalMpfr, PowEnclosesExactPowers) {
  for (int n = 2; n <= 5; ++n) {
    unary_property(("pow" + std::to_string(n)).c_str(), 30 + n, kUnaryCount * scale(),
                   general_operand, [n](const Interval& x) { return pow(x, n); },
                   [n](mpfr_ptr v, mpfr_srcptr x) {
                     return mpfr_pow_ui(v, x, static_cast<unsigned long>(n), MPFR_RNDN);
                   },
                   2 * n);
  }
}

// sin/cos arguments: wide (up to 1e6), narrow around multiples of pi/2, moderate, large (up to
// 2^40, where enclosures stay tight), beyond (where the result is [-1, 1]), tiny, points.
Interval trig_operand(Draw& d) {
  const int shape = d.pick(100);
  if (shape < 15) {  // wide, up to 1e6
    const double c = d.uniform(-1e6, 1e6);
    const double w = d.magnitude(-3, 6.3);
    return Interval(c - w / 2, c + w / 2);
  }
  if (shape < 45) {  // narrow (or a point) around k pi / 2
    const double k = std::round(d.coin(0.5) ? d.uniform(-8, 8) : d.uniform(-1e6, 1e6));
    const double c = k * (3.14159265358979323846 / 2);
    const double s = d.sign();
    const double lo = c + s * d.magnitude(-17, -4) * std::max(1.0, std::fabs(c));
    if (d.coin(0.2)) return Interval(lo);
    return d.narrow(lo);
  }
  if (shape < 65) {
    const double a = d.uniform(-10, 10);
    return Interval(a, 0) | Interval(d.uniform(-10, 10));
  }
  const double s = d.sign();
  if (shape < 75) return d.narrow(s * d.magnitude(3, 12.04));    // up to 2^40
  if (shape < 80) return d.narrow(s * d.magnitude(12.05, 300));  // beyond: [-1, 1]
  if (shape < 85) return d.narrow(s * d.magnitude(-320, -5));
  if (shape < 95) return Interval(s * d.magnitude(-3, 6));
  return d.operand();
}

constexpr int kTrigCount = 20'000;
// Up to here sin and cos of a point are a few ulps wide; beyond it they are [-1, 1].
constexpr double kTrigTightLimit = 0x1p40;

TEST(IntervalMpfr, SinEnclosesExactSines) {
  unary_property(
      "sin", 41, kTrigCount * scale(), trig_operand, [](const Interval& x) { return sin(x); },
      [](mpfr_ptr v, mpfr_srcptr x) { return mpfr_sin(v, x, MPFR_RNDN); }, 8, nullptr,
      kTrigTightLimit);
}

TEST(IntervalMpfr, CosEnclosesExactCosines) {
  unary_property(
      "cos", 42, kTrigCount * scale(), trig_operand, [](const Interval& x) { return cos(x); },
      [](mpfr_ptr v, mpfr_srcptr x) { return mpfr_cos(v, x, MPFR_RNDN); }, 8, nullptr,
      kTrigTightLimit);
}

TEST(IntervalMpfr, PiEnclosureContainsPi) {
  Checker checker("pi");
  Mp v;
  const int t = mpfr_const_pi(v.get(), MPFR_RNDN);
  checker.check(Interval::pi(), v.get(), t, [] { return std::string("pi:"); });
  EXPECT_EQ(ulps_between(Interval::pi().lo(), Interval::pi().hi()), 1);
}

// ---- The model's row expression -----------------------------------------------------------------

// s*s*a + 2*s*c*b*d with s = sin(q), c = cos(q): the oracle is evaluated at 200 bits in
// round-to-nearest, about ten roundings, so it is within 2^-190 (|s*s*a| + |2*s*c*b*d|) of the
// exact value; that slack is checked to lie in the enclosure too.
TEST(IntervalMpfr, ModelRowExpressionEnclosesExactValues) {
  Checker checker("row s*s*a + 2*s*c*b*d");
  Draw draw(51);
  Mp mq, ma, mb, md, s, c, t1, t2, v, slack;
  const int count = 20'000 * scale();
  auto parameter = [&draw] {
    if (draw.coin(0.7)) {
      const double s = draw.sign();
      const double v = s * draw.magnitude(-4, 1);
      if (draw.coin(0.3)) return Interval(v);
      const Interval near_v = draw.narrow(v);
      return near_v | Interval(v * draw.uniform(0.5, 2));
    }
    return draw.operand();
  };
  for (int n = 0; n < count; ++n) {
    const Interval q = draw.coin(0.8) ? (draw.coin(0.5) ? Interval(draw.uniform(-7, 7))
                                                        : draw.narrow(draw.uniform(-7, 7)))
                                      : trig_operand(draw);
    const Interval a = parameter(), b = parameter(), d = parameter();
    const Interval si = sin(q), co = cos(q);
    const Interval r = si * si * a + Interval(2.0) * si * co * b * d;
    for (int k = 0; k < 8; ++k) {
      const int w = k < 2 ? k : 2;
      const double pq = draw.point_in(q, w), pa = draw.point_in(a, w), pb = draw.point_in(b, w),
                   pd = draw.point_in(d, w);
      mpfr_set_d(mq.get(), pq, MPFR_RNDN);
      mpfr_set_d(ma.get(), pa, MPFR_RNDN);
      mpfr_set_d(mb.get(), pb, MPFR_RNDN);
      mpfr_set_d(md.get(), pd, MPFR_RNDN);
      mpfr_sin(s.get(), mq.get(), MPFR_RNDN);
      mpfr_cos(c.get(), mq.get(), MPFR_RNDN);
      mpfr_sqr(t1.get(), s.get(), MPFR_RNDN);
      mpfr_mul(t1.get(), t1.get(), ma.get(), MPFR_RNDN);
      mpfr_mul(t2.get(), s.get(), c.get(), MPFR_RNDN);
      mpfr_mul_2ui(t2.get(), t2.get(), 1, MPFR_RNDN);
      mpfr_mul(t2.get(), t2.get(), mb.get(), MPFR_RNDN);
      mpfr_mul(t2.get(), t2.get(), md.get(), MPFR_RNDN);
      mpfr_add(v.get(), t1.get(), t2.get(), MPFR_RNDN);
      mpfr_abs(slack.get(), t1.get(), MPFR_RNDU);
      mpfr_abs(s.get(), t2.get(), MPFR_RNDU);
      mpfr_add(slack.get(), slack.get(), s.get(), MPFR_RNDU);
      mpfr_mul_2si(slack.get(), slack.get(), -190, MPFR_RNDU);
      checker.check_slack(r, v.get(), slack.get(), [=] {
        std::ostringstream o;
        o << "q = " << q << ", a = " << a << ", b = " << b << ", d = " << d << " at (" << d_str(pq)
          << ", " << d_str(pa) << ", " << d_str(pb) << ", " << d_str(pd) << "):";
        return o.str();
      });
    }
  }
}

// ---- Backward operators -------------------------------------------------------------------------

// An interval containing p: p itself, p widened on either side, or its hull with a random operand.
Interval around(Draw& d, double p) {
  switch (d.pick(4)) {
    case 0:
      return Interval(p);
    case 1:
      return Interval(p) | d.operand();
    case 2: {
      const double w = std::max(std::fabs(p), 1.0) * d.magnitude(-12, 1);
      const double below = d.uniform(0, 1) * w;
      return Interval(p - below, p + d.uniform(0, 1) * w) | Interval(p);
    }
    default:
      return d.narrow(p) | Interval(std::nextafter(p, -kInf));
  }
}

// y enclosing the exact value v: its two roundings to double, sometimes widened.
Interval enclose(Draw& d, mpfr_srcptr v) {
  const Interval y(mpfr_get_d(v, MPFR_RNDD), mpfr_get_d(v, MPFR_RNDU));
  if (d.coin(0.5)) return y;
  return y | Interval(d.coin(0.5) ? y.lo() - d.magnitude(-10, 2) : y.hi() + d.magnitude(-10, 2));
}

using Backward2 = void (*)(const Interval&, Interval&, Interval&);

void backward_binary_property(const char* name, std::uint64_t seed, int count, Backward2 bwd,
                              MpfrBinary mop, bool is_division) {
  Checker checker(name);
  Draw draw(seed);
  Mp mx, my, v;
  for (int n = 0; n < count; ++n) {
    const double p1 = draw.coin(0.7) ? draw.scalar(draw.coin(0.5) ? 0 : 5) : draw.scalar();
    const double p2 = draw.coin(0.7) ? draw.scalar(draw.coin(0.5) ? 0 : 5) : draw.scalar();
    if (is_division && p2 == 0) continue;
    mpfr_set_d(mx.get(), p1, MPFR_RNDN);
    mpfr_set_d(my.get(), p2, MPFR_RNDN);
    mop(v.get(), mx.get(), my.get(), MPFR_RNDZ);  // 200 bits; y's bounds below are directed
    // v may be inexact at 200 bits: widen y by the rounding.
    Interval y = enclose(draw, v.get());
    y = Interval(std::nextafter(y.lo(), -kInf), std::nextafter(y.hi(), kInf));
    const Interval x1 = around(draw, p1), x2 = around(draw, p2);
    Interval c1 = x1, c2 = x2;
    bwd(y, c1, c2);
    auto what = [=] {
      std::ostringstream o;
      o << "y = " << y << ", x1 = " << x1 << ", x2 = " << x2 << " -> " << c1 << ", " << c2
        << " for (" << d_str(p1) << ", " << d_str(p2) << "):";
      return o.str();
    };
    checker.check_kept(c1, p1, what);
    checker.check_kept(c2, p2, what);
  }
}

constexpr int kBackwardCount = 25'000;

TEST(IntervalMpfr, BackwardAddKeepsConsistentPoints) {
  backward_binary_property("bwd_add", 61, kBackwardCount * scale(), bwd_add, mpfr_add, false);
}
TEST(IntervalMpfr, BackwardSubKeepsConsistentPoints) {
  backward_binary_property("bwd_sub", 62, kBackwardCount * scale(), bwd_sub, mpfr_sub, false);
}
TEST(IntervalMpfr, BackwardMulKeepsConsistentPoints) {
  backward_binary_property("bwd_mul", 63, kBackwardCount * scale(), bwd_mul, mpfr_mul, false);
}
TEST(IntervalMpfr, BackwardDivKeepsConsistentPoints) {
  backward_binary_property("bwd_div", 64, kBackwardCount * scale(), bwd_div, mpfr_div, true);
}

using Backward1 = void (*)(const Interval&, Interval&);

void backward_unary_property(const char* name, std::uint64_t seed, int count, Backward1 bwd,
                             const std::function<double(Draw&)>& point,
                             const std::function<void(mpfr_ptr, mpfr_srcptr)>& mop) {
  Checker checker(name);
  Draw draw(seed);
  Mp mx, v;
  for (int n = 0; n < count; ++n) {
    const double p = point(draw);
    mpfr_set_d(mx.get(), p, MPFR_RNDN);
    mop(v.get(), mx.get());
    Interval y = enclose(draw, v.get());
    y = Interval(std::nextafter(y.lo(), -kInf), std::nextafter(y.hi(), kInf));
    const Interval x = around(draw, p);
    Interval c = x;
    bwd(y, c);
    checker.check_kept(c, p, [=] {
      std::ostringstream o;
      o << "y = " << y << ", x = " << x << " -> " << c << ":";
      return o.str();
    });
  }
}

double trig_point(Draw& d) {
  const Interval x = trig_operand(d);
  return d.point_in(x, d.pick(3));
}

TEST(IntervalMpfr, BackwardUnaryOperatorsKeepConsistentPoints) {
  const int count = kBackwardCount * scale();
  backward_unary_property(
      "bwd_neg", 71, count, bwd_neg, [](Draw& d) { return d.scalar(); },
      [](mpfr_ptr v, mpfr_srcptr x) { mpfr_neg(v, x, MPFR_RNDN); });
  backward_unary_property(
      "bwd_sqr", 72, count, bwd_sqr, [](Draw& d) { return d.scalar(); },
      [](mpfr_ptr v, mpfr_srcptr x) { mpfr_sqr(v, x, MPFR_RNDN); });
  backward_unary_property("bwd_sin", 73, count, bwd_sin, trig_point,
                          [](mpfr_ptr v, mpfr_srcptr x) { mpfr_sin(v, x, MPFR_RNDN); });
  backward_unary_property("bwd_cos", 74, count, bwd_cos, trig_point,
                          [](mpfr_ptr v, mpfr_srcptr x) { mpfr_cos(v, x, MPFR_RNDN); });
}

// The bound the trigonometric enclosures rest on: glibc's sin, cos, asin and acos within
// detail::kLibmErrorUlps steps of the exact value, on the architecture the test runs on (libm is
// where amd64 and arm64 differ: docs/arm64.md). Points as the operations meet them: trig_point up
// to 2^40 (beyond it sin and cos give [-1, 1] without libm), and all of [-1, 1] for asin and acos,
// crowded near +-1 and 0. Reports the largest error, in steps and in ulps of the computed value.
void libm_error_property(const char* name, std::uint64_t seed, int count,
                         const std::function<double(Draw&)>& point, double (*libm)(double),
                         int (*mop)(mpfr_ptr, mpfr_srcptr, mpfr_rnd_t)) {
  Checker checker(name);
  Draw draw(seed);
  Mp mx, exact, diff;
  std::int64_t worst_steps = 0;
  double worst_ulps = 0;
  for (int n = 0; n < count; ++n) {
    const double x = point(draw);
    if (!(std::fabs(x) <= kTrigTightLimit)) continue;
    const double v = libm(x);
    mpfr_set_d(mx.get(), x, MPFR_RNDN);
    const int ternary = mop(exact.get(), mx.get(), MPFR_RNDN);
    // Steps of v's neighbours out to the exact value: the widening that encloses it.
    const bool above = mpfr_cmp_d(exact.get(), v) > 0;
    const double outward = mpfr_get_d(exact.get(), above ? MPFR_RNDU : MPFR_RNDD);
    const std::int64_t steps = above ? ulps_between(v, outward) : ulps_between(outward, v);
    const double ulp = std::nextafter(std::fabs(v), kInf) - std::fabs(v);
    mpfr_sub_d(diff.get(), exact.get(), v, MPFR_RNDN);
    worst_ulps = std::max(worst_ulps, std::fabs(mpfr_get_d(diff.get(), MPFR_RNDN)) / ulp);
    worst_steps = std::max(worst_steps, steps);
    Interval r(v);
    for (int k = 0; k < detail::kLibmErrorUlps; ++k)
      r = Interval(std::nextafter(r.lo(), -kInf), std::nextafter(r.hi(), kInf));
    checker.check(r, exact.get(), ternary, [&] {
      std::ostringstream o;
      o.precision(17);
      o << name << "(" << x << ") = " << v << ", " << steps << " steps from";
      return o.str();
    });
  }
  std::printf("[ measured ] %s: largest error %lld steps, %.3f ulp\n", name,
              static_cast<long long>(worst_steps), worst_ulps);
}

double unit_point(Draw& d) {
  const int shape = d.pick(4);
  const double s = d.sign();
  if (shape == 0) return s * (1 - d.magnitude(-16, -1));  // near +-1
  if (shape == 1) return s * d.magnitude(-300, -1);       // near 0
  return d.uniform(-1, 1);
}

TEST(IntervalMpfr, LibmIsWithinTheErrorBoundTheEnclosuresWiden) {
  const int count = kTrigCount * scale();
  libm_error_property("libm sin", 81, count, trig_point, static_cast<double (*)(double)>(std::sin),
                      mpfr_sin);
  libm_error_property("libm cos", 82, count, trig_point, static_cast<double (*)(double)>(std::cos),
                      mpfr_cos);
  libm_error_property("libm asin", 83, count, unit_point,
                      static_cast<double (*)(double)>(std::asin), mpfr_asin);
  libm_error_property("libm acos", 84, count, unit_point,
                      static_cast<double (*)(double)>(std::acos), mpfr_acos);
}

}  // namespace
}  // namespace furuta::interval::interval_mpfr_test
