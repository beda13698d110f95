// The balance law's spec check: each member out of range is refused by a BalanceSpecError naming
// it by its path in the spec, so a file's reader can point at the key it came from.
#include "furuta/control/balance_law.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace furuta::control::balance_law_test {
namespace {

// A spec the law accepts: the defaults with a model and a drive.
BalanceControllerSpec valid_spec() {
  BalanceControllerSpec s;
  s.parameters = {
      .mu1 = 4e-3, .mu2 = 1e-3, .mu3 = 2e-3, .mu4 = 1.5e-3, .mug = 0.1, .fv1 = 1e-3, .fv2 = 1e-5};
  s.gain = {-1, 30, -1.5, 3, 0.2};
  s.delayed = 1;
  s.duty_torque_nm = 0.5;
  s.back_emf_nm_s = 0.05;
  return s;
}

TEST(BalanceLaw, EachFieldOutOfRangeIsNamedByItsPathInTheSpec) {
  EXPECT_NO_THROW(BalanceLaw{valid_spec()});
  const std::vector<std::pair<std::string, std::function<void(BalanceControllerSpec&)>>> cases = {
      {"period_s", [](auto& s) { s.period_s = 0; }},
      {"delayed", [](auto& s) { s.delayed = kMaxDelayedDuties + 1; }},
      {"gain", [](auto& s) { s.gain[6] = 1; }},
      {"max_duty", [](auto& s) { s.max_duty = 1.5; }},
      {"duty_step", [](auto& s) { s.duty_step = 0; }},
      {"parameters.mu4", [](auto& s) { s.parameters.mu4 = -1; }},
      {"parameters.fv2", [](auto& s) { s.parameters.fv2 = -1; }},
      {"duty_torque_nm", [](auto& s) { s.duty_torque_nm = 0; }},
      {"back_emf_nm_s", [](auto& s) { s.back_emf_nm_s = -1; }},
      {"swing_up.energy_gain", [](auto& s) { s.swing_up.energy_gain = -1; }},
      {"swing_up.start_acceleration",
       [](auto& s) { s.swing_up.start_acceleration = 2 * s.swing_up.max_acceleration; }},
      {"swing_up.max_duty", [](auto& s) { s.swing_up.max_duty = s.max_duty + 0.1; }},
      {"region.catch_rad", [](auto& s) { s.region.catch_rad = std::numbers::pi; }},
      {"region.release_rad", [](auto& s) { s.region.release_rad = s.region.catch_rad; }},
      {"region.settle_s", [](auto& s) { s.region.settle_s = -1; }},
      {"region.fall_rad", [](auto& s) { s.region.fall_rad = 0.5 * s.region.catch_rad; }},
  };
  for (const auto& [field, spoil] : cases) {
    BalanceControllerSpec s = valid_spec();
    spoil(s);
    try {
      BalanceLaw law(s);
      ADD_FAILURE() << field << " accepted";
    } catch (const BalanceSpecError& e) {
      EXPECT_EQ(e.field(), field);
      EXPECT_EQ(std::string(e.what()), "balance controller: " + field + " " + e.rule());
      EXPECT_FALSE(e.rule().empty());
    }
  }
}

}  // namespace
}  // namespace furuta::control::balance_law_test
