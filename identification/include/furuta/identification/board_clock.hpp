#pragma once
// Readings stamped twice: by the host when it received them (late by the USB and scheduler delay,
// which varies from one reading to the next) and by the board on its own clock (steady, but with
// its own origin and rate). The board's times mapped onto the host clock keep the host's origin and
// lose the varying delay.

#include <cstddef>
#include <optional>
#include <span>

namespace furuta::identification {

// host ~ offset_s + rate * board: the line under every (board, host) pair that the least-delayed
// receptions lie on. `rate` converts the board's unit to seconds (a report counter's period, a
// tick's length) and absorbs the two clocks' drift.
struct BoardClock {
  double offset_s = 0;
  double rate = 1;
  // How far the host's stamps lie above the line: their mean and largest [s] (the varying part of
  // the delay that the board's stamps remove; the least delay stays in both).
  double host_delay_mean_s = 0;
  double host_delay_max_s = 0;
  std::size_t readings = 0;
  double host_time(double board) const { return offset_s + rate * board; }
};

// The `max_delay_s` the refinement's readers pass: one report period of a slow board (8 ms); a
// board clock whose line leaves most host stamps later than that is not keeping time.
inline constexpr double kBoardClockMaxDelay_s = 8e-3;

// The line from the least-delayed receptions: the smallest host - rate * board in each of a few
// stretches of board time, a straight line through them by least squares, moved down until no
// reading lies below it. Nothing when there are fewer than 16 readings, the board's times do not
// increase, or more than a tenth of the host's stamps lie further than `max_delay_s` above the line
// (the board does not keep time: its stamps are not to be trusted over the host's; a few stamps
// far late are the host's stalls, which is what the board's stamps remove).
std::optional<BoardClock> fit_board_clock(std::span<const double> host_s,
                                          std::span<const double> board, double max_delay_s);

}  // namespace furuta::identification
