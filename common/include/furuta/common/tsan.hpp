#pragma once
// Happens-before edges that ThreadSanitizer cannot see by itself (the `tsan` preset,
// docs/reliability.d/sanitizers.md); no code at all in other builds.
//
// Debian's oneTBB is not built with -fsanitize=thread: its scheduler hands work to the workers, and
// waits for them, through atomics inside libtbb that ThreadSanitizer never sees. A parallel_for
// body then looks unordered with what the calling thread wrote before the call and read after it.
// ParallelEdges states exactly what oneTBB guarantees, and no more: everything before start()
// happens before every body, and every body happens before everything after finish(). Bodies
// stay unordered with each other, so a race between two of them is still reported.

#if defined(__SANITIZE_THREAD__)
#include <sanitizer/tsan_interface.h>
#endif

namespace furuta {

class ParallelEdges {
 public:
  void start() noexcept { release(&start_); }        // the caller, before the parallel call
  void body_begins() noexcept { acquire(&start_); }  // each body (chunk), first
  void body_ends() noexcept { release(&done_); }     // each body (chunk), last
  void finish() noexcept { acquire(&done_); }        // the caller, after the parallel call

 private:
  static void release(char* sync) noexcept {
#if defined(__SANITIZE_THREAD__)
    __tsan_release(sync);
#else
    static_cast<void>(sync);
#endif
  }
  static void acquire(char* sync) noexcept {
#if defined(__SANITIZE_THREAD__)
    __tsan_acquire(sync);
#else
    static_cast<void>(sync);
#endif
  }
  char start_ = 0;
  char done_ = 0;
};

}  // namespace furuta
