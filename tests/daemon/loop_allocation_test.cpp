// The loop thread does not allocate after start-up: a counting scope opened on the loop thread
// itself (from a board link it calls every cycle) spans thousands of cycles — the rest check, the
// session's start, every cycle of it, its end, and idle cycles after — and must see no call to
// operator new or delete. The simulated rig runs on the same thread and keeps no truth record
// (that would allocate in the rig, not in the loop).
#include <gtest/gtest.h>

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "allocation_counter.hpp"
#include "daemon_test_support.hpp"
#include "furuta/control/upright_lqr.hpp"
#include "furuta/daemon/control_loop.hpp"
#include "furuta/daemon/rig_connection.hpp"

namespace furuta::daemon {
namespace {

using sim::RigBoard;

// Counts allocations on the loop thread from its second cycle until `idle_after_end` cycles after
// the session has ended, then asks the loop to exit. Calls `script` before each drain, with the
// number of running cycles so far and of cycles since the session ended (0 before), so a test can
// inject faults from the loop thread. Allocates nothing itself.
class CountingLink final : public BoardLink {
 public:
  CountingLink(BoardLink& inner, int idle_after_end)
      : inner_(inner), idle_after_end_(idle_after_end) {}
  // The loop this link serves (built after the link); before the loop thread starts.
  void attach(ControlLoop& loop) { loop_ = &loop; }

  std::function<void(int running_cycle, int idle_cycle)> script;

  bridge::TransportStatus drain(BoardReports& out) override {
    ++cycles_;
    const bool running = loop_->counters().state.load() == LoopState::running;
    if (running) {
      ++running_cycles_;
      ran_ = true;
    } else if (ran_) {
      ++idle_cycles_;
    }
    if (cycles_ == 2) counter_.emplace();
    if (counter_) ++counted_cycles_;
    if (script) script(running ? running_cycles_ : 0, idle_cycles_);
    if (counter_ && idle_cycles_ == idle_after_end_) {
      allocations_ = counter_->allocations();
      deallocations_ = counter_->deallocations();
      counter_.reset();
      closed_ = true;
      loop_->request_exit();
    }
    return inner_.drain(out);
  }
  bridge::TransportStatus write(std::span<const std::uint8_t> report) override {
    return inner_.write(report);
  }
  bridge::TransportStatus reconnect() override { return inner_.reconnect(); }
  const bridge::DeviceInfo& device_info() const noexcept override { return inner_.device_info(); }

  // Read after the loop thread has been joined.
  bool closed() const { return closed_; }
  std::size_t allocations() const { return allocations_; }
  std::size_t deallocations() const { return deallocations_; }
  int counted_cycles() const { return counted_cycles_; }
  int running_cycles() const { return running_cycles_; }

 private:
  BoardLink& inner_;
  ControlLoop* loop_ = nullptr;
  int idle_after_end_;
  int cycles_ = 0;
  int running_cycles_ = 0;
  int idle_cycles_ = 0;
  bool ran_ = false;
  std::optional<furuta::testing::ScopedAllocationCounter> counter_;
  int counted_cycles_ = 0;
  bool closed_ = false;
  std::size_t allocations_ = 0;
  std::size_t deallocations_ = 0;
};

// Takes the loop's events off its queue on another thread (allocating there is fine) and tallies
// what it saw.
class EventDrain {
 public:
  explicit EventDrain(EventQueue& events) : events_(events) {
    thread_ = std::thread([this] { run(); });
  }
  ~EventDrain() { stop(); }
  void stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  int samples = 0;
  int balanced = 0;  // samples whose controller cycle was in balance mode
  int sessions_started = 0;
  std::optional<StopReason> end_reason;
  std::map<std::string, int> faults;  // by `what`

 private:
  void run() {
    auto event = std::make_unique<LoopEvent>();
    for (;;) {
      bool any = false;
      while (events_.pop(*event)) {
        any = true;
        switch (event->kind) {
          case LoopEvent::Kind::sample:
            ++samples;
            if (event->sample.control.present &&
                event->sample.control.mode ==
                    static_cast<std::uint8_t>(control::BalanceMode::balance)) {
              ++balanced;
            }
            break;
          case LoopEvent::Kind::session_start:
            ++sessions_started;
            break;
          case LoopEvent::Kind::session_end:
            end_reason = event->end.reason;
            break;
          case LoopEvent::Kind::fault:
            ++faults[event->fault.what.data()];
            break;
        }
      }
      if (!any && stop_.load()) return;
      if (!any) std::this_thread::yield();
    }
  }
  EventQueue& events_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

struct LoopRig {
  config::RigConfig config = furuta::daemon::testing::quiet_rig();
  RigConnection io;
  LoopSettings settings;
  EventQueue events{256};

  explicit LoopRig(bool record_truth = false) {
    config.simulation.record_truth = record_truth;
    io = connect_rig(config, {BackendChoice::simulated, {}, /*virtual_time=*/true});
    settings = daemon_settings_from_config(config).loop;
    settings.wait_when_queue_full = true;
    settings.rest_wait_s = 1.5;  // the first session waits out the one-second rest check
  }

  SessionRequest request(const ExcitationSpec& spec) const {
    SessionRequest r;
    r.excitation = Excitation(spec);
    copy_text(r.session, "allocation");
    return r;
  }

  bridge::VirtualClock& clock() { return static_cast<bridge::VirtualClock&>(*io.clock); }
};

void expect_no_allocation(const CountingLink& link, int min_cycles) {
  ASSERT_TRUE(link.closed()) << "the counting scope never closed";
  EXPECT_GE(link.counted_cycles(), min_cycles);
  EXPECT_EQ(link.allocations(), 0u);
  EXPECT_EQ(link.deallocations(), 0u);
}

ExcitationSpec session_spec(const LoopRig& s, ProfileKind kind) {
  ExcitationSpec spec = excitation_from_config(s.config.excitation);
  spec.kind = kind;
  spec.amplitude_duty = 0.3;
  spec.duration_s = 50.0;  // 3125 cycles at 16 ms
  return spec;
}

// One session through a loop whose motor link counts, with an optional fault script.
struct CountedRun {
  CountingLink link;
  ControlLoop loop;
  EventDrain drain;

  CountedRun(LoopRig& s, int idle_after_end)
      : link(*s.io.motor_link, idle_after_end),
        loop(s.settings, link, *s.io.encoder_link, *s.io.clock, s.events),
        drain(s.events) {
    link.attach(loop);
  }
  void run() {
    std::thread thread([this] { loop.run(); });
    thread.join();
    drain.stop();
  }
};

TEST(LoopAllocation, BangBangSessionDoesNotAllocateOnTheLoopThread) {
  LoopRig s;
  ExcitationSpec spec = session_spec(s, ProfileKind::bang_bang);
  spec.switch_period_jitter = 0.3;  // the randomised period draws from the generator every switch
  CountedRun run(s, 50);
  ASSERT_TRUE(run.loop.request_session(s.request(spec)));
  run.run();
  expect_no_allocation(run.link, 3000);
  EXPECT_EQ(run.drain.end_reason, StopReason::duration_reached);
  EXPECT_EQ(run.drain.samples, 3125);
}

TEST(LoopAllocation, MultisineSessionDoesNotAllocateOnTheLoopThread) {
  LoopRig s;
  ExcitationSpec spec = session_spec(s, ProfileKind::multisine);
  spec.multisine_components = 16;
  // Nothing keeps a multisine's arm centred (the bang-bang has its thresholds); the arm limit is
  // not what this test is about.
  s.settings.safety.arm_limit_rad = 1e6;
  CountedRun run(s, 50);
  ASSERT_TRUE(run.loop.request_session(s.request(spec)));
  run.run();
  expect_no_allocation(run.link, 3000);
  EXPECT_EQ(run.drain.end_reason, StopReason::duration_reached);
  EXPECT_EQ(run.drain.samples, 3125);
}

TEST(LoopAllocation, BalanceSessionDoesNotAllocateOnTheLoopThread) {
  LoopRig s;
  ExcitationSpec spec = session_spec(s, ProfileKind::free_decay);
  SessionRequest request = s.request(spec);
  // The law as `furuta controller design` makes it, from the simulated rig's true parameters.
  const control::DesignPlant plant{s.config.simulation.parameters, s.config.motor,
                                   s.config.simulation.supply_voltage_v};
  const control::SampledPlant sampled =
      control::sample(control::linearize_upright(plant), 0.016, 0.002);
  request.balance = true;
  control::ObserverWeights filter;
  filter.arm_count_rad = bridge::resolution_rad(s.config.arm_encoder);
  filter.pendulum_count_rad = bridge::resolution_rad(s.config.pendulum_encoder);
  request.balance_law = control::BalanceLaw(control::balance_spec(
      plant, sampled, control::design_lqr(sampled, control::LqrWeights{}),
      control::design_observer(sampled, filter), control::DutyPath{0.002, 62.5}, 0.5, 1.0 / 255));
  CountedRun run(s, 50);
  ASSERT_TRUE(run.loop.request_session(request));
  run.run();
  expect_no_allocation(run.link, 3000);
  EXPECT_EQ(run.drain.end_reason, StopReason::duration_reached);
  EXPECT_EQ(run.drain.samples, 3125);
  // Swung up, caught and held: the swing-up, the catch and the balance all ran in the scope.
  EXPECT_GT(run.drain.balanced, 2500);
}

// The scope is not vacuous: with the simulated rig recording its truth (a vector that grows on the
// thread that drives the rig, the loop thread) it counts.
TEST(LoopAllocation, TheScopeSeesAllocationsMadeOnTheLoopThread) {
  LoopRig s(/*record_truth=*/true);
  ExcitationSpec spec = session_spec(s, ProfileKind::bang_bang);
  spec.duration_s = 5.0;
  CountedRun run(s, 10);
  ASSERT_TRUE(run.loop.request_session(s.request(spec)));
  run.run();
  ASSERT_TRUE(run.link.closed());
  EXPECT_GT(run.link.allocations(), 0u);
}

// The paths a session takes when things go wrong allocate no more than the happy one: lost,
// corrupt and short reports, missed cycles, a fatal fault, an e-stop while idle, and a start that
// is refused because the pendulum still swings.
TEST(LoopAllocation, FaultsAndRefusalsDoNotAllocateOnTheLoopThread) {
  LoopRig s;
  ExcitationSpec spec = session_spec(s, ProfileKind::bang_bang);
  const SessionRequest second = s.request(spec);  // built here: constructing one allocates
  CountedRun run(s, 200);
  sim::SimulatedRig& rig = *s.io.simulated_rig;
  bridge::VirtualClock& clock = s.clock();
  const std::int64_t period = s.settings.period_ns;
  ControlLoop& loop = run.loop;
  bool second_queued = false;
  run.link.script = [&](int running_cycle, int idle_cycle) {
    switch (running_cycle) {
      case 300:
        rig.drop_reports(RigBoard::motor_1065, 3);
        rig.drop_reports(RigBoard::encoder_1047, 2);
        break;
      case 600:
        rig.corrupt_reports(RigBoard::motor_1065, 2);
        break;
      case 900:
        rig.truncate_reports(RigBoard::encoder_1047, 2, 10);
        break;
      case 1200:
        clock.advance_ns(5 * period);  // the loop wakes five periods late
        break;
      case 1500:
        rig.stall(RigBoard::motor_1065, 1'000'000'000);  // ends the session: stale reports
        break;
      default:
        break;
    }
    if (idle_cycle == 10) loop.request_stop(StopReason::estop_command);
    if (idle_cycle == 20 && !second_queued) second_queued = loop.request_session(second);
  };
  ASSERT_TRUE(loop.request_session(s.request(spec)));
  run.run();
  expect_no_allocation(run.link, 1500);
  EXPECT_TRUE(second_queued);
  EXPECT_EQ(run.drain.end_reason, StopReason::stale_motor_reports);
  EXPECT_EQ(run.drain.sessions_started, 1);
  EXPECT_GE(run.drain.faults["lost_reports"], 1);
  EXPECT_EQ(run.drain.faults["overrun"], 1);
  EXPECT_EQ(run.drain.faults["stale_motor_reports"], 1);
  EXPECT_EQ(run.drain.faults["start_refused"], 1);
}

}  // namespace
}  // namespace furuta::daemon
