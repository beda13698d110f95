// The second-order term of the Taylor coefficients over the set, with Jet2<N> and QuadJet<N> (see
// jets.hpp).

#include <algorithm>
#include <cstddef>
#include <iterator>
#include <utility>

#include "jets.hpp"

namespace furuta::validated::detail {
namespace {

// The second-order term over the set m + C r0 + B r inside the box y: second[i n + v] = half the
// second derivative of x_[i]_v along delta = C rho + e (rho in r0, e in B r) over y, i = 0..order.
// The jets' x0: y over the box, the direction's linear form (row v of c) in rho, e = br.
template <class Jet, std::size_t N>
std::vector<Jet> direction_jets(const Box& y, const Matrix& c, const std::vector<Interval>& r0,
                                const std::vector<Interval>& br) {
  std::vector<Jet> x0(N);
  for (std::size_t v = 0; v < N; ++v) {
    x0[v] = Jet(y[v]);
    for (std::size_t a = 0; a < N; ++a) {
      x0[v].g[a] = Interval(c(static_cast<Eigen::Index>(v), static_cast<Eigen::Index>(a)));
    }
    x0[v].e = br[v];
    x0[v].rho = r0.data();
    x0[v].changed();
  }
  return x0;
}

// The second-order term over the set inside the box y: second[i n + v] = half the second
// derivative of x_[i]_v along delta = C rho + e (rho in r0, e in the interval vector `e`) over y,
// i = 0..order. Both jets enclose the same quantity: the low orders (0..quadratic_order), where
// the terms are largest, from the quadratic forms (tight, several times Jet2's cost), the
// others from Jet2. With `forms` (not null) the low orders also give their quadratic form in rho:
// forms[(i n + v) P + pair] (interval coefficients over y, P = n (n + 1) / 2 pairs a <= b) and
// d2e[i n + v] (the terms with e), so that second = forms(rho) + d2e; the other orders have a
// zero form and d2e = second.
template <std::size_t N>
void second_order_n(const Tape& tape, const Box& y, const Matrix& c,
                    const std::vector<Interval>& r0, const std::vector<Interval>& e, int order,
                    int quadratic_order, bool quadratic_part, std::vector<Interval>& second,
                    std::vector<Interval>* forms, std::vector<Interval>* d2e) {
  constexpr std::size_t kPairs = QuadJet<N>::kPairs;
  const auto count = static_cast<std::size_t>(order) + 1;
  second.resize(count * N);
  if (forms != nullptr) {
    forms->assign(count * N * kPairs, Interval(0.0));
    d2e->assign(count * N, Interval(0.0));
  }
  const int low = std::min(order, quadratic_order);
  if (low < order) {
    const std::vector<Jet2<N>> x0 = direction_jets<Jet2<N>, N>(y, c, r0, e);
    TaylorRunner<Jet2<N>> runner;
    runner.run(tape, std::span<const Jet2<N>>(x0), order);
    for (std::size_t i = static_cast<std::size_t>(low) + 1; i < count; ++i) {
      for (std::size_t v = 0; v < N; ++v) {
        second[i * N + v] = runner.coefficient(v, static_cast<int>(i)).d2;
        if (d2e != nullptr) (*d2e)[i * N + v] = second[i * N + v];
      }
    }
  }
  if (low >= 0 && quadratic_part) {
    const std::vector<QuadJet<N>> x0 = direction_jets<QuadJet<N>, N>(y, c, r0, e);
    TaylorRunner<QuadJet<N>> runner;
    runner.run(tape, std::span<const QuadJet<N>>(x0), low);
    for (std::size_t i = 0; i <= static_cast<std::size_t>(low); ++i) {
      for (std::size_t v = 0; v < N; ++v) {
        const QuadJet<N>& jet = runner.coefficient(v, static_cast<int>(i));
        second[i * N + v] = jet.range();
        if (forms != nullptr) {
          if (jet.rho != nullptr) {
            std::copy(jet.q.begin(), jet.q.end(),
                      forms->begin() + static_cast<std::ptrdiff_t>((i * N + v) * kPairs));
            (*d2e)[i * N + v] = jet.d2e;
          } else {
            (*d2e)[i * N + v] = second[i * N + v];  // range() is d2e alone then
          }
        }
      }
    }
  }
}

template <std::size_t... Is>
void second_order_dispatch(std::index_sequence<Is...>, const Tape& tape, const Box& y,
                           const Matrix& c, const std::vector<Interval>& r0,
                           const std::vector<Interval>& e, int order, int quadratic_order,
                           bool quadratic_part, std::vector<Interval>& second,
                           std::vector<Interval>* forms, std::vector<Interval>* d2e) {
  const std::size_t n = y.size();
  (void)((n == Is + 1 ? (second_order_n<Is + 1>(tape, y, c, r0, e, order, quadratic_order,
                                                quadratic_part, second, forms, d2e),
                         true)
                      : false) ||
         ...);
}

}  // namespace

void second_order_coefficients(const Tape& tape, const Box& y, const Matrix& c,
                               const std::vector<Interval>& r0, const std::vector<Interval>& e,
                               int order, int quadratic_order, std::vector<Interval>& second,
                               std::vector<Interval>* forms, std::vector<Interval>* d2e,
                               bool quadratic_part) {
  second_order_dispatch(std::make_index_sequence<kMaxDimension>{}, tape, y, c, r0, e, order,
                        quadratic_order, quadratic_part, second, forms, d2e);
}

namespace {

// The orders 0..quadratic_order with the error part's live coordinates r_L in the jets' linear
// form too: the direction is delta = C rho + B r + e (e: the interval vector P(r0)), the QuadJet
// runs on the coordinates (rho (all n), r_l for l in `live`), padded with zero coordinates up to
// M, so that the products of first-order terms with B r are kept as a form too (the field's large
// terms cancel in them as in the rho terms). B's columns outside `live` must meet r entries that
// are exactly 0 (the constant components: parameters carried as state). forms (sized by the caller
// as second_order_n): the rho-rho block; d2e: the jets' d2e plus the range of the blocks with r
// over (r0, r).
template <std::size_t M>
void second_order_extended_m(const Tape& tape, const Box& y, const Matrix& c, const Matrix& b,
                             const std::vector<std::size_t>& live, const std::vector<Interval>& r0,
                             const std::vector<Interval>& r,
                             const std::vector<Interval>& e_quadratic, int quadratic_order,
                             std::vector<Interval>& second, std::vector<Interval>& forms,
                             std::vector<Interval>& d2e) {
  const std::size_t n = y.size();
  const std::size_t kPairs = n * (n + 1) / 2;
  const std::size_t used = n + live.size();
  std::vector<Interval> coordinates(M, Interval(0.0));
  std::copy(r0.begin(), r0.end(), coordinates.begin());
  for (std::size_t l = 0; l < live.size(); ++l) coordinates[n + l] = r[live[l]];
  std::vector<QuadJet<M>> x0(n);
  for (std::size_t v = 0; v < n; ++v) {
    const auto ev = static_cast<Eigen::Index>(v);
    x0[v] = QuadJet<M>(y[v]);
    for (std::size_t a = 0; a < n; ++a) x0[v].g[a] = Interval(c(ev, static_cast<Eigen::Index>(a)));
    for (std::size_t l = 0; l < live.size(); ++l) {
      x0[v].g[n + l] = Interval(b(ev, static_cast<Eigen::Index>(live[l])));
    }
    x0[v].e = e_quadratic[v];
    x0[v].rho = coordinates.data();
    x0[v].changed();
  }
  TaylorRunner<QuadJet<M>> runner;
  runner.run(tape, std::span<const QuadJet<M>>(x0), quadratic_order);
  for (std::size_t i = 0; i <= static_cast<std::size_t>(quadratic_order); ++i) {
    for (std::size_t v = 0; v < n; ++v) {
      const QuadJet<M>& jet = runner.coefficient(v, static_cast<int>(i));
      second[i * n + v] = jet.range();
      if (jet.rho == nullptr) {
        d2e[i * n + v] = second[i * n + v];
        continue;
      }
      Interval rest = jet.d2e;
      std::size_t k = 0;
      std::size_t kk = 0;
      for (std::size_t a = 0; a < M; ++a) {
        for (std::size_t bb = a; bb < M; ++bb, ++k) {
          if (bb < n) {
            forms[(i * n + v) * kPairs + kk++] = jet.q[k];
          } else if (bb >= used) {
            continue;  // padding: zero coordinates
          } else if (a == bb) {
            rest += jet.q[k] * sqr(coordinates[a]);
          } else {
            rest += jet.q[k] * (coordinates[a] * coordinates[bb]);
          }
        }
      }
      d2e[i * n + v] = rest;
    }
  }
}

// The jets over (rho, r_L) run for n + |L| coordinates up to this, padded to the next of
// kExtendedSizes (each size is an instantiation of the QuadJet runner, whose cost per operation
// grows with its pairs: QuadJet<15> has 120, QuadJet<8> 36). 15 = the Furuta model with its seven
// parameters carried as state (11 coordinates of rho, 4 of r).
constexpr std::size_t kExtendedSizes[] = {2, 4, 6, 8, 10, 12, 15};
static_assert(kExtendedSizes[std::size(kExtendedSizes) - 1] == kMaxExtended);

template <std::size_t... Is>
void second_order_extended_dispatch(std::index_sequence<Is...>, std::size_t size, const Tape& tape,
                                    const Box& y, const Matrix& c, const Matrix& b,
                                    const std::vector<std::size_t>& live,
                                    const std::vector<Interval>& r0, const std::vector<Interval>& r,
                                    const std::vector<Interval>& e_quadratic, int quadratic_order,
                                    std::vector<Interval>& second, std::vector<Interval>& forms,
                                    std::vector<Interval>& d2e) {
  (void)((size <= kExtendedSizes[Is]
              ? (second_order_extended_m<kExtendedSizes[Is]>(
                     tape, y, c, b, live, r0, r, e_quadratic, quadratic_order, second, forms, d2e),
                 true)
              : false) ||
         ...);
}

}  // namespace

void second_order_extended(const Tape& tape, const Box& y, const Matrix& c, const Matrix& b,
                           const std::vector<std::size_t>& live, const std::vector<Interval>& r0,
                           const std::vector<Interval>& r, const std::vector<Interval>& e_quadratic,
                           const std::vector<Interval>& e_all, int order, int quadratic_order,
                           std::vector<Interval>& second, std::vector<Interval>& forms,
                           std::vector<Interval>& d2e) {
  // The orders above quadratic_order from Jet2 (and the sizes of forms and d2e).
  second_order_coefficients(tape, y, c, r0, e_all, order, quadratic_order, second, &forms, &d2e,
                            false);
  const int low = std::min(order, quadratic_order);
  if (low < 0) return;
  second_order_extended_dispatch(std::make_index_sequence<std::size(kExtendedSizes)>{},
                                 y.size() + live.size(), tape, y, c, b, live, r0, r, e_quadratic,
                                 low, second, forms, d2e);
}

}  // namespace furuta::validated::detail
