#include "furuta/daemon/realtime.hpp"

#include <gtest/gtest.h>
#include <linux/capability.h>
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace furuta::daemon {
namespace {

// ---------------------------------------------------------------------------------------------
// LatencyHistogram

// The reference quantile: the sample of rank ceil(q * n) (1-based) in sorted order.
std::int64_t reference_quantile(const std::vector<std::int64_t>& sorted, double q) {
  const auto n = static_cast<double>(sorted.size());
  const double rank = std::max(1.0, std::ceil(q * n - 1e-6));
  return sorted[static_cast<std::size_t>(rank) - 1];
}

double bucket_width_us(std::int64_t latency_ns) {
  if (latency_ns <= 1'000'000) return 1.0;
  return 100.0;
}

TEST(LatencyHistogram, QuantilesMatchASortedReferenceWithinOneBucket) {
  std::mt19937_64 rng(20240611);
  // Log-uniform from 1 ns to 300 ms covers the fine, coarse and overflow ranges; a few negatives
  // stand for early wake-ups.
  std::uniform_real_distribution<double> log_ns(0.0, std::log(300e6));
  std::bernoulli_distribution early(0.01);
  std::uniform_int_distribution<std::int64_t> early_ns(-900, 0);
  std::vector<std::int64_t> samples;
  LatencyHistogram histogram;
  for (int i = 0; i < 100'000; ++i) {
    const std::int64_t sample =
        early(rng) ? early_ns(rng) : static_cast<std::int64_t>(std::exp(log_ns(rng)));
    samples.push_back(sample);
    histogram.record(sample);
  }
  std::sort(samples.begin(), samples.end());

  ASSERT_EQ(histogram.count(), samples.size());
  EXPECT_DOUBLE_EQ(histogram.max_us(), static_cast<double>(samples.back()) / 1000.0);
  double sum = 0.0;
  for (const auto s : samples) sum += static_cast<double>(s);
  EXPECT_NEAR(histogram.mean_us(), sum / static_cast<double>(samples.size()) / 1000.0, 1e-6);

  for (const double q : {0.0, 0.001, 0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 0.999, 0.9999, 1.0}) {
    const std::int64_t reference_ns = reference_quantile(samples, q);
    const double reference_us = static_cast<double>(reference_ns) / 1000.0;
    const double got = histogram.quantile_us(q);
    SCOPED_TRACE("q = " + std::to_string(q) + ", reference " + std::to_string(reference_us) +
                 " us");
    EXPECT_GE(got, reference_us - 1e-9);
    if (reference_ns > 100'000'000) {
      EXPECT_DOUBLE_EQ(got, histogram.max_us());  // the overflow bucket reports the exact max
    } else {
      // Early wake-ups share the first bucket, whose upper edge is 1 us.
      EXPECT_LE(got - std::max(reference_us, 0.0), bucket_width_us(reference_ns) + 1e-9);
    }
  }
}

// One sample at the given latency, plus one far beyond it so that the max does not cap the
// reported edge: the median is then the edge of the first sample's bucket.
double edge_of_bucket_holding(std::int64_t latency_ns) {
  LatencyHistogram histogram;
  histogram.record(latency_ns);
  histogram.record(500'000'000);
  return histogram.quantile_us(0.5);
}

TEST(LatencyHistogram, BucketEdgesAreInclusiveAtOneMillisecondAndOneHundred) {
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(-5'000), 1.0);  // woke early: first bucket
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(0), 1.0);
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(1'000), 1.0);
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(1'001), 2.0);
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(999'999), 1000.0);
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(1'000'000), 1000.0);  // exactly 1 ms: last fine bucket
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(1'000'001), 1100.0);  // first coarse bucket
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(1'100'000), 1100.0);
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(1'100'001), 1200.0);
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(100'000'000), 100'000.0);  // exactly 100 ms
  // Past 100 ms: the overflow bucket, which reports the exact max.
  EXPECT_DOUBLE_EQ(edge_of_bucket_holding(100'000'001), 500'000.0);
}

TEST(LatencyHistogram, OverflowKeepsTheExactMax) {
  LatencyHistogram histogram;
  histogram.record(2'000);
  histogram.record(123'456'789);
  EXPECT_DOUBLE_EQ(histogram.max_us(), 123'456.789);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(1.0), 123'456.789);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(0.5), 2.0);
  EXPECT_DOUBLE_EQ(histogram.mean_us(), (2'000.0 + 123'456'789.0) / 2.0 / 1000.0);
}

TEST(LatencyHistogram, AQuantileNeverReadsAboveTheMax) {
  LatencyHistogram histogram;
  for (int i = 0; i < 10; ++i) histogram.record(10'200);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(0.5), 10.2);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(0.999), 10.2);
}

TEST(LatencyHistogram, EarlyWakeUpsAreCountedAndKeepAnExactMaxAndMean) {
  LatencyHistogram histogram;
  histogram.record(-3'000);
  histogram.record(-1'000);
  EXPECT_EQ(histogram.count(), 2u);
  EXPECT_DOUBLE_EQ(histogram.max_us(), -1.0);
  EXPECT_DOUBLE_EQ(histogram.mean_us(), -2.0);
  EXPECT_LE(histogram.quantile_us(1.0), 1.0);
}

TEST(LatencyHistogram, OutOfRangeQuantilesAreClamped) {
  LatencyHistogram histogram;
  histogram.record(5'000);
  histogram.record(50'000);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(-1.0), 5.0);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(std::nan("")), 5.0);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(2.0), 50.0);
}

TEST(LatencyHistogram, EmptyReadsZero) {
  const LatencyHistogram histogram;
  EXPECT_EQ(histogram.count(), 0u);
  EXPECT_EQ(histogram.mean_us(), 0.0);
  EXPECT_EQ(histogram.max_us(), 0.0);
  EXPECT_EQ(histogram.quantile_us(0.5), 0.0);
  EXPECT_EQ(histogram.quantile_us(1.0), 0.0);
}

TEST(LatencyHistogram, ResetForgetsEverything) {
  LatencyHistogram histogram;
  for (int i = 0; i < 100; ++i) histogram.record(250'000'000);
  histogram.reset();
  EXPECT_EQ(histogram.count(), 0u);
  EXPECT_EQ(histogram.mean_us(), 0.0);
  EXPECT_EQ(histogram.max_us(), 0.0);
  EXPECT_EQ(histogram.quantile_us(0.99), 0.0);
  // After a reset the old overflow samples and max are gone, not merely hidden.
  histogram.record(7'500);
  EXPECT_EQ(histogram.count(), 1u);
  EXPECT_DOUBLE_EQ(histogram.max_us(), 7.5);
  EXPECT_DOUBLE_EQ(histogram.quantile_us(1.0), 7.5);
  EXPECT_DOUBLE_EQ(histogram.mean_us(), 7.5);
}

// ---------------------------------------------------------------------------------------------
// Real-time set-up. Each test applies it on a thread of its own (or in a child process), so the
// test process never keeps SCHED_FIFO, a pinned CPU or locked memory.

struct ThreadState {
  int policy = -1;
  int priority = -1;
  std::vector<int> cpus;
  int timer_slack_ns = -1;
};

ThreadState state_of_this_thread() {
  ThreadState state;
  sched_param param{};
  pthread_getschedparam(pthread_self(), &state.policy, &param);
  state.priority = param.sched_priority;
  cpu_set_t set;
  CPU_ZERO(&set);
  if (pthread_getaffinity_np(pthread_self(), sizeof(set), &set) == 0) {
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
      if (CPU_ISSET(cpu, &set)) state.cpus.push_back(cpu);
  }
  state.timer_slack_ns = prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0);
  return state;
}

struct Outcome {
  RealtimeResult result;
  ThreadState before;
  ThreadState after;
  int scheduler_after = -1;  // as sched_getscheduler reports it, independently of pthread
};

Outcome apply_on_a_fresh_thread(const RealtimeOptions& options) {
  Outcome outcome;
  std::thread thread([&] {
    outcome.before = state_of_this_thread();
    outcome.result = apply_realtime_to_this_thread(options);
    outcome.after = state_of_this_thread();
    outcome.scheduler_after = sched_getscheduler(0);  // 0: the calling thread on Linux
  });
  thread.join();
  return outcome;
}

bool has_line_starting(const std::vector<std::string>& lines, const std::string& prefix) {
  return std::any_of(lines.begin(), lines.end(), [&](const std::string& line) {
    return line.rfind(prefix, 0) == 0 && line.size() > prefix.size();  // a reason follows
  });
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& line : lines) out += line + "\n";
  return out;
}

TEST(Realtime, FifoIsReportedExactlyAsTheThreadHasIt) {
  RealtimeOptions options;
  options.enabled = true;
  options.fifo_priority = 80;
  const ThreadState main_before = state_of_this_thread();
  const Outcome outcome = apply_on_a_fresh_thread(options);
  SCOPED_TRACE(joined(outcome.result.refused));
  if (outcome.result.fifo) {
    EXPECT_EQ(outcome.after.policy, SCHED_FIFO);
    EXPECT_EQ(outcome.scheduler_after, SCHED_FIFO);
    EXPECT_EQ(outcome.after.priority, 80);
    EXPECT_FALSE(has_line_starting(outcome.result.refused, "SCHED_FIFO"));
  } else {
    EXPECT_NE(outcome.after.policy, SCHED_FIFO);
    EXPECT_NE(outcome.scheduler_after, SCHED_FIFO);
    EXPECT_TRUE(has_line_starting(outcome.result.refused, "SCHED_FIFO priority 80: "));
  }
  // The calling thread only: this one is untouched.
  const ThreadState main_after = state_of_this_thread();
  EXPECT_EQ(main_after.policy, main_before.policy);
  EXPECT_NE(main_after.policy, SCHED_FIFO);
}

TEST(Realtime, InvalidPriorityIsRefusedWithTheReasonAndTheRestStillApplies) {
  RealtimeOptions options;
  options.enabled = true;
  options.fifo_priority = 150;
  options.timer_slack_ns = 2'000;
  const Outcome outcome = apply_on_a_fresh_thread(options);
  EXPECT_FALSE(outcome.result.fifo);
  EXPECT_EQ(outcome.after.policy, outcome.before.policy);
  EXPECT_NE(std::find(outcome.result.refused.begin(), outcome.result.refused.end(),
                      "SCHED_FIFO priority 150: Invalid argument"),
            outcome.result.refused.end())
      << joined(outcome.result.refused);
  // Not SCHED_FIFO, so the kernel honours the requested slack exactly.
  EXPECT_TRUE(outcome.result.timer_slack);
  EXPECT_EQ(outcome.after.timer_slack_ns, 2'000);
  EXPECT_FALSE(outcome.result.complete(options));
}

TEST(Realtime, TimerSlackIsReportedAsTheThreadHasIt) {
  RealtimeOptions options;
  options.enabled = true;
  options.timer_slack_ns = 1;
  const Outcome outcome = apply_on_a_fresh_thread(options);
  SCOPED_TRACE(joined(outcome.result.refused));
  ASSERT_GE(outcome.after.timer_slack_ns, 0);
  if (outcome.result.timer_slack) {
    // SCHED_FIFO threads get zero slack on recent kernels; otherwise exactly what was asked.
    EXPECT_LE(outcome.after.timer_slack_ns, 1);
    if (!outcome.result.fifo) {
      EXPECT_EQ(outcome.after.timer_slack_ns, 1);
    }
  } else {
    EXPECT_TRUE(has_line_starting(outcome.result.refused, "timer slack 1 ns: "));
    EXPECT_GT(outcome.after.timer_slack_ns, 1);
  }
}

TEST(Realtime, AffinityPinsTheThreadToTheCpu) {
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  ASSERT_EQ(sched_getaffinity(0, sizeof(allowed), &allowed), 0);
  int cpu = 0;  // CPU 0 unless this process's cpuset leaves it out
  while (cpu < CPU_SETSIZE && !CPU_ISSET(cpu, &allowed)) ++cpu;
  ASSERT_LT(cpu, CPU_SETSIZE);

  RealtimeOptions options;
  options.enabled = true;
  options.cpu = cpu;
  const ThreadState main_before = state_of_this_thread();
  const Outcome outcome = apply_on_a_fresh_thread(options);
  SCOPED_TRACE(joined(outcome.result.refused));
  if (outcome.result.affinity) {
    EXPECT_EQ(outcome.after.cpus, std::vector<int>{cpu});
  } else {
    EXPECT_TRUE(has_line_starting(outcome.result.refused, "CPU affinity " + std::to_string(cpu)));
    EXPECT_EQ(outcome.after.cpus, outcome.before.cpus);
  }
  EXPECT_EQ(state_of_this_thread().cpus, main_before.cpus);
}

TEST(Realtime, NonexistentCpuIsRefusedWithTheReason) {
  RealtimeOptions options;
  options.enabled = true;
  options.cpu = 9999;
  const Outcome outcome = apply_on_a_fresh_thread(options);
  EXPECT_FALSE(outcome.result.affinity);
  EXPECT_TRUE(has_line_starting(outcome.result.refused, "CPU affinity 9999: no such CPU"))
      << joined(outcome.result.refused);
  EXPECT_EQ(outcome.after.cpus, outcome.before.cpus);
  EXPECT_FALSE(outcome.result.complete(options));
}

TEST(Realtime, DisabledAttemptsNothing) {
  RealtimeOptions options;
  options.enabled = false;
  options.cpu = 0;
  options.fifo_priority = 80;
  options.timer_slack_ns = 1;
  const Outcome outcome = apply_on_a_fresh_thread(options);
  EXPECT_FALSE(outcome.result.fifo);
  EXPECT_FALSE(outcome.result.affinity);
  EXPECT_FALSE(outcome.result.timer_slack);
  EXPECT_TRUE(outcome.result.refused.empty());
  EXPECT_TRUE(outcome.result.complete(options));
  EXPECT_EQ(outcome.after.policy, outcome.before.policy);
  EXPECT_EQ(outcome.after.priority, outcome.before.priority);
  EXPECT_EQ(outcome.after.cpus, outcome.before.cpus);
  EXPECT_EQ(outcome.after.timer_slack_ns, outcome.before.timer_slack_ns);
}

TEST(Realtime, CompleteMeansEveryStepAskedForSucceeded) {
  RealtimeOptions options;
  options.enabled = true;
  options.cpu = -1;
  options.timer_slack_ns = 1;
  RealtimeResult result;
  result.fifo = true;
  result.timer_slack = true;
  EXPECT_TRUE(result.complete(options));  // affinity was not asked for
  options.cpu = 1;
  EXPECT_FALSE(result.complete(options));
  result.affinity = true;
  EXPECT_TRUE(result.complete(options));
  result.refused.push_back("something: refused");
  EXPECT_FALSE(result.complete(options));
  result.refused.clear();
  result.fifo = false;
  EXPECT_FALSE(result.complete(options));
  options.enabled = false;
  EXPECT_TRUE(RealtimeResult{}.complete(options));
}

// Runs body in a forked child and returns what it wrote: for process-wide or privilege-dropping
// steps that must not touch the test process. The test process has no other threads here.
std::string in_child_process(const std::function<std::string()>& body) {
  int fds[2];
  if (pipe(fds) != 0) return "pipe failed";
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    const std::string text = body();
    std::size_t written = 0;
    while (written < text.size()) {
      const ssize_t n = write(fds[1], text.data() + written, text.size() - written);
      if (n <= 0) _exit(2);
      written += static_cast<std::size_t>(n);
    }
    _exit(0);
  }
  close(fds[1]);
  std::string text;
  char buffer[256];
  ssize_t n = 0;
  while ((n = read(fds[0], buffer, sizeof(buffer))) > 0)
    text.append(buffer, static_cast<std::size_t>(n));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) return "child failed: " + text;
  return text;
}

// Only ever called in a child process.
bool drop_effective_capability(unsigned capability) {
  __user_cap_header_struct header{_LINUX_CAPABILITY_VERSION_3, 0};
  __user_cap_data_struct data[2]{};
  if (syscall(SYS_capget, &header, data) != 0) return false;
  data[capability / 32].effective &= ~(1u << (capability % 32));
  return syscall(SYS_capset, &header, data) == 0;
}

// Root in a container usually holds CAP_SYS_NICE, so the refusal path is exercised by giving it up
// (and any RLIMIT_RTPRIO allowance) in a child: the message must then carry the kernel's reason.
TEST(Realtime, WithoutPrivilegeFifoIsRefusedAsNotPermitted) {
  const std::string text = in_child_process([] {
    const rlimit none{0, 0};
    if (setrlimit(RLIMIT_RTPRIO, &none) != 0) return std::string("setrlimit failed");
    if (!drop_effective_capability(CAP_SYS_NICE)) return std::string("capset failed");
    RealtimeOptions options;
    options.enabled = true;
    const RealtimeResult result = apply_realtime_to_this_thread(options);
    return std::string(result.fifo ? "fifo\n" : "not fifo\n") + joined(result.refused) +
           (sched_getscheduler(0) == SCHED_FIFO ? "policy fifo\n" : "policy other\n");
  });
  EXPECT_NE(text.find("not fifo\n"), std::string::npos) << text;
  EXPECT_NE(text.find("SCHED_FIFO priority 80: Operation not permitted\n"), std::string::npos)
      << text;
  EXPECT_NE(text.find("policy other\n"), std::string::npos) << text;
}

// The sanitizers (the asan and tsan presets) replace mlockall with a no-op that succeeds: their
// terabytes of shadow memory cannot be locked. What the kernel did is then not what it was asked.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define FURUTA_SKIP_UNDER_SANITIZERS() \
  GTEST_SKIP() << "mlockall is a no-op under the sanitizers (their shadow memory)"
#else
#define FURUTA_SKIP_UNDER_SANITIZERS() static_cast<void>(0)
#endif

// mlockall is process-wide, so it is tried in a child; the answer must match what the kernel says
// the child has locked.
TEST(Realtime, LockProcessMemoryReportsTheTruth) {
  FURUTA_SKIP_UNDER_SANITIZERS();
  const std::string text = in_child_process([] {
    const std::string reason = lock_process_memory();
    std::ifstream status("/proc/self/status");
    std::string line;
    std::string locked = "VmLck: unknown";
    while (std::getline(status, line))
      if (line.rfind("VmLck:", 0) == 0) locked = line;
    return (reason.empty() ? std::string("locked\n") : "refused: " + reason + "\n") + locked;
  });
  if (text.rfind("locked\n", 0) == 0) {
    const auto pos = text.find("VmLck:");
    ASSERT_NE(pos, std::string::npos) << text;
    EXPECT_GT(std::stol(text.substr(pos + 6)), 0) << text;
  } else {
    // The reason alone (the caller names the step), and not empty.
    EXPECT_EQ(text.rfind("refused: ", 0), 0u) << text;
    EXPECT_EQ(text.find("mlockall"), std::string::npos) << text;
    EXPECT_GT(text.find('\n'), std::string("refused: ").size()) << text;
  }
}

TEST(Realtime, WithoutPrivilegeLockProcessMemoryGivesTheReason) {
  FURUTA_SKIP_UNDER_SANITIZERS();
  const std::string text = in_child_process([] {
    const rlimit none{0, 0};
    if (setrlimit(RLIMIT_MEMLOCK, &none) != 0) return std::string("setrlimit failed");
    if (!drop_effective_capability(CAP_IPC_LOCK)) return std::string("capset failed");
    return "[" + lock_process_memory() + "]";
  });
  // No CAP_IPC_LOCK and a zero RLIMIT_MEMLOCK: mlockall(2) documents EPERM.
  EXPECT_EQ(text, "[Operation not permitted]");
}

}  // namespace
}  // namespace furuta::daemon
