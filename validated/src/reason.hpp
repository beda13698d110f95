#pragma once
// Numbers in the integrator's failure reasons (internal to the validated integrator).

#include <sstream>
#include <string>

namespace furuta::validated::detail {

inline std::string describe(double value) {
  std::ostringstream out;
  out.precision(17);
  out << value;
  return out.str();
}

}  // namespace furuta::validated::detail
