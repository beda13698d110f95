#pragma once
// A balance session's figures as `furuta run` and `furuta log info` print them.
#include <iomanip>
#include <sstream>
#include <string>

#include "furuta/pipeline/balance.hpp"

namespace furuta::app {

inline std::string balance_text(const pipeline::BalanceSummary& b) {
  std::ostringstream t;
  t << std::fixed << std::setprecision(2);
  t << "  balance   ";
  if (b.caught_at_s) {
    t << "caught at " << *b.caught_at_s << " s, balanced " << b.balanced_s << " s, upright RMS "
      << std::setprecision(3) << b.upright_rms_deg << " deg (max " << b.upright_max_deg
      << " deg), duty RMS " << b.duty_rms;
  } else {
    t << "never caught";
  }
  t << std::setprecision(1) << "; arm within +-" << b.max_abs_arm_deg
    << " deg, |duty| <= " << std::setprecision(3) << b.max_abs_duty << (b.fell ? "; FELL" : "")
    << "\n";
  t << "  law       " << b.cycles << " cycles, " << b.law_time_p50_ns << " ns median, "
    << b.law_time_max_ns << " ns max\n";
  return t.str();
}

}  // namespace furuta::app
