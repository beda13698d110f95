#pragma once
// The figures' axes: tick positions at nice numbers (1, 2 or 5 times a power of ten) and their
// labels, and the SVG of a plot's frame, grid, ticks and axis names. Every figure (Fig. 2/3/5,
// Fig. 4, Fig. 6) draws its axes with this, so they read alike.
//
//   const Ticks y = nice_ticks(80, 328, 4, true);   // 50, 100, ..., 350: the range grows to them
//   const Ticks t = nice_ticks(0, 6.0, 5);          // 0, 1, ..., 6 s

#include <string>
#include <vector>

namespace furuta::report {

struct Ticks {
  double lo = 0, hi = 1;  // the range the axis shows (grown to the outer ticks when asked)
  double step = 1;
  std::vector<double> values;  // lo <= v <= hi, every step apart
};

// Ticks over [lo, hi]: the largest nice step that still gives at least `min_count` of them (so
// never more than about 2.5 times that many). `grow` widens the range to the ticks just outside
// it (a y axis: the data fill the plot between labelled lines); otherwise the range stays and the
// ticks fall inside it (a time axis). A zero or non-finite range is widened around its value
// (0 +- 1 for nothing finite), so a figure of a constant still has an axis.
Ticks nice_ticks(double lo, double hi, int min_count = 4, bool grow = false);

// A tick's label: as many decimals as the step needs and no more ("0.05", "150", "0"), scientific
// notation for the very large and very small ("2.5e-05").
std::string tick_label(double value, double step);

// Where a plot sits in the SVG (its frame), in user units.
struct PlotArea {
  double x = 0, y = 0, width = 0, height = 0;
};

// The frame, the grid lines and tick labels of both axes, and their names (`x_name` under the
// plot, `y_name` turned along its left side). Marked for readers and tests: each axis is a
// <g class="axis x|y" data-ticks="n"> holding its <text class="tick"> labels and its
// <text class="axis-label">. A y axis with neither ticks nor a name is left out (a figure whose
// rows are categories names them itself).
std::string svg_axes(const PlotArea& area, const Ticks& x, const Ticks& y,
                     const std::string& x_name, const std::string& y_name);

}  // namespace furuta::report
