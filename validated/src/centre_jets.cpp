// The Taylor coefficients at the centre and their Jacobian, with Grad<N> (see jets.hpp).

#include <algorithm>
#include <cstddef>
#include <utility>

#include "jets.hpp"

namespace furuta::validated::detail {
namespace {

template <std::size_t N>
void centre_coefficients_n(const Tape& tape, const std::vector<double>& m, int order,
                           std::vector<Interval>& values, std::vector<Interval>& jac) {
  std::vector<Grad<N>> x0;
  x0.reserve(N);
  for (std::size_t c = 0; c < N; ++c) x0.push_back(Grad<N>::variable(Interval(m[c]), c));
  TaylorRunner<Grad<N>> runner;
  runner.run(tape, std::span<const Grad<N>>(x0), order);
  const auto count = static_cast<std::size_t>(order) + 1;
  values.resize(count * N);
  jac.resize(count * N * N);
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t v = 0; v < N; ++v) {
      const Grad<N>& g = runner.coefficient(v, static_cast<int>(i));
      values[i * N + v] = g.v;
      std::copy(g.d.begin(), g.d.end(), jac.begin() + static_cast<std::ptrdiff_t>((i * N + v) * N));
    }
  }
}

template <std::size_t... Is>
void centre_dispatch(std::index_sequence<Is...>, const Tape& tape, const std::vector<double>& m,
                     int order, std::vector<Interval>& values, std::vector<Interval>& jac) {
  const std::size_t n = m.size();
  (void)((n == Is + 1 ? (centre_coefficients_n<Is + 1>(tape, m, order, values, jac), true)
                      : false) ||
         ...);
}

}  // namespace

void centre_coefficients(const Tape& tape, const std::vector<double>& m, int order,
                         std::vector<Interval>& values, std::vector<Interval>& jac) {
  centre_dispatch(std::make_index_sequence<kMaxDimension>{}, tape, m, order, values, jac);
}

}  // namespace furuta::validated::detail
