#pragma once
// Fields with known behaviour that the integrators are measured and tested on, written as the
// systems of ode.hpp: the DynIbex benchmark's pendulum and two oscillators with closed-form
// solutions. The product integrates the Furuta models of ode.hpp only.

#include <cmath>
#include <cstddef>
#include <span>

namespace furuta::validated::research {

// x1' = x2, x2' = -a sin x1 - b x2 (the DynIbex benchmark: a = 56, b = 0.5).
struct SimplePendulum {
  static constexpr std::size_t dimension = 2;
  double a = 56.0;
  double b = 0.5;

  template <class S>
  void operator()(std::span<const S> x, std::span<S> dx) const {
    using std::sin;
    dx[0] = x[1];
    dx[1] = -(S(a) * sin(x[0])) - S(b) * x[1];
  }
};

// x'' = -omega^2 x as x1' = x2, x2' = -omega^2 x1; x1(t) = x1(0) cos wt + x2(0)/w sin wt.
struct HarmonicOscillator {
  static constexpr std::size_t dimension = 2;
  double omega = 1.0;

  template <class S>
  void operator()(std::span<const S> x, std::span<S> dx) const {
    const S w(omega);
    dx[0] = x[1];
    dx[1] = -(w * w) * x[0];
  }
};

// x'' + 2 zeta omega x' + omega^2 x = 0 (underdamped for 0 <= zeta < 1).
struct DampedOscillator {
  static constexpr std::size_t dimension = 2;
  double omega = 1.0;
  double zeta = 0.1;

  template <class S>
  void operator()(std::span<const S> x, std::span<S> dx) const {
    const S w(omega);
    const S z(zeta);
    dx[0] = x[1];
    dx[1] = -(w * w) * x[0] - (S(2.0) * z * w) * x[1];
  }
};

}  // namespace furuta::validated::research
