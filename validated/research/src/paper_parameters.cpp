#include "furuta/validated/research/paper_parameters.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace furuta::validated::research {

ParameterSet interval_parameters(std::string name, const model::Parameters<double>& mu_centre,
                                 const std::array<double, 5>& mu_percent,
                                 const interval::Interval& fv1, const interval::Interval& fv2) {
  for (const double pct : mu_percent) {
    if (!(pct >= 0.0) || !std::isfinite(pct)) {
      throw std::invalid_argument("interval parameters: the mu's percentages must be >= 0");
    }
  }
  if (fv1.is_empty() || !fv1.is_bounded() || fv2.is_empty() || !fv2.is_bounded()) {
    throw std::invalid_argument("interval parameters: fv1 and fv2 must be bounded, non-empty");
  }
  // Enclosed in interval arithmetic: centre * (1 +- pct / 100).
  const auto widen = [](double centre, double pct) {
    return interval::Interval(centre) *
           (interval::Interval(1.0) + interval::Interval(-pct, pct) / interval::Interval(100.0));
  };
  ParameterSet set;
  set.name = std::move(name);
  set.parameters.mu1 = widen(mu_centre.mu1, mu_percent[0]);
  set.parameters.mu2 = widen(mu_centre.mu2, mu_percent[1]);
  set.parameters.mu3 = widen(mu_centre.mu3, mu_percent[2]);
  set.parameters.mu4 = widen(mu_centre.mu4, mu_percent[3]);
  set.parameters.mug = widen(mu_centre.mug, mu_percent[4]);
  set.parameters.fv1 = fv1;
  set.parameters.fv2 = fv2;
  return set;
}

}  // namespace furuta::validated::research
