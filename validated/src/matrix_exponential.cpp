#include "furuta/validated/matrix_exponential.hpp"

#include "interval_matrix.hpp"

namespace furuta::validated {

std::vector<interval::Interval> exp_enclosure(const Eigen::MatrixXd& a, interval::Interval t) {
  return detail::exp_enclosure(a, t).v;
}

}  // namespace furuta::validated
