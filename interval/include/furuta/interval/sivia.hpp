#pragma once
// SIVIA (Jaulin and Walter's set inversion via interval analysis) as a paver over any set test:
// boxes proven inside the set (inner), proven outside (outer), and the undecided ones bisected
// down to epsilon (boundary). The set is given by a BoxTest, which may also contract the box
// (forward-backward propagation) before deciding.
//
// The paving is the same whatever the thread count: boxes are processed generation by generation,
// each generation's tests run in parallel, and their results are gathered in generation order.

#include <atomic>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"

namespace furuta::interval {

enum class BoxVerdict { inner, outer, undecided };

// What a test says about one box. `box` may be contracted in place by the test: every point of the
// set inside the original box must stay inside the contracted one. An empty contracted box is
// outer.
struct BoxDecision {
  BoxVerdict verdict = BoxVerdict::undecided;
};

// Called concurrently from several threads: must not mutate shared state.
using BoxTest = std::function<BoxDecision(Box& box)>;

struct SiviaOptions {
  // A boundary box is not bisected further once every component's width relative to `scale` is at
  // most epsilon (scale empty: the prior box's widths, so epsilon is a fraction of the prior box).
  double epsilon = 0.01;
  std::vector<double> scale;
  // 0: all cores.
  int threads = 0;
  // Keep the outer boxes (for drawing); else only counted.
  bool keep_outer = true;
  // Keep (before, after) of at most this many boxes a test contracted, the first ones in the
  // paving's order (generation by generation, each in index order); all are counted. Each kept one
  // costs two boxes, so this bounds the memory the record takes. 0: count only.
  std::size_t max_kept_contractions = 100'000;
  // A hard cap on tests run; reached, the remaining boxes are returned as boundary and
  // `SubPaving::truncated` is set.
  std::size_t max_boxes = 50'000'000;
  // Called after each generation from the calling thread: boxes tested so far and boxes pending.
  std::function<void(std::size_t tested, std::size_t pending)> progress;
  // Set to true from another thread to stop early (the result is then truncated).
  const std::atomic<bool>* cancel = nullptr;
  // Optional, called concurrently on each box that epsilon stops undecided: a sub-box proven inside
  // the set, or nothing. The sub-box goes to inner and the rest of the box (difference()) to
  // boundary. Bisection alone never proves a set inner when it is smaller than an epsilon box;
  // a probe around the contracted box's centre does.
  std::function<std::optional<Box>(const Box&)> inner_probe;
};

// A box a test contracted without deciding it outer: every point of `before` outside `after` is
// proven outside the set (the test's contract), and `after` went on (inner, boundary or bisected).
struct Contraction {
  Box before, after;
};

struct SubPaving {
  Box prior;
  // outer: the tested boxes (before contraction) proven outside; what a contracting test cut off
  // a box it did not decide outer is in `contractions`. boundary also holds the untested boxes of
  // a truncated run.
  std::vector<Box> inner, boundary, outer;
  // The first SiviaOptions::max_kept_contractions contractions. When every outer box and every
  // contraction is kept, inner, boundary, outer and the before \ after together cover the prior.
  std::vector<Contraction> contractions;
  std::size_t boxes_tested = 0;
  std::size_t bisections = 0;
  std::size_t outer_count = 0;        // also counted when not kept
  std::size_t contraction_count = 0;  // also counted when not kept
  std::size_t probed_inner = 0;       // inner boxes found by options.inner_probe
  bool truncated = false;
  double seconds = 0;

  bool empty_inner_and_boundary() const { return inner.empty() && boundary.empty(); }
  // The smallest box containing inner and boundary (the outer approximation's hull); when the set
  // is proven empty, a box of prior.size() components that are all empty.
  Box outer_hull() const;
  // The hull of the inner boxes (prior.size() empty components when there are none).
  Box inner_hull() const;
  // Sums of the boxes' volumes (products of widths; 0 for an empty box).
  double inner_volume() const;
  double boundary_volume() const;
};

// Paves `prior` (non-empty, bounded). Throws std::invalid_argument naming the bad field (prior,
// options.epsilon, options.scale, options.threads) or for an empty test. An exception thrown by the
// test stops the parallel work and is rethrown here (no partial result); a test that changes the
// box's dimension gives std::logic_error.
SubPaving sivia(const Box& prior, const BoxTest& test, const SiviaOptions& options = {});

}  // namespace furuta::interval
