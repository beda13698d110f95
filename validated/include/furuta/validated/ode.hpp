#pragma once
// Vector fields for the validated integrator (see validated/README.md).
//
// A system is a type with `static constexpr std::size_t dimension` and a field written once as a
// template over the scalar S (Interval, Recorder, double, long double):
//
//   template <class S> void operator()(std::span<const S> x, std::span<S> dx) const;
//
// A system whose field changes at given times (a piecewise constant input) also has
// `std::vector<double> switch_times() const` (sorted) and takes the piece number first:
//
//   template <class S> void operator()(std::size_t piece, std::span<const S> x, std::span<S> dx)
//
// where piece k holds on [switch_times()[k - 1], switch_times()[k]) (piece 0 before the first
// switch, the last piece after the last one). Use `sin`/`cos` unqualified after
// `using std::sin; using std::cos;`, and `constant_as<S>(interval)` for interval constants.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/interval/interval.hpp"
#include "furuta/model/model.hpp"
#include "furuta/validated/taylor.hpp"

namespace furuta::validated {

using interval::Box;

template <class System>
concept PiecewiseSystem = requires(const System& s) {
  { s.switch_times() } -> std::convertible_to<std::vector<double>>;
};

// The times where the field changes (none for an autonomous system).
template <class System>
std::vector<double> switch_times(const System& system) {
  if constexpr (PiecewiseSystem<System>) {
    return system.switch_times();
  } else {
    (void)system;
    return {};
  }
}

// The piece that holds at time t: the number of switch times <= t.
inline std::size_t piece_at(const std::vector<double>& switches, double t) {
  return static_cast<std::size_t>(std::upper_bound(switches.begin(), switches.end(), t) -
                                  switches.begin());
}

// Evaluates the field of `piece` (ignored by autonomous systems).
template <class System, class S>
void evaluate_field(const System& system, std::size_t piece, std::span<const S> x,
                    std::span<S> dx) {
  if constexpr (PiecewiseSystem<System>) {
    system(piece, x, dx);
  } else {
    (void)piece;
    system(x, dx);
  }
}

// The model's parameters as intervals (docs/model.md): the point parameters p, and p with each
// parameter widened by +-relative * |value| (an enclosure of it).
model::Parameters<Interval> interval_parameters(const model::Parameters<double>& p);
model::Parameters<Interval> parameters_around(const model::Parameters<double>& p, double relative);

// A piece of piecewise constant arm torque: tau from t_start on (until the next piece).
struct InputPiece {
  double t_start = 0.0;
  Interval tau = 0.0;  // N m
};

// The torque pieces' common checks and switch times (see the two Furuta systems).
std::vector<InputPiece> checked_pieces(std::vector<InputPiece> pieces);
std::vector<double> piece_switch_times(const std::vector<InputPiece>& pieces);

// The Furuta pendulum, M(q) ddq + B(q, dq) + Q(q) = Gamma (docs/model.md), with the parameters
// carried as state of zero derivative, so that the integrator tracks their correlation with the
// motion: x = [q1, dq1, q2, dq2, mu1, mu2, mu3, mu4, mug, fv1, fv2].
class FurutaDynamics {
 public:
  static constexpr std::size_t dimension = 11;
  enum Component : std::size_t { q1, dq1, q2, dq2, mu1, mu2, mu3, mu4, mug, fv1, fv2 };

  // Constant torque.
  explicit FurutaDynamics(const Interval& tau = Interval(0.0));
  // Piecewise constant torque; pieces sorted by strictly increasing t_start, at least one. The
  // first piece also holds before its t_start.
  explicit FurutaDynamics(std::vector<InputPiece> pieces);

  const std::vector<InputPiece>& pieces() const { return pieces_; }
  std::vector<double> switch_times() const { return piece_switch_times(pieces_); }

  // The 11-dimensional initial box from the state [q1, dq1, q2, dq2] and the parameters.
  static Box initial_box(const Box& state, const model::Parameters<Interval>& p);

  template <class S>
  void operator()(std::size_t piece, std::span<const S> x, std::span<S> dx) const {
    const S tau = constant_as<S>(pieces_[std::min(piece, pieces_.size() - 1)].tau);
    dx[q1] = x[dq1];
    dx[q2] = x[dq2];
    const model::Parameters<S> p{x[mu1], x[mu2], x[mu3], x[mu4], x[mug], x[fv1], x[fv2]};
    const model::JointAccelerations<S> a = model::accelerations(p, x[q2], x[dq1], x[dq2], tau);
    dx[dq1] = a.ddq1;
    dx[dq2] = a.ddq2;
    for (std::size_t i = mu1; i <= fv2; ++i) dx[i] = S(0.0);
  }

 private:
  std::vector<InputPiece> pieces_;
};

// FurutaDynamics with its input as a state: x = [q1, dq1, q2, dq2, mu1, ..., fv2, u], and each
// piece's `tau` the input's rate du/dt. A board that ramps its duty towards each command is then
// described exactly (u piecewise linear in time, its start a point), where constant pieces would
// need the ramp's spread over each piece as an interval input, which a flow can only carry in its
// error part (and through the arm's stiff mode that part grows step by step).
class FurutaRampedDynamics {
 public:
  static constexpr std::size_t dimension = 12;
  static constexpr std::size_t input = 11;  // u's component

  // Pieces of the input's rate, sorted by strictly increasing t_start, at least one.
  explicit FurutaRampedDynamics(std::vector<InputPiece> rate_pieces);

  const std::vector<InputPiece>& pieces() const { return pieces_; }
  std::vector<double> switch_times() const { return piece_switch_times(pieces_); }

  // FurutaDynamics::initial_box with the input's start u0 appended.
  static Box initial_box(const Box& state, const model::Parameters<Interval>& p,
                         const Interval& u0);

  template <class S>
  void operator()(std::size_t piece, std::span<const S> x, std::span<S> dx) const {
    using F = FurutaDynamics;
    dx[F::q1] = x[F::dq1];
    dx[F::q2] = x[F::dq2];
    const model::Parameters<S> p{x[F::mu1], x[F::mu2], x[F::mu3], x[F::mu4],
                                 x[F::mug], x[F::fv1], x[F::fv2]};
    const model::JointAccelerations<S> a =
        model::accelerations(p, x[F::q2], x[F::dq1], x[F::dq2], x[input]);
    dx[F::dq1] = a.ddq1;
    dx[F::dq2] = a.ddq2;
    for (std::size_t i = F::mu1; i <= F::fv2; ++i) dx[i] = S(0.0);
    dx[input] = constant_as<S>(pieces_[std::min(piece, pieces_.size() - 1)].tau);
  }

 private:
  std::vector<InputPiece> pieces_;
};

// The same model on the state alone, x = [q1, dq1, q2, dq2], the parameters (intervals) as
// constants of the field: the Jacobian and second-order jets are 4-dimensional instead of 11
// (much cheaper per step). Sound for interval parameters too, but their correlation with the
// motion is lost at every step (each step re-encloses the field over the whole parameter box), so
// the tube is wider than FurutaDynamics's; it is the system of choice for point parameters.
class FurutaStateDynamics {
 public:
  static constexpr std::size_t dimension = 4;
  enum Component : std::size_t { q1, dq1, q2, dq2 };

  explicit FurutaStateDynamics(const model::Parameters<Interval>& p,
                               const Interval& tau = Interval(0.0));
  FurutaStateDynamics(const model::Parameters<Interval>& p, std::vector<InputPiece> pieces);

  const model::Parameters<Interval>& parameters() const { return p_; }
  const std::vector<InputPiece>& pieces() const { return pieces_; }
  std::vector<double> switch_times() const { return piece_switch_times(pieces_); }

  template <class S>
  void operator()(std::size_t piece, std::span<const S> x, std::span<S> dx) const {
    const S tau = constant_as<S>(pieces_[std::min(piece, pieces_.size() - 1)].tau);
    dx[q1] = x[dq1];
    dx[q2] = x[dq2];
    const model::Parameters<S> p = p_.map([](const Interval& v) { return constant_as<S>(v); });
    const model::JointAccelerations<S> a = model::accelerations(p, x[q2], x[dq1], x[dq2], tau);
    dx[dq1] = a.ddq1;
    dx[dq2] = a.ddq2;
  }

 private:
  model::Parameters<Interval> p_;
  std::vector<InputPiece> pieces_;
};

}  // namespace furuta::validated
