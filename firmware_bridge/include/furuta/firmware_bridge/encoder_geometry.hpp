#pragma once
// From encoder counts to joint angles, and back.

#include <cstdint>

namespace furuta::bridge {

struct EncoderGeometry {
  double counts_per_rev = 0.0;   // counts per revolution of the encoder's own shaft (calibrated)
  double gear_ratio = 1.0;       // encoder-shaft revolutions per joint revolution
  int sign = 1;                  // +1 or -1
  double zero_offset_rad = 0.0;  // joint angle subtracted after scaling

  double counts_per_joint_rev() const { return counts_per_rev * gear_ratio; }
  bool operator==(const EncoderGeometry&) const = default;
};

// sign * 2 pi * counts / (counts_per_rev * gear_ratio) - zero_offset_rad
double counts_to_rad(const EncoderGeometry& geometry, std::int64_t counts);
// The count an ideal encoder shows at `angle_rad`: floor of the inverse, so quantisation is
// one-sided as on a real incremental encoder.
std::int64_t rad_to_counts(const EncoderGeometry& geometry, double angle_rad);
// Size of one count in joint radians.
double resolution_rad(const EncoderGeometry& geometry);

}  // namespace furuta::bridge
