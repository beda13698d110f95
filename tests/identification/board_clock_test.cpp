// fit_board_clock: the board's stamps mapped onto the host clock through the least-delayed
// receptions.
#include "furuta/identification/board_clock.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace furuta::identification {
namespace {

struct Stamps {
  std::vector<double> host_s, board, true_host_s;
};

// Readings every 8 ms of board time on a counter (one unit per reading), received after a delay
// of 0.3 ms plus up to `jitter_s`; the board's clock runs 50 ppm fast; now and then the host
// stalls for `stall_s`.
Stamps stamps(std::size_t n, double jitter_s, double stall_s, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> delay(0.0, jitter_s);
  Stamps s;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = 100.0 + 0.008 * static_cast<double>(i) * (1 + 50e-6);
    s.board.push_back(static_cast<double>(i) + 7.0);
    s.true_host_s.push_back(t + 0.3e-3);
    s.host_s.push_back(t + 0.3e-3 + delay(rng) + (i % 97 == 50 ? stall_s : 0.0));
  }
  return s;
}

TEST(BoardClock, TheBoardsStampsRemoveTheVaryingDelayOfTheHosts) {
  const Stamps s = stamps(1250, 1e-3, 20e-3, 1);
  const auto clock = fit_board_clock(s.host_s, s.board, 8e-3);
  ASSERT_TRUE(clock.has_value());
  EXPECT_NEAR(clock->rate, 0.008 * (1 + 50e-6), 1e-8);
  double worst = 0;
  for (std::size_t i = 0; i < s.board.size(); ++i) {
    worst = std::max(worst, std::abs(clock->host_time(s.board[i]) - s.true_host_s[i]));
  }
  // The least delay is found to a small part of the jitter, everywhere in the session.
  EXPECT_LT(worst, 30e-6);
  EXPECT_NEAR(clock->host_delay_mean_s, 0.5e-3 + 12 * 20e-3 / 1250, 0.1e-3);
  EXPECT_NEAR(clock->host_delay_max_s, 20e-3, 1.1e-3);  // the stalls
  EXPECT_EQ(clock->readings, 1250u);
}

TEST(BoardClock, ABoardThatDoesNotKeepTimeOrTooFewReadingsGiveNothing) {
  Stamps s = stamps(400, 1e-3, 0.0, 2);
  // The board's counter restarts half way: its stamps no longer increase.
  for (std::size_t i = 200; i < s.board.size(); ++i) s.board[i] -= 150;
  EXPECT_FALSE(fit_board_clock(s.host_s, s.board, 8e-3).has_value());
  // A board whose every other stamp is 3.6 ms off against a steady host: half the host's stamps
  // would be 3.6 ms late.
  Stamps irregular = stamps(400, 0.0, 0.0, 3);
  for (std::size_t i = 1; i < irregular.board.size(); i += 2) irregular.board[i] += 0.45;
  ASSERT_TRUE(fit_board_clock(irregular.host_s, irregular.board, 4e-3).has_value());
  EXPECT_FALSE(fit_board_clock(irregular.host_s, irregular.board, 2e-3).has_value());
  const Stamps few = stamps(15, 1e-3, 0.0, 4);
  EXPECT_FALSE(fit_board_clock(few.host_s, few.board, 8e-3).has_value());
}

}  // namespace
}  // namespace furuta::identification
