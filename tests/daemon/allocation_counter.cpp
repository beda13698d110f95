#include "allocation_counter.hpp"

#include <cstdlib>
#include <new>

namespace {

// Plain thread_local integers: constant-initialised, so touching them inside operator new never
// allocates or runs a constructor.
constinit thread_local int active_counters = 0;
constinit thread_local std::size_t allocation_count = 0;
constinit thread_local std::size_t deallocation_count = 0;

void* allocate(std::size_t size, std::size_t alignment) {
  if (active_counters > 0) ++allocation_count;
  if (size == 0) size = 1;  // every allocation must return a distinct pointer
  for (;;) {
    void* p = nullptr;
    if (alignment <= alignof(std::max_align_t)) {
      p = std::malloc(size);
    } else if (posix_memalign(&p, alignment, size) != 0) {
      p = nullptr;
    }
    if (p != nullptr) return p;
    // The standard's contract: retry through the installed handler, else bad_alloc.
    std::new_handler handler = std::get_new_handler();
    if (handler == nullptr) throw std::bad_alloc();
    handler();
  }
}

void* allocate_nothrow(std::size_t size, std::size_t alignment) noexcept {
  try {
    return allocate(size, alignment);
  } catch (...) {
    return nullptr;
  }
}

void deallocate(void* p) noexcept {
  if (p == nullptr) return;
  if (active_counters > 0) ++deallocation_count;
  std::free(p);
}

}  // namespace

namespace furuta::testing {

ScopedAllocationCounter::ScopedAllocationCounter() noexcept
    : allocations_at_start_(allocation_count), deallocations_at_start_(deallocation_count) {
  ++active_counters;
}

ScopedAllocationCounter::~ScopedAllocationCounter() {
  --active_counters;
}

std::size_t ScopedAllocationCounter::allocations() const noexcept {
  return allocation_count - allocations_at_start_;
}

std::size_t ScopedAllocationCounter::deallocations() const noexcept {
  return deallocation_count - deallocations_at_start_;
}

}  // namespace furuta::testing

// The replacements. Every form is defined so none falls back to a library default that might
// bypass (or double-count through) another.
void* operator new(std::size_t size) {
  return allocate(size, 0);
}
void* operator new[](std::size_t size) {
  return allocate(size, 0);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return allocate_nothrow(size, 0);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return allocate_nothrow(size, 0);
}
void* operator new(std::size_t size, std::align_val_t alignment) {
  return allocate(size, static_cast<std::size_t>(alignment));
}
void* operator new[](std::size_t size, std::align_val_t alignment) {
  return allocate(size, static_cast<std::size_t>(alignment));
}
void* operator new(std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return allocate_nothrow(size, static_cast<std::size_t>(alignment));
}
void* operator new[](std::size_t size, std::align_val_t alignment, const std::nothrow_t&) noexcept {
  return allocate_nothrow(size, static_cast<std::size_t>(alignment));
}

void operator delete(void* p) noexcept {
  deallocate(p);
}
void operator delete[](void* p) noexcept {
  deallocate(p);
}
void operator delete(void* p, std::size_t) noexcept {
  deallocate(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  deallocate(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  deallocate(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  deallocate(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  deallocate(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  deallocate(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  deallocate(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  deallocate(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  deallocate(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  deallocate(p);
}
