#pragma once
// Counts heap allocations made by one thread, to prove that real-time code does not allocate.
//
// allocation_counter.cpp replaces the global operator new and operator delete (every form: plain,
// array, nothrow, sized, aligned) for the whole daemon_tests binary. The replacements allocate with
// malloc/free as before and, while a ScopedAllocationCounter is alive on the calling thread,
// count the call in thread_local counters. Other threads (gtest, a simulated rig, a logger) are
// never counted, so a test can run a loop thread next to allocating helpers and still ask
// "did the loop thread allocate?".
//
//   furuta::testing::ScopedAllocationCounter counter;   // on the thread under test
//   for (...) excitation.duty(t, q);
//   EXPECT_EQ(counter.allocations(), 0U);
//
// Read the counts and run gtest assertions after the code under test: a failing assertion builds
// its message on the heap and would be counted. Counters nest: an inner counter sees only its own
// scope, an outer one sees everything since it started. Note that the compiler may elide a
// new/delete pair it can see through; code that must be counted should let its pointer escape.

#include <cstddef>

namespace furuta::testing {

class ScopedAllocationCounter {
 public:
  ScopedAllocationCounter() noexcept;  // starts counting on this thread
  ~ScopedAllocationCounter();          // stops, unless an outer counter is still alive
  ScopedAllocationCounter(const ScopedAllocationCounter&) = delete;
  ScopedAllocationCounter& operator=(const ScopedAllocationCounter&) = delete;

  // Calls to operator new (any form) / operator delete (any form, null pointers excluded) on this
  // thread since construction. Call from the constructing thread.
  std::size_t allocations() const noexcept;
  std::size_t deallocations() const noexcept;

 private:
  std::size_t allocations_at_start_;
  std::size_t deallocations_at_start_;
};

}  // namespace furuta::testing
