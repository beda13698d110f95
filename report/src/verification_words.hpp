#pragma once
// The verification's failure kinds as verification.json names them and as the page and the
// figure say them, in one place so that the three agree.

#include <string>

#include "furuta/verification/balance_certificate.hpp"

namespace furuta::report {

// verification.json's "kind": "pendulum_limit", "arm_limit", "duty_limit", "law_mode",
// "no_enclosure".
inline std::string failure_kind_code(verification::FailureKind kind) {
  switch (kind) {
    case verification::FailureKind::pendulum_limit:
      return "pendulum_limit";
    case verification::FailureKind::arm_limit:
      return "arm_limit";
    case verification::FailureKind::duty_limit:
      return "duty_limit";
    case verification::FailureKind::law_mode:
      return "law_mode";
    case verification::FailureKind::no_enclosure:
      return "no_enclosure";
  }
  return "unknown";
}

// The kind as a short phrase for a figure's label: "pendulum limit".
inline std::string failure_kind_label(verification::FailureKind kind) {
  std::string label = failure_kind_code(kind);
  for (char& c : label) c = c == '_' ? ' ' : c;
  return label;
}

// Failure::value and Failure::limit are radians for every kind but the duty's, which has no unit:
// the page and the figure show the angles in degrees.
inline bool failure_is_angle(verification::FailureKind kind) {
  return kind != verification::FailureKind::duty_limit;
}

}  // namespace furuta::report
