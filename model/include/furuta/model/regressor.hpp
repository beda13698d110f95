#pragma once
// The model is linear in its parameters (paper eq. 5, docs/model.md): y = [tau, 0] = D(q, dq, ddq)
// p.

#include "furuta/model/parameters.hpp"

namespace furuta::model {

// The two rows of D at one sample: the coefficient of each parameter, in p's order.
struct RegressorRows {
  Parameters<double> row1{}, row2{};
};
RegressorRows regressor(double q2, double dq1, double dq2, double ddq1, double ddq2);

}  // namespace furuta::model
