#pragma once
// The verifier's run of the loop from a start or from a box of the loop's whole state (internal):
// verify_balance is the former; verify_balance_split hands its pieces over to one run of the
// latter once their transients are over.

#include <array>
#include <cstddef>
#include <variant>
#include <vector>

#include "furuta/verification/balance_certificate.hpp"

namespace furuta::verification::detail {

// The loop's state at a sample in the coordinates in which it contracts each direction on its
// own: the plant's [q1, q2 - pi, p1, p2]; the filter's estimate less the plant's (its angles, and
// its rates against the linearisation's, inverse p); the duty sent at the sample before; the duty
// on its way less the law's unrounded value of it; the board's and the law's applied duty less
// the duty sent before.
using LoopStateBox = std::array<Interval, 12>;

struct LoopRun {
  BalanceCertificate certificate;
  // The state after each of the checkpoints' periods that was proven, in their order.
  std::vector<LoopStateBox> at_checkpoints;
};

// checkpoints: numbers of periods from the start, increasing.
LoopRun run_loop(const control::BalanceControllerSpec& law, const LoopModel& loop,
                 const std::variant<LoopStart, LoopStateBox>& from, const LoopLimits& limits,
                 const VerifyOptions& options, const std::vector<std::size_t>& checkpoints = {});

}  // namespace furuta::verification::detail
