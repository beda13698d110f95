// The SIVIA paver on a set known exactly, the ring 1 <= x1^2 + x2^2 <= 4: inner boxes must lie in
// it, outer boxes outside it, boundary boxes must be small and straddle its edge, and the three
// lists together must tile the prior. Then the paver's contract: same paving for every thread
// count, contraction, truncation, cancellation, progress, validation and exceptions.
#include "furuta/interval/sivia.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace furuta::interval::sivia_test {
namespace {

const Interval kRing(1.0, 4.0);
const double kPi = 3.14159265358979323846;

bool in_ring(double x1, double x2) {
  const double r = x1 * x1 + x2 * x2;
  return 1.0 <= r && r <= 4.0;
}

Box ring_prior() {
  return Box{Interval(-3.0, 3.0), Interval(-3.0, 3.0)};
}

// Plain test: interval evaluation of x1^2 + x2^2 against [1, 4].
BoxDecision ring_test(Box& b) {
  const Interval y = sqr(b[0]) + sqr(b[1]);
  if (y.is_subset(kRing)) {
    return {BoxVerdict::inner};
  }
  if (y.is_disjoint(kRing)) {
    return {BoxVerdict::outer};
  }
  return {BoxVerdict::undecided};
}

// Forward-backward contraction of x1^2 + x2^2 in [1, 4], then the same decision on what is left.
// An inconsistent box is returned emptied with no verdict: the paver must call it outer.
BoxDecision contracting_ring_test(Box& b) {
  Interval a = sqr(b[0]);
  Interval c = sqr(b[1]);
  const Interval y = a + c;
  if (y.is_subset(kRing)) {
    return {BoxVerdict::inner};
  }
  const Interval yc = y & kRing;
  bwd_add(yc, a, c);
  bwd_sqr(a, b[0]);
  bwd_sqr(c, b[1]);
  if (yc.is_empty() || b.is_empty()) {
    b.set_empty();
    return {BoxVerdict::undecided};
  }
  if ((sqr(b[0]) + sqr(b[1])).is_subset(kRing)) {
    return {BoxVerdict::inner};
  }
  return {BoxVerdict::undecided};
}

bool in_any(const std::vector<Box>& boxes, const std::vector<double>& p) {
  for (const Box& b : boxes) {
    if (b.contains(p)) {
      return true;
    }
  }
  return false;
}

bool in_any(const std::vector<Box>& a, const std::vector<Box>& b, const std::vector<double>& p) {
  return in_any(a, p) || in_any(b, p);
}

double uniform_in(const Interval& x, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double v = x.lo() + u(rng) * (x.hi() - x.lo());
  return v > x.hi() ? x.hi() : v;
}

// The four corners and `random` uniform points of a 2-D box.
std::vector<std::vector<double>> samples(const Box& b, int random, std::mt19937_64& rng) {
  std::vector<std::vector<double>> p = {{b[0].lo(), b[1].lo()},
                                        {b[0].lo(), b[1].hi()},
                                        {b[0].hi(), b[1].lo()},
                                        {b[0].hi(), b[1].hi()}};
  for (int k = 0; k < random; ++k) {
    p.push_back({uniform_in(b[0], rng), uniform_in(b[1], rng)});
  }
  return p;
}

// The exact range of x1^2 + x2^2 over a box (exact in doubles for the dyadic boxes of the plain
// paving; a slight inward error elsewhere does not matter for the checks below).
std::pair<double, double> ring_range(const Box& b) {
  return {b[0].mig() * b[0].mig() + b[1].mig() * b[1].mig(),
          b[0].mag() * b[0].mag() + b[1].mag() * b[1].mag()};
}

double relative_width(const Box& b, const Box& prior) {
  double w = 0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    w = std::max(w, b[i].width() / prior[i].width());
  }
  return w;
}

SiviaOptions ring_options(int threads = 0) {
  SiviaOptions o;
  o.epsilon = 0.01;
  o.threads = threads;
  return o;
}

TEST(Sivia, RingInnerOuterBoundaryAreSoundAndTileThePrior) {
  const Box prior = ring_prior();
  const SubPaving p = sivia(prior, ring_test, ring_options());
  ASSERT_FALSE(p.truncated);
  ASSERT_FALSE(p.inner.empty());
  ASSERT_FALSE(p.boundary.empty());
  ASSERT_FALSE(p.outer.empty());
  EXPECT_EQ(p.outer_count, p.outer.size());
  EXPECT_EQ(p.boxes_tested, p.inner.size() + p.boundary.size() + p.outer.size() + p.bisections);
  EXPECT_EQ(p.prior, prior);

  std::mt19937_64 rng(1);
  for (const Box& b : p.inner) {
    for (const auto& x : samples(b, 4, rng)) {
      ASSERT_TRUE(in_ring(x[0], x[1])) << "inner box " << b;
    }
  }
  for (const Box& b : p.outer) {
    for (const auto& x : samples(b, 4, rng)) {
      ASSERT_FALSE(in_ring(x[0], x[1])) << "outer box " << b;
    }
  }
  for (const Box& b : p.boundary) {
    EXPECT_LE(relative_width(b, prior), 0.01) << b;
    // Neither inside nor outside: the box really straddles a circle.
    const auto [lo, hi] = ring_range(b);
    EXPECT_FALSE(1.0 <= lo && hi <= 4.0) << b;
    EXPECT_FALSE(hi < 1.0 || lo > 4.0) << b;
  }

  // The three lists tile the prior: total volume, and every random point falls in some box.
  double outer_volume = 0;
  for (const Box& b : p.outer) {
    outer_volume += b[0].width() * b[1].width();
  }
  EXPECT_NEAR(p.inner_volume() + p.boundary_volume() + outer_volume, 36.0, 1e-9);
  for (int k = 0; k < 1000; ++k) {
    const std::vector<double> x = {uniform_in(prior[0], rng), uniform_in(prior[1], rng)};
    ASSERT_TRUE(in_any(p.inner, p.boundary, x) || in_any(p.outer, x));
  }

  // The ring's area 3 pi lies between the inner and the outer approximation.
  EXPECT_LT(p.inner_volume(), 3 * kPi);
  EXPECT_GT(p.inner_volume() + p.boundary_volume(), 3 * kPi);

  // Hulls: the outer one encloses [-2, 2]^2 within one boundary box; the inner one lies inside.
  const Box oh = p.outer_hull();
  const Box ih = p.inner_hull();
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_TRUE(Interval(-2, 2).is_subset(oh[i])) << oh;
    EXPECT_TRUE(oh[i].is_subset(Interval(-2.1, 2.1))) << oh;
    EXPECT_TRUE(ih[i].is_subset(Interval(-2, 2))) << ih;
    EXPECT_GT(ih[i].width(), 3.8) << ih;
  }
  EXPECT_GE(p.seconds, 0.0);
  std::printf(
      "[ measured ] ring eps 0.01: %zu tested, %zu inner, %zu boundary, %zu outer, inner "
      "%.4f < 3pi %.4f < %.4f, %.4f s\n",
      p.boxes_tested, p.inner.size(), p.boundary.size(), p.outer.size(), p.inner_volume(), 3 * kPi,
      p.inner_volume() + p.boundary_volume(), p.seconds);
}

// A probe carves a proven sub-box out of the boxes epsilon stops: at a coarse epsilon the ring's
// boundary boxes gain inner parts, and inner, boundary and outer still tile the prior.
TEST(Sivia, InnerProbeCarvesInnerPartsOutOfStoppedBoxes) {
  const Box prior = ring_prior();
  SiviaOptions o = ring_options();
  o.epsilon = 0.2;
  const SubPaving plain = sivia(prior, ring_test, o);
  std::atomic<int> probes{0};
  o.inner_probe = [&](const Box& b) -> std::optional<Box> {
    ++probes;
    Box sub = b;
    for (std::size_t i = 0; i < 2; ++i) {
      const double c = b[i].mid(), h = b[i].width() / 4;
      sub[i] = Interval(c - h, c + h);
    }
    Box tested = sub;
    if (ring_test(tested).verdict == BoxVerdict::inner) return sub;
    return std::nullopt;
  };
  const SubPaving p = sivia(prior, ring_test, o);
  EXPECT_EQ(static_cast<std::size_t>(probes.load()), plain.boundary.size());
  ASSERT_GT(p.probed_inner, 0u);
  EXPECT_EQ(p.inner.size(), plain.inner.size() + p.probed_inner);
  EXPECT_GT(p.inner_volume(), plain.inner_volume());
  EXPECT_LT(p.boundary_volume(), plain.boundary_volume());
  // The probe moves area from boundary to inner and nowhere else.
  EXPECT_NEAR(p.inner_volume() + p.boundary_volume(),
              plain.inner_volume() + plain.boundary_volume(), 1e-9);
  EXPECT_EQ(p.outer.size(), plain.outer.size());
  std::mt19937_64 rng(5);
  for (const Box& b : p.inner) {
    for (const auto& x : samples(b, 4, rng)) {
      ASSERT_TRUE(in_ring(x[0], x[1])) << "inner box " << b;
    }
  }
  EXPECT_LT(p.inner_volume(), 3 * kPi);
  EXPECT_GT(p.inner_volume() + p.boundary_volume(), 3 * kPi);
  // A probe that answers a box outside the stopped box is ignored (the paving stays plain).
  o.inner_probe = [](const Box& b) -> std::optional<Box> {
    Box away = b;
    away[0] = Interval(b[0].hi() + 1, b[0].hi() + 2);
    return away;
  };
  const SubPaving ignored = sivia(prior, ring_test, o);
  EXPECT_EQ(ignored.probed_inner, 0u);
  EXPECT_EQ(ignored.inner.size(), plain.inner.size());
}

TEST(Sivia, PavingIsIdenticalForEveryThreadCount) {
  for (const BoxTest& test : {BoxTest(ring_test), BoxTest(contracting_ring_test)}) {
    SiviaOptions o = ring_options(1);
    o.epsilon = 0.004;
    const SubPaving ref = sivia(ring_prior(), test, o);
    ASSERT_GT(ref.boxes_tested, 1000u);
    for (int threads : {2, 4, 0}) {
      o.threads = threads;
      const SubPaving p = sivia(ring_prior(), test, o);
      EXPECT_EQ(p.inner, ref.inner) << threads << " threads";
      EXPECT_EQ(p.boundary, ref.boundary) << threads << " threads";
      EXPECT_EQ(p.outer, ref.outer) << threads << " threads";
      EXPECT_EQ(p.boxes_tested, ref.boxes_tested);
      EXPECT_EQ(p.bisections, ref.bisections);
      EXPECT_EQ(p.outer_count, ref.outer_count);
    }
  }
}

TEST(Sivia, ContractingTestGivesTheSameSetWithFewerTests) {
  const Box prior = ring_prior();
  const SubPaving plain = sivia(prior, ring_test, ring_options());
  const SubPaving contracted = sivia(prior, contracting_ring_test, ring_options());
  ASSERT_FALSE(plain.truncated);
  ASSERT_FALSE(contracted.truncated);

  std::mt19937_64 rng(2);
  // Points of the set found in either outer approximation are in the other one too.
  auto check = [&](const SubPaving& from, const SubPaving& to, const char* what) {
    for (const std::vector<Box>* list : {&from.inner, &from.boundary}) {
      for (const Box& b : *list) {
        for (const auto& x : samples(b, 2, rng)) {
          if (in_ring(x[0], x[1])) {
            ASSERT_TRUE(in_any(to.inner, to.boundary, x)) << what << " " << x[0] << " " << x[1];
          }
        }
      }
    }
  };
  check(plain, contracted, "plain->contracted");
  check(contracted, plain, "contracted->plain");
  // And every point of the set drawn from the prior is in both.
  for (int k = 0; k < 2000; ++k) {
    const std::vector<double> x = {uniform_in(prior[0], rng), uniform_in(prior[1], rng)};
    if (in_ring(x[0], x[1])) {
      ASSERT_TRUE(in_any(plain.inner, plain.boundary, x));
      ASSERT_TRUE(in_any(contracted.inner, contracted.boundary, x));
    }
  }
  // Inner boxes stay inside the set; boundary boxes are small and touch it.
  for (const Box& b : contracted.inner) {
    for (const auto& x : samples(b, 2, rng)) {
      ASSERT_TRUE(in_ring(x[0], x[1])) << b;
    }
  }
  for (const Box& b : contracted.boundary) {
    EXPECT_LE(relative_width(b, prior), 0.01) << b;
    const auto [lo, hi] = ring_range(b);
    EXPECT_FALSE(hi < 1.0 - 1e-12 || lo > 4.0 + 1e-12) << b;
  }
  const double v_plain = plain.inner_volume() + plain.boundary_volume();
  const double v_contracted = contracted.inner_volume() + contracted.boundary_volume();
  EXPECT_GT(v_contracted, 3 * kPi);
  EXPECT_LE(v_contracted, v_plain);
  // Contracted-away slices are not outer boxes (they are in `contractions`): outer holds whole
  // tested boxes only.
  EXPECT_EQ(contracted.outer.size(), contracted.outer_count);
  EXPECT_LT(contracted.boxes_tested, plain.boxes_tested);
  std::printf(
      "[ measured ] ring eps 0.01: plain %zu tests (outer approx. %.4f), contracting %zu "
      "tests (outer approx. %.4f), 3pi = %.4f\n",
      plain.boxes_tested, v_plain, contracted.boxes_tested, v_contracted, 3 * kPi);
}

// What a contracting test cut off a box it did not call outer is kept as the box before and after,
// so that a reader can check it: no point of before \ after is in the set, and with it the paving
// accounts for every point of the prior.
TEST(Sivia, ContractionsAreKeptSoWhatTheyRemovedCanBeChecked) {
  const Box prior = ring_prior();
  const SubPaving p = sivia(prior, contracting_ring_test, ring_options());
  ASSERT_GT(p.contraction_count, 0u);
  ASSERT_EQ(p.contractions.size(), p.contraction_count);
  std::mt19937_64 rng(21);
  std::size_t removed_points = 0;
  for (const Contraction& c : p.contractions) {
    ASSERT_TRUE(c.after.is_subset(c.before)) << c.before << " -> " << c.after;
    ASSERT_NE(c.after, c.before);
    for (const auto& x : samples(c.before, 20, rng)) {
      if (c.after.contains(x)) continue;
      ++removed_points;
      // Proven outside; a point within rounding of the ring's edge is not a counterexample.
      const double r = x[0] * x[0] + x[1] * x[1];
      ASSERT_TRUE(r < 1.0 + 1e-12 || r > 4.0 - 1e-12)
          << "(" << x[0] << ", " << x[1] << ") removed from " << c.before << " -> " << c.after;
    }
  }
  EXPECT_GT(removed_points, 0u);
  // Every point of the prior is in an inner, boundary or outer box or in a removed part.
  const auto removed = [&](const std::vector<double>& x) {
    for (const Contraction& c : p.contractions) {
      if (c.before.contains(x) && !c.after.contains(x)) return true;
    }
    return false;
  };
  for (int k = 0; k < 2000; ++k) {
    const std::vector<double> x = {uniform_in(prior[0], rng), uniform_in(prior[1], rng)};
    ASSERT_TRUE(in_any(p.inner, p.boundary, x) || in_any(p.outer, x) || removed(x))
        << x[0] << ", " << x[1];
  }
  // A test that never contracts leaves no record.
  const SubPaving plain = sivia(prior, ring_test, ring_options());
  EXPECT_EQ(plain.contraction_count, 0u);
  EXPECT_TRUE(plain.contractions.empty());
}

TEST(Sivia, KeptContractionsStopAtTheCapInTheSameOrderForEveryThreadCount) {
  SiviaOptions o = ring_options(1);
  const SubPaving all = sivia(ring_prior(), contracting_ring_test, o);
  ASSERT_GT(all.contraction_count, 10u);
  for (int threads : {1, 2, 0}) {
    o.threads = threads;
    o.max_kept_contractions = 10;
    const SubPaving capped = sivia(ring_prior(), contracting_ring_test, o);
    EXPECT_EQ(capped.contraction_count, all.contraction_count) << threads << " threads";
    ASSERT_EQ(capped.contractions.size(), 10u);
    for (std::size_t i = 0; i < 10; ++i) {
      EXPECT_EQ(capped.contractions[i].before, all.contractions[i].before) << i;
      EXPECT_EQ(capped.contractions[i].after, all.contractions[i].after) << i;
    }
    EXPECT_EQ(capped.boundary, all.boundary);
    o.max_kept_contractions = 0;
    const SubPaving none = sivia(ring_prior(), contracting_ring_test, o);
    EXPECT_TRUE(none.contractions.empty());
    EXPECT_EQ(none.contraction_count, all.contraction_count);
  }
}

TEST(Sivia, EmptySetHasNoInnerNorBoundary) {
  const Box prior = ring_prior();
  auto check = [&](const SubPaving& p) {
    EXPECT_TRUE(p.inner.empty());
    EXPECT_TRUE(p.boundary.empty());
    EXPECT_TRUE(p.empty_inner_and_boundary());
    EXPECT_EQ(p.boxes_tested, 1u);
    EXPECT_EQ(p.outer_count, 1u);
    EXPECT_FALSE(p.truncated);
    EXPECT_EQ(p.inner_volume(), 0.0);
    EXPECT_EQ(p.boundary_volume(), 0.0);
    const Box h = p.outer_hull();
    ASSERT_EQ(h.size(), 2u);
    EXPECT_TRUE(h[0].is_empty());
    EXPECT_TRUE(h[1].is_empty());
    EXPECT_TRUE(p.inner_hull()[0].is_empty());
  };
  // Said outer.
  const SubPaving a = sivia(prior, [](Box&) { return BoxDecision{BoxVerdict::outer}; });
  check(a);
  EXPECT_EQ(a.outer, std::vector<Box>{prior});
  // Contracted to nothing: outer too, and the kept outer box is the tested one, not the empty one.
  const SubPaving b = sivia(prior, [](Box& x) {
    x.set_empty();
    return BoxDecision{};
  });
  check(b);
  EXPECT_EQ(b.outer, std::vector<Box>{prior});
  // Not kept, still counted.
  SiviaOptions o;
  o.keep_outer = false;
  const SubPaving c = sivia(
      prior, [](Box&) { return BoxDecision{BoxVerdict::outer}; }, o);
  check(c);
  EXPECT_TRUE(c.outer.empty());
}

TEST(Sivia, BisectsTheWidestComponentRelativeToScale) {
  auto undecided = [](Box&) { return BoxDecision{}; };
  // Relative widths: [0,1] x [0,100] at epsilon 0.5 needs one cut in each direction, not seven
  // cuts of the absolutely widest component first.
  SiviaOptions o;
  o.epsilon = 0.5;
  const SubPaving p = sivia(Box{Interval(0, 1), Interval(0, 100)}, undecided, o);
  ASSERT_EQ(p.boundary.size(), 4u);
  EXPECT_EQ(p.boxes_tested, 7u);
  EXPECT_EQ(p.bisections, 3u);
  for (const Box& b : p.boundary) {
    EXPECT_EQ(b[0].width(), 0.5);
    EXPECT_EQ(b[1].width(), 50.0);
  }
  // A point component is never bisected; the others come out in generation order, lower first.
  o.epsilon = 0.25;
  const SubPaving q = sivia(Box{Interval(0, 1), Interval(2)}, undecided, o);
  const std::vector<Box> expected = {
      Box{Interval(0, 0.25), Interval(2)}, Box{Interval(0.25, 0.5), Interval(2)},
      Box{Interval(0.5, 0.75), Interval(2)}, Box{Interval(0.75, 1), Interval(2)}};
  EXPECT_EQ(q.boundary, expected);
  // Scale 0: that component is never bisected; an explicit scale replaces the prior's widths.
  o.epsilon = 0.01;
  o.scale = {6.0, 0.0};
  const SubPaving r = sivia(ring_prior(), ring_test, o);
  for (const std::vector<Box>* list : {&r.inner, &r.boundary, &r.outer}) {
    for (const Box& b : *list) {
      EXPECT_EQ(b[1], Interval(-3, 3));
    }
  }
  EXPECT_TRUE(r.inner.empty());  // no full-height strip lies inside the ring
  EXPECT_FALSE(r.boundary.empty());
}

TEST(Sivia, MaxBoxesTruncatesSoundly) {
  const Box prior = ring_prior();
  const SubPaving full = sivia(prior, ring_test, ring_options());
  // Exactly enough: not truncated, same paving.
  SiviaOptions o = ring_options();
  o.max_boxes = full.boxes_tested;
  const SubPaving exact = sivia(prior, ring_test, o);
  EXPECT_FALSE(exact.truncated);
  EXPECT_EQ(exact.boundary, full.boundary);

  for (std::size_t cap : {std::size_t{0}, std::size_t{10}, std::size_t{500}}) {
    o.max_boxes = cap;
    const SubPaving p = sivia(prior, ring_test, o);
    EXPECT_TRUE(p.truncated) << cap;
    EXPECT_LE(p.boxes_tested, cap);
    EXPECT_LT(p.boxes_tested, full.boxes_tested);
    // Still an outer approximation: every point of the set is in inner or boundary.
    std::mt19937_64 rng(3);
    for (int k = 0; k < 1000; ++k) {
      const std::vector<double> x = {uniform_in(prior[0], rng), uniform_in(prior[1], rng)};
      if (in_ring(x[0], x[1])) {
        ASSERT_TRUE(in_any(p.inner, p.boundary, x)) << cap;
      }
    }
  }
  o.max_boxes = 0;
  EXPECT_EQ(sivia(prior, ring_test, o).boundary, std::vector<Box>{prior});
  o.max_boxes = 10;  // generations of 1, 2 and 4 boxes; the next 8 would exceed it
  EXPECT_EQ(sivia(prior, ring_test, o).boxes_tested, 7u);
}

TEST(Sivia, CancelStopsEarlyAndSoundly) {
  const Box prior = ring_prior();
  const SubPaving full = sivia(prior, ring_test, ring_options());

  // Set before the call: nothing tested.
  std::atomic<bool> cancel{true};
  SiviaOptions o = ring_options(4);
  o.cancel = &cancel;
  const SubPaving none = sivia(prior, ring_test, o);
  EXPECT_TRUE(none.truncated);
  EXPECT_EQ(none.boxes_tested, 0u);
  EXPECT_EQ(none.boundary, std::vector<Box>{prior});

  // Set from the progress callback after the third generation: no fourth one.
  cancel = false;
  int generations = 0;
  o.progress = [&](std::size_t, std::size_t) {
    if (++generations == 3) {
      cancel = true;
    }
  };
  const SubPaving three = sivia(prior, ring_test, o);
  EXPECT_TRUE(three.truncated);
  EXPECT_EQ(generations, 3);
  EXPECT_EQ(three.boxes_tested, 7u);
  EXPECT_EQ(three.boundary.size(), 8u);

  // Set by the test itself, mid-generation: the boxes not tested yet go to boundary untested.
  cancel = false;
  o.progress = nullptr;
  std::atomic<std::size_t> calls{0};
  const SubPaving mid = sivia(
      prior,
      [&](Box& b) {
        if (++calls == 300) {
          cancel = true;
        }
        return ring_test(b);
      },
      o);
  EXPECT_TRUE(mid.truncated);
  EXPECT_EQ(mid.boxes_tested, calls.load());
  EXPECT_GE(mid.boxes_tested, 300u);
  EXPECT_LT(mid.boxes_tested, full.boxes_tested);
  std::mt19937_64 rng(4);
  for (int k = 0; k < 1000; ++k) {
    const std::vector<double> x = {uniform_in(prior[0], rng), uniform_in(prior[1], rng)};
    if (in_ring(x[0], x[1])) {
      ASSERT_TRUE(in_any(mid.inner, mid.boundary, x));
    }
  }
}

TEST(Sivia, ProgressIsCalledPerGenerationFromTheCallingThread) {
  struct Call {
    std::size_t tested, pending;
    std::thread::id thread;
  };
  std::vector<Call> calls;
  SiviaOptions o = ring_options(4);
  o.progress = [&](std::size_t tested, std::size_t pending) {
    calls.push_back({tested, pending, std::this_thread::get_id()});
  };
  const SubPaving p = sivia(ring_prior(), ring_test, o);
  ASSERT_GE(calls.size(), 5u);
  std::size_t tested = 0, pending = 1;
  for (const Call& c : calls) {
    EXPECT_EQ(c.thread, std::this_thread::get_id());
    EXPECT_GT(c.tested, tested);
    EXPECT_EQ(c.tested, tested + pending);  // each generation tests all that was pending
    tested = c.tested;
    pending = c.pending;
  }
  EXPECT_EQ(calls.back().tested, p.boxes_tested);
  EXPECT_EQ(calls.back().pending, 0u);
}

void expect_invalid(const Box& prior, const SiviaOptions& o, const std::string& field) {
  try {
    sivia(prior, ring_test, o);
    ADD_FAILURE() << "no exception for " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(Sivia, InvalidOptionsAreRejected) {
  const Box prior = ring_prior();
  for (double eps : {0.0, -0.1, std::nan(""), HUGE_VAL}) {
    SiviaOptions o;
    o.epsilon = eps;
    expect_invalid(prior, o, "epsilon");
  }
  SiviaOptions o;
  o.scale = {1.0, 1.0, 1.0};
  expect_invalid(prior, o, "scale");
  o.scale = {1.0, -1.0};
  expect_invalid(prior, o, "scale");
  o.scale = {};
  o.threads = -1;
  expect_invalid(prior, o, "threads");
  o.threads = 0;
  expect_invalid(Box{}, o, "prior");
  expect_invalid(Box{Interval(0, 1), Interval::empty()}, o, "prior");
  expect_invalid(Box{Interval(0, 1), Interval(0, HUGE_VAL)}, o, "prior");
  expect_invalid(Box(2), o, "prior");
  EXPECT_THROW(sivia(prior, BoxTest{}), std::invalid_argument);
}

TEST(Sivia, ExceptionFromTheTestPropagates) {
  for (int threads : {1, 4}) {
    SiviaOptions o = ring_options(threads);
    std::size_t tested_before = 0;  // by the generations that completed
    o.progress = [&](std::size_t tested, std::size_t) { tested_before = tested; };
    std::atomic<std::size_t> calls{0};
    auto throwing = [&](Box& b) {
      ++calls;
      if (b[0].width() < 0.2) {
        throw std::runtime_error("test failed on a small box");
      }
      return ring_test(b);
    };
    try {
      sivia(ring_prior(), throwing, o);
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_STREQ(e.what(), "test failed on a small box");
    }
    // Every box of the generation with x1 narrower than 0.2 throws: each thread tests at most one
    // of them before the paver stops the generation.
    EXPECT_GT(tested_before, 100u);
    EXPECT_GT(calls.load(), tested_before) << threads;
    EXPECT_LE(calls.load(), tested_before + static_cast<std::size_t>(threads)) << threads;
  }
  // A test that changes the box's dimension is a programming error.
  EXPECT_THROW(sivia(ring_prior(),
                     [](Box& b) {
                       b = Box(3, Interval(0, 1));
                       return BoxDecision{};
                     }),
               std::logic_error);
}

}  // namespace
}  // namespace furuta::interval::sivia_test
