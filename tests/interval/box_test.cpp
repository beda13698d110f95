// Boxes: construction, widths, bisection, hull and intersection, containment and empty boxes.
#include "furuta/interval/box.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace furuta::interval {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(Box, Construction) {
  EXPECT_EQ(Box().size(), 0U);
  const Box entire(3);
  EXPECT_EQ(entire.size(), 3U);
  for (const Interval& x : entire) EXPECT_TRUE(x.is_entire());
  const Box filled(2, Interval(1.0, 2.0));
  EXPECT_EQ(filled[1], Interval(1.0, 2.0));
  const Box listed{Interval(1.0, 2.0), Interval(3.0)};
  EXPECT_EQ(listed.size(), 2U);
  EXPECT_EQ(listed[1], Interval(3.0));
  const Box from_vector(std::vector<Interval>{Interval(0.0, 1.0)});
  EXPECT_EQ(from_vector.size(), 1U);
  Box mutable_box(2, Interval(0.0, 1.0));
  mutable_box[0] = Interval(5.0);
  EXPECT_EQ(mutable_box[0], Interval(5.0));
  EXPECT_EQ(mutable_box, (Box{Interval(5.0), Interval(0.0, 1.0)}));
  EXPECT_NE(mutable_box, filled);
}

TEST(Box, EmptyAsSoonAsOneComponentIs) {
  EXPECT_FALSE(Box().is_empty());
  Box b{Interval(1.0, 2.0), Interval(3.0, 4.0)};
  EXPECT_FALSE(b.is_empty());
  b[1] = Interval::empty();
  EXPECT_TRUE(b.is_empty());
  Box c{Interval(1.0, 2.0), Interval(3.0, 4.0)};
  c.set_empty();
  EXPECT_TRUE(c.is_empty());
  EXPECT_TRUE(c[0].is_empty());
  EXPECT_TRUE(c[1].is_empty());
  EXPECT_EQ(c.size(), 2U);
}

TEST(Box, Widths) {
  const Box b{Interval(0.0, 1.0), Interval(0.0, 5.0), Interval(2.0)};
  EXPECT_EQ(b.max_width(), 5.0);
  EXPECT_EQ(b.widest_index(), 1U);
  EXPECT_EQ(Box().max_width(), 0.0);
  EXPECT_EQ(Box{Interval(0.0, kInf)}.max_width(), kInf);
  // Ties: the first.
  EXPECT_EQ((Box{Interval(0.0, 2.0), Interval(1.0, 3.0)}).widest_index(), 0U);
}

TEST(Box, WidestRelativeIndex) {
  const Box b{Interval(0.0, 1.0), Interval(0.0, 5.0), Interval(0.0, 0.5)};
  EXPECT_EQ(b.widest_relative_index({1.0, 1.0, 1.0}), 1U);
  EXPECT_EQ(b.widest_relative_index({1.0, 100.0, 0.1}), 2U);  // 0.05 vs 5
  // Scale 0 never wins, however wide the component.
  EXPECT_EQ(b.widest_relative_index({1.0, 0.0, 1.0}), 0U);
  // All scales 0: the widest in absolute terms.
  EXPECT_EQ(b.widest_relative_index({0.0, 0.0, 0.0}), 1U);
  EXPECT_THROW(b.widest_relative_index({1.0}), std::invalid_argument);
}

TEST(Box, MidAndContains) {
  const Box b{Interval(0.0, 2.0), Interval(-4.0, -2.0)};
  EXPECT_EQ(b.mid(), (std::vector<double>{1.0, -3.0}));
  EXPECT_TRUE(b.contains({0.0, -2.0}));
  EXPECT_TRUE(b.contains({1.5, -3.5}));
  EXPECT_FALSE(b.contains({2.5, -3.0}));
  EXPECT_FALSE(b.contains({1.0}));  // wrong size
  Box e = b;
  e.set_empty();
  EXPECT_FALSE(e.contains({1.0, -3.0}));
}

TEST(Box, SubsetAndIntersects) {
  const Box outer{Interval(0.0, 10.0), Interval(0.0, 10.0)};
  const Box inner{Interval(1.0, 2.0), Interval(3.0, 4.0)};
  const Box apart{Interval(1.0, 2.0), Interval(11.0, 12.0)};
  EXPECT_TRUE(inner.is_subset(outer));
  EXPECT_FALSE(outer.is_subset(inner));
  EXPECT_TRUE(outer.is_subset(outer));
  EXPECT_FALSE(apart.is_subset(outer));
  EXPECT_TRUE(inner.intersects(outer));
  EXPECT_FALSE(apart.intersects(outer));
  Box empty = inner;
  empty.set_empty();
  EXPECT_TRUE(empty.is_subset(outer));
  EXPECT_FALSE(empty.intersects(outer));
  EXPECT_FALSE(Box(1).is_subset(outer));  // sizes differ
}

TEST(Box, BisectSplitsOneComponent) {
  const Box b{Interval(0.0, 4.0), Interval(10.0, 20.0)};
  const auto [lower, upper] = b.bisect(1);
  EXPECT_EQ(lower, (Box{Interval(0.0, 4.0), Interval(10.0, 15.0)}));
  EXPECT_EQ(upper, (Box{Interval(0.0, 4.0), Interval(15.0, 20.0)}));
  EXPECT_EQ(hull(lower, upper), b);
  const auto [l2, u2] = b.bisect(0, 0.25);
  EXPECT_EQ(l2[0], Interval(0.0, 1.0));
  EXPECT_EQ(u2[0], Interval(1.0, 4.0));
  EXPECT_EQ(l2[1], b[1]);
  EXPECT_THROW(b.bisect(2), std::out_of_range);
}

TEST(Box, HullAndIntersect) {
  const Box a{Interval(0.0, 1.0), Interval(0.0, 1.0)};
  const Box b{Interval(2.0, 3.0), Interval(0.5, 0.7)};
  EXPECT_EQ(hull(a, b), (Box{Interval(0.0, 3.0), Interval(0.0, 1.0)}));
  const Box i = intersect(a, b);
  EXPECT_TRUE(i.is_empty());
  EXPECT_TRUE(i[1].is_empty());  // the whole box is set empty
  const Box c{Interval(0.5, 3.0), Interval(-1.0, 0.5)};
  EXPECT_EQ(intersect(a, c), (Box{Interval(0.5, 1.0), Interval(0.0, 0.5)}));
  // Hull with an empty box ignores it (even its non-empty components).
  Box e{Interval(100.0, 200.0), Interval::empty()};
  EXPECT_EQ(hull(a, e), a);
  EXPECT_EQ(hull(e, a), a);
  EXPECT_THROW(hull(a, Box(3)), std::invalid_argument);
  EXPECT_THROW(intersect(a, Box(1)), std::invalid_argument);
}

TEST(Box, DifferenceTilesTheOuterBoxWithoutTheInner) {
  const Box outer{Interval(0, 4), Interval(-1, 1), Interval(2, 3)};
  const Box inner{Interval(1, 2), Interval(-1, 0.5), Interval(2.25, 2.75)};
  const std::vector<Box> pieces = difference(outer, inner);
  EXPECT_EQ(pieces.size(), 5u);  // below and above in components 0 and 2, above in 1
  const auto volume = [](const Box& b) {
    double v = 1;
    for (const Interval& x : b) v *= x.width();
    return v;
  };
  double total = volume(inner);
  for (const Box& b : pieces) {
    EXPECT_TRUE(b.is_subset(outer)) << b;
    total += volume(b);
  }
  EXPECT_DOUBLE_EQ(total, volume(outer));
  // Each point of the outer box lies in the inner box or a piece (interiors are disjoint).
  for (double x0 = 0.05; x0 < 4; x0 += 0.3) {
    for (double x1 = -0.95; x1 < 1; x1 += 0.3) {
      for (double x2 = 2.05; x2 < 3; x2 += 0.2) {
        const std::vector<double> x = {x0, x1, x2};
        int in = inner.contains(x) ? 1 : 0;
        for (const Box& b : pieces) in += b.contains(x) ? 1 : 0;
        EXPECT_GE(in, 1);
      }
    }
  }
  EXPECT_TRUE(difference(outer, outer).empty());
  EXPECT_EQ(difference(outer, Box(3, Interval::empty())), std::vector<Box>{outer});
  EXPECT_THROW(difference(outer, Box{Interval(0, 5), Interval(0, 1), Interval(2, 3)}),
               std::invalid_argument);
  EXPECT_THROW(difference(outer, Box{Interval(0, 1)}), std::invalid_argument);
}

TEST(Box, Prints) {
  std::ostringstream s;
  s << Box{Interval(1.0, 2.0), Interval::empty()};
  EXPECT_EQ(s.str(), "([1, 2], [empty])");
}

}  // namespace
}  // namespace furuta::interval
