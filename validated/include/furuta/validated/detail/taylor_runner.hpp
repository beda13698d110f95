#pragma once
// `TaylorRunner<T>`: the Taylor coefficients of the solution of x' = f(x) from a tape. Part of
// furuta/validated/taylor.hpp: include that.

#include <cstddef>
#include <span>
#include <stdexcept>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/validated/detail/constant_as.hpp"
#include "furuta/validated/detail/series.hpp"
#include "furuta/validated/detail/tape.hpp"

namespace furuta::validated {

using interval::Interval;

template <class T>
class TaylorRunner {
 public:
  // Computes x_[0..order] of the solution of x' = f(x), x(0) = x0 (x_[i+1] = f(x)_[i] / (i+1)).
  void run(const Tape& tape, std::span<const T> x0, int order) {
    if (x0.size() != tape.dimension) throw std::invalid_argument("TaylorRunner: dimension");
    tape_ = &tape;
    stride_ = static_cast<std::size_t>(order) + 1;
    c_.assign(tape.nodes.size() * stride_, T(0.0));
    for (std::size_t v = 0; v < tape.dimension; ++v) c_[v * stride_] = x0[v];
    for (std::size_t n = tape.dimension; n < tape.nodes.size(); ++n) {
      if (tape.nodes[n].op == Op::constant) c_[n * stride_] = constant_as<T>(tape.nodes[n].value);
    }
    ja_.assign(tape.nodes.size() * stride_, T(0.0));
    for (int i = 0; i < order; ++i) {
      for (std::size_t n = tape.dimension; n < tape.nodes.size(); ++n) step(n, i);
      for (std::size_t v = 0; v < tape.dimension; ++v) {
        if (tape.nodes[v].time_constant) continue;
        const T& fi = at(static_cast<std::size_t>(tape.outputs[v]), i);
        c_[v * stride_ + static_cast<std::size_t>(i) + 1] = series::unscale(fi, i + 1);
      }
    }
  }

  // Coefficient i of component v of the solution.
  const T& coefficient(std::size_t v, int i) const { return at(v, i); }
  int order() const { return static_cast<int>(stride_) - 1; }

 private:
  const T& at(std::size_t node, int i) const {
    return c_[node * stride_ + static_cast<std::size_t>(i)];
  }
  T* series_of(std::size_t node) { return c_.data() + node * stride_; }

  void step(std::size_t n, int i) {
    const TapeNode& node = tape_->nodes[n];
    if (node.op == Op::constant || node.op == Op::cos) return;  // cos: filled with its sin
    if (i > 0 && node.time_constant) return;                    // stays 0
    const auto ia = static_cast<std::size_t>(node.a);
    const auto ib = static_cast<std::size_t>(node.b);
    T* c = series_of(n);
    const T* a = series_of(ia);
    const auto ui = static_cast<std::size_t>(i);
    switch (node.op) {
      case Op::add:
        c[ui] = a[ui] + series_of(ib)[ui];
        break;
      case Op::sub:
        c[ui] = a[ui] - series_of(ib)[ui];
        break;
      case Op::neg:
        c[ui] = -a[ui];
        break;
      case Op::mul: {
        const T* b = series_of(ib);
        if (tape_->nodes[ia].time_constant) {
          c[ui] = a[0] * b[ui];
        } else if (tape_->nodes[ib].time_constant) {
          c[ui] = a[ui] * b[0];
        } else {
          c[ui] = series::mul(a, b, i);
        }
        break;
      }
      case Op::div: {
        const T* b = series_of(ib);
        c[ui] = tape_->nodes[ib].time_constant ? a[ui] / b[0] : series::div(a, b, c, i);
        break;
      }
      case Op::sqr:
        c[ui] = series::sqr(a, i);
        break;
      case Op::sin: {
        // j a_j of the operand, kept per sin node (each is computed once).
        T* ja = ja_.data() + n * stride_;
        if (i > 0) ja[ui] = series::scale(a[ui], i);
        series::sin_cos(a, c, series_of(n + 1), i, ja);
        break;
      }
      default:
        break;
    }
  }

  const Tape* tape_ = nullptr;
  std::size_t stride_ = 1;
  std::vector<T> c_;   // node-major: c_[node * stride_ + i] = coefficient i of the node
  std::vector<T> ja_;  // for sin nodes: j times coefficient j of the operand
};

}  // namespace furuta::validated
