#pragma once
// The paper's interval parameter set for the scenarios (scenarios.hpp), built from Table II's
// percentages. The product's sets come from its own identification (pipeline/).

#include <array>
#include <string>

#include "furuta/interval/interval.hpp"
#include "furuta/model/model.hpp"
#include "furuta/validated/scenarios.hpp"

namespace furuta::validated::research {

// The paper's interval parameters: the mu's as mu_centre +- percent (Table II: 12, 12, 10, 12, 15
// for mu1, mu2, mu3, mu4, mug), the frictions as given (SIVIA's outer hull).
// std::invalid_argument for a negative or non-finite percentage, or an empty or unbounded friction.
ParameterSet interval_parameters(std::string name, const model::Parameters<double>& mu_centre,
                                 const std::array<double, 5>& mu_percent,
                                 const interval::Interval& fv1, const interval::Interval& fv2);

}  // namespace furuta::validated::research
