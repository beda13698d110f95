#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <new>
#include <thread>
#include <vector>

namespace furuta::testing {
namespace {

// Keeps the compiler from eliding an allocation it could otherwise see through.
template <typename T>
void escape(T* p) {
  asm volatile("" : : "g"(p) : "memory");
}

struct alignas(64) OverAligned {
  char bytes[64];
};

TEST(AllocationCounter, CountsThisThreadsAllocationsOfEveryForm) {
  std::size_t allocations = 0;
  std::size_t deallocations = 0;
  {
    ScopedAllocationCounter counter;
    {
      auto one = std::make_unique<int>(1);
      escape(one.get());
      auto many = std::make_unique<int[]>(10);
      escape(many.get());
      auto aligned = std::make_unique<OverAligned>();
      escape(aligned.get());
      int* nothrow = new (std::nothrow) int(3);
      escape(nothrow);
      delete nothrow;
    }
    allocations = counter.allocations();
    deallocations = counter.deallocations();
  }
  EXPECT_EQ(allocations, 4U);
  EXPECT_EQ(deallocations, 4U);
}

TEST(AllocationCounter, OverAlignedAllocationsAreAligned) {
  auto aligned = std::make_unique<OverAligned>();
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(aligned.get()) % 64, 0U);
}

TEST(AllocationCounter, OtherThreadsAreNotCounted) {
  std::size_t allocations = 0;
  {
    ScopedAllocationCounter counter;
    std::size_t other_thread_allocations = 0;
    std::thread other([&] {
      auto p = std::make_unique<std::vector<int>>(100, 1);
      escape(p.get());
      other_thread_allocations = p->size();
    });
    // Starting a thread allocates its state on this thread: measure from after that.
    const std::size_t before_join = counter.allocations();
    other.join();
    allocations = counter.allocations() - before_join;
    EXPECT_EQ(other_thread_allocations, 100U);
  }
  EXPECT_EQ(allocations, 0U);
}

TEST(AllocationCounter, ScopesNestAndStartFromZero) {
  std::size_t outer_count = 0;
  std::size_t inner_count = 0;
  {
    ScopedAllocationCounter outer;
    auto a = std::make_unique<int>(1);
    escape(a.get());
    {
      ScopedAllocationCounter inner;
      auto b = std::make_unique<int>(2);
      escape(b.get());
      b.reset();
      inner_count = inner.allocations();
    }
    outer_count = outer.allocations();
  }
  EXPECT_EQ(inner_count, 1U);
  EXPECT_EQ(outer_count, 2U);

  auto outside = std::make_unique<int>(3);
  escape(outside.get());
  ScopedAllocationCounter later;
  const std::size_t at_start = later.allocations();
  EXPECT_EQ(at_start, 0U);
}

}  // namespace
}  // namespace furuta::testing
