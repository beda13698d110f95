#pragma once
// The splitting drivers' generations run in parallel (internal to the validated library).

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstddef>

#include "furuta/common/tsan.hpp"

namespace furuta::validated::detail {

// run(i) for i in [0, count) on the arena's threads, one index per task; returns when all are
// done. Each run must touch only its own outputs: the result then does not depend on the schedule.
template <class Run>
void parallel_runs(tbb::task_arena& arena, std::size_t count, const Run& run) {
  ParallelEdges edges;  // for ThreadSanitizer only (furuta/common/tsan.hpp)
  edges.start();
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        edges.body_begins();
                        for (std::size_t i = range.begin(); i < range.end(); ++i) run(i);
                        edges.body_ends();
                      });
  });
  edges.finish();
}

}  // namespace furuta::validated::detail
