// SIVIA as a generational loop: the pending boxes of one generation are tested in parallel, each
// test writing only its own slot, then the slots are gathered in index order. The outcome of a box
// depends on nothing but the box and the test, so the paving is the same for every thread count.
#include "furuta/interval/sivia.hpp"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "furuta/common/tsan.hpp"

namespace furuta::interval {
namespace {

// What became of one pending box in a generation.
enum class Outcome : unsigned char { inner, outer, boundary, split, skipped, carved };

void validate(const Box& prior, const SiviaOptions& options) {
  if (prior.size() == 0) {
    throw std::invalid_argument("sivia: prior has no component");
  }
  if (prior.is_empty()) {
    throw std::invalid_argument("sivia: prior is empty");
  }
  for (std::size_t i = 0; i < prior.size(); ++i) {
    if (!prior[i].is_bounded()) {
      throw std::invalid_argument("sivia: prior[" + std::to_string(i) + "] is unbounded");
    }
  }
  if (!(options.epsilon > 0) || !std::isfinite(options.epsilon)) {
    throw std::invalid_argument("sivia: options.epsilon must be finite and > 0");
  }
  if (!options.scale.empty()) {
    if (options.scale.size() != prior.size()) {
      throw std::invalid_argument("sivia: options.scale has " +
                                  std::to_string(options.scale.size()) + " components, the prior " +
                                  std::to_string(prior.size()));
    }
    for (std::size_t i = 0; i < options.scale.size(); ++i) {
      if (!(options.scale[i] >= 0) || !std::isfinite(options.scale[i])) {
        throw std::invalid_argument("sivia: options.scale[" + std::to_string(i) +
                                    "] must be finite and >= 0");
      }
    }
  }
  if (options.threads < 0) {
    throw std::invalid_argument("sivia: options.threads must be >= 0");
  }
}

// The scale each component's width is compared with; 0 marks a component that is never bisected
// (scale 0, or a point in the prior).
std::vector<double> effective_scale(const Box& prior, const SiviaOptions& options) {
  std::vector<double> s(prior.size());
  for (std::size_t i = 0; i < prior.size(); ++i) {
    const double w = prior[i].width();
    s[i] = w == 0 ? 0.0 : (options.scale.empty() ? w : options.scale[i]);
  }
  return s;
}

bool small_enough(const Box& b, const std::vector<double>& scale, double epsilon) {
  for (std::size_t i = 0; i < b.size(); ++i) {
    if (scale[i] > 0 && !(b[i].width() / scale[i] <= epsilon)) {
      return false;
    }
  }
  return true;
}

// A box that epsilon stops: boundary, or carved into an inner sub-box (left in `slot`) and the
// boundary rest (in `rest`) when the probe proves one.
Outcome stop(const SiviaOptions& options, Box&& work, Box& slot, std::vector<Box>& rest) {
  if (options.inner_probe) {
    std::optional<Box> inner = options.inner_probe(work);
    if (inner && !inner->is_empty() && inner->size() == work.size() && inner->is_subset(work)) {
      rest = difference(work, *inner);
      slot = std::move(*inner);
      return Outcome::carved;
    }
  }
  slot = std::move(work);
  return Outcome::boundary;
}

// Whether a test contracted its box, and (when the record is kept) the box before and after.
struct Shrink {
  bool contracted = false;
  Contraction record;
};

// Tests box `slot` (in place: it ends as the box to keep, contracted unless outer) and, when it is
// to be bisected, leaves the lower half in `slot` and the upper one in `upper`. A box contracted
// but not outer is noted in `shrink` (with copies of both boxes when `record`).
Outcome process(const BoxTest& test, const std::vector<double>& scale, const SiviaOptions& options,
                bool record, Box& slot, Box& upper, std::vector<Box>& rest, Shrink& shrink) {
  const double epsilon = options.epsilon;
  Box work = slot;
  const BoxDecision decision = test(work);
  if (work.size() != slot.size()) {
    throw std::logic_error("sivia: the test changed the box's dimension");
  }
  if (decision.verdict == BoxVerdict::outer || work.is_empty()) {
    return Outcome::outer;  // the whole tested box is outside the set: keep it as it was
  }
  if (!work.is_subset(slot)) {
    // A contractor may only shrink; what it added is outside the tested box anyway.
    work = intersect(work, slot);
    if (work.is_empty()) {
      return Outcome::outer;
    }
  }
  if (!(work == slot)) {
    shrink.contracted = true;
    if (record) {
      shrink.record = Contraction{slot, work};
    }
  }
  if (decision.verdict == BoxVerdict::inner) {
    slot = std::move(work);
    return Outcome::inner;
  }
  if (small_enough(work, scale, epsilon)) {
    return stop(options, std::move(work), slot, rest);
  }
  auto halves = work.bisect(work.widest_relative_index(scale), 0.5);
  if (halves.first == work || halves.second == work) {
    // The component is down to adjacent doubles (only with a tiny epsilon): cannot split further.
    return stop(options, std::move(work), slot, rest);
  }
  slot = std::move(halves.first);
  upper = std::move(halves.second);
  return Outcome::split;
}

double volume(const Box& b) {
  if (b.is_empty()) {
    return 0.0;
  }
  double v = 1.0;
  for (const Interval& x : b) {
    v *= x.width();
  }
  return v;
}

Box hull_of(std::size_t n, const std::vector<Box>& a, const std::vector<Box>* b) {
  Box h(n, Interval::empty());
  auto add = [&](const std::vector<Box>& boxes) {
    for (const Box& box : boxes) {
      for (std::size_t i = 0; i < n && i < box.size(); ++i) {
        h[i] = hull(h[i], box[i]);
      }
    }
  };
  add(a);
  if (b != nullptr) {
    add(*b);
  }
  return h;
}

}  // namespace

Box SubPaving::outer_hull() const {
  return hull_of(prior.size(), inner, &boundary);
}

Box SubPaving::inner_hull() const {
  return hull_of(prior.size(), inner, nullptr);
}

double SubPaving::inner_volume() const {
  double v = 0;
  for (const Box& b : inner) {
    v += volume(b);
  }
  return v;
}

double SubPaving::boundary_volume() const {
  double v = 0;
  for (const Box& b : boundary) {
    v += volume(b);
  }
  return v;
}

SubPaving sivia(const Box& prior, const BoxTest& test, const SiviaOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  validate(prior, options);
  if (!test) {
    throw std::invalid_argument("sivia: test is empty");
  }
  const std::vector<double> scale = effective_scale(prior, options);
  auto cancelled = [&] {
    return options.cancel != nullptr && options.cancel->load(std::memory_order_relaxed);
  };

  SubPaving result;
  result.prior = prior;
  // More threads than cores would only make oneTBB print a warning: clamp.
  const int cores = tbb::info::default_concurrency();
  tbb::task_arena arena(options.threads > 0 ? std::min(options.threads, cores)
                                            : tbb::task_arena::automatic);

  std::vector<Box> current{prior};
  std::vector<Box> upper;
  std::vector<std::vector<Box>> rests;  // the boundary rests of carved boxes
  std::vector<Outcome> outcomes;
  std::vector<Shrink> shrinks;
  std::vector<Box> next;
  while (!current.empty()) {
    if (cancelled() || result.boxes_tested + current.size() > options.max_boxes) {
      for (Box& b : current) {
        result.boundary.push_back(std::move(b));
      }
      result.truncated = true;
      break;
    }
    const std::size_t n = current.size();
    upper.clear();
    upper.resize(n);
    rests.clear();
    rests.resize(n);
    outcomes.assign(n, Outcome::skipped);
    shrinks.clear();
    shrinks.resize(n);
    // Copies are made only while the record has room at the generation's start: at most one
    // generation's worth is copied and then not kept.
    const bool record = result.contractions.size() < options.max_kept_contractions;
    const auto process_slot = [&](std::size_t i) {
      return process(test, scale, options, record, current[i], upper[i], rests[i], shrinks[i]);
    };

    // The first exception thrown by a test stops the generation; it is rethrown below.
    std::atomic<bool> failed{false};
    std::mutex error_mutex;
    std::exception_ptr error;
    std::size_t error_index = n;
    ParallelEdges edges;  // for ThreadSanitizer only (furuta/common/tsan.hpp)
    edges.start();
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          edges.body_begins();
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                            if (failed.load(std::memory_order_relaxed) || cancelled()) {
                              continue;  // skipped: stays pending, goes to boundary
                            }
                            try {
                              outcomes[i] = process_slot(i);
                            } catch (...) {
                              failed.store(true, std::memory_order_relaxed);
                              const std::lock_guard<std::mutex> lock(error_mutex);
                              if (i < error_index) {
                                error_index = i;
                                error = std::current_exception();
                              }
                            }
                          }
                          edges.body_ends();
                        });
    });
    edges.finish();
    if (error) {
      std::rethrow_exception(error);
    }

    next.clear();
    for (std::size_t i = 0; i < n; ++i) {
      if (shrinks[i].contracted) {
        ++result.contraction_count;
        if (result.contractions.size() < options.max_kept_contractions) {
          result.contractions.push_back(std::move(shrinks[i].record));
        }
      }
      switch (outcomes[i]) {
        case Outcome::inner:
          result.inner.push_back(std::move(current[i]));
          break;
        case Outcome::outer:
          ++result.outer_count;
          if (options.keep_outer) {
            result.outer.push_back(std::move(current[i]));
          }
          break;
        case Outcome::boundary:
          result.boundary.push_back(std::move(current[i]));
          break;
        case Outcome::carved:
          ++result.probed_inner;
          result.inner.push_back(std::move(current[i]));
          for (Box& b : rests[i]) {
            result.boundary.push_back(std::move(b));
          }
          break;
        case Outcome::split:
          ++result.bisections;
          next.push_back(std::move(current[i]));
          next.push_back(std::move(upper[i]));
          break;
        case Outcome::skipped:
          result.boundary.push_back(std::move(current[i]));
          result.truncated = true;
          continue;  // not tested
      }
      ++result.boxes_tested;
    }
    std::swap(current, next);
    if (options.progress) {
      options.progress(result.boxes_tested, current.size());
    }
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace furuta::interval
