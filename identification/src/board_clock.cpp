#include "furuta/identification/board_clock.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace furuta::identification {

namespace {

constexpr std::size_t kMinReadings = 16;
// Stretches whose least-delayed reading each pins the line: enough that the line's slope is set
// by points far apart, few enough that each stretch holds many readings to find its least delay.
constexpr std::size_t kStretches = 8;

struct Line {
  double offset = 0, slope = 0;
};

// Least squares of y on x (x not all equal).
Line least_squares(const std::vector<double>& x, const std::vector<double>& y) {
  const auto n = static_cast<double>(x.size());
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= n;
  my /= n;
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  const double slope = sxy / sxx;
  return {my - slope * mx, slope};
}

}  // namespace

std::optional<BoardClock> fit_board_clock(std::span<const double> host_s,
                                          std::span<const double> board, double max_delay_s) {
  const std::size_t n = host_s.size();
  if (n < kMinReadings || board.size() != n) return std::nullopt;
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(host_s[i]) || !std::isfinite(board[i])) return std::nullopt;
    if (i > 0 && !(board[i] > board[i - 1])) return std::nullopt;
  }
  // Times relative to the first reading: a board's counter and a host's monotonic clock can be
  // large numbers whose products would lose the sub-millisecond part.
  std::vector<double> x(n), y(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = board[i] - board[0];
    y[i] = host_s[i] - host_s[0];
  }
  // The rate from every reading (the delay's mean does not tilt it), then refined through each
  // stretch's least-delayed reading, whose delays lie closest to the least one.
  const Line all = least_squares(x, y);
  std::vector<double> low_x, low_y;
  for (std::size_t k = 0; k < kStretches; ++k) {
    const std::size_t begin = k * n / kStretches, end = (k + 1) * n / kStretches;
    std::size_t best = begin;
    for (std::size_t i = begin; i < end; ++i) {
      if (y[i] - all.slope * x[i] < y[best] - all.slope * x[best]) best = i;
    }
    low_x.push_back(x[best]);
    low_y.push_back(y[best]);
  }
  const double slope = least_squares(low_x, low_y).slope;
  if (!(slope > 0) || !std::isfinite(slope)) return std::nullopt;
  double offset = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) offset = std::min(offset, y[i] - slope * x[i]);

  BoardClock clock;
  clock.rate = slope;
  clock.offset_s = host_s[0] + offset - slope * board[0];
  clock.readings = n;
  std::vector<double> delays(n);
  for (std::size_t i = 0; i < n; ++i) {
    delays[i] = y[i] - slope * x[i] - offset;
    clock.host_delay_mean_s += delays[i];
    clock.host_delay_max_s = std::max(clock.host_delay_max_s, delays[i]);
  }
  clock.host_delay_mean_s /= static_cast<double>(n);
  // A few stamps far late are the scheduler's stalls, which the board's stamps are there to
  // remove; most of them far late is a board that does not keep time.
  const auto tenth = delays.begin() + static_cast<std::ptrdiff_t>(n * 9 / 10);
  std::nth_element(delays.begin(), tenth, delays.end());
  if (!(*tenth <= max_delay_s)) return std::nullopt;
  return clock;
}

}  // namespace furuta::identification
