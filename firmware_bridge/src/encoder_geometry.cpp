#include "furuta/firmware_bridge/encoder_geometry.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace furuta::bridge {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Angle -> counts -> angle loses a few ulps (the zero offset is added and subtracted), which would
// put an exact count a hair below its integer and floor it one count low. This slack, far below any
// physical meaning, keeps rad_to_counts(counts_to_rad(n)) == n.
constexpr double kRelativeSlack = 1e-12;

}  // namespace

double counts_to_rad(const EncoderGeometry& geometry, std::int64_t counts) {
  return geometry.sign * kTwoPi * static_cast<double>(counts) / geometry.counts_per_joint_rev() -
         geometry.zero_offset_rad;
}

// Quantisation follows the encoder's own direction of counting, whatever `sign` is: the encoder
// shows count n while its shaft is in [n, n + 1) of its own counts, so the result is floor() of the
// count position. With sign +1 that means counts_to_rad(rad_to_counts(a)) <= a < it + resolution;
// with sign -1 the joint angle runs against the count, and the bound flips:
// counts_to_rad(rad_to_counts(a)) - resolution < a <= counts_to_rad(rad_to_counts(a)).
// (Flooring in the joint's direction instead would model an encoder that counts differently
// depending on how it is mounted, which none does.)
std::int64_t rad_to_counts(const EncoderGeometry& geometry, double angle_rad) {
  const double per_rad = geometry.counts_per_joint_rev() / kTwoPi;
  const double position = geometry.sign * (angle_rad + geometry.zero_offset_rad) * per_rad;
  if (std::isnan(position)) return 0;  // a broken geometry; no exceptions on this path
  const double slack =
      kRelativeSlack * (1.0 + std::fabs(position) + std::fabs(geometry.zero_offset_rad * per_rad));
  const double counts = std::floor(position + slack);
  // Saturate rather than invoke undefined behaviour on an out-of-range conversion.
  constexpr double kLimit = 9.2e18;  // just inside the int64 range
  if (counts >= kLimit) return std::numeric_limits<std::int64_t>::max();
  if (counts <= -kLimit) return std::numeric_limits<std::int64_t>::min();
  return static_cast<std::int64_t>(counts);
}

double resolution_rad(const EncoderGeometry& geometry) {
  return kTwoPi / geometry.counts_per_joint_rev();
}

}  // namespace furuta::bridge
