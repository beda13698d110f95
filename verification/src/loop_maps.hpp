#pragma once
// The exact maps of a linear model dx/dt = a x + b u over a stretch of time, as interval matrices
// (internal to the verifier), and the plant's distance from its linearisation.

#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <map>
#include <utility>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/model/parameters.hpp"

namespace furuta::verification::detail {

using interval::Interval;
using IVector4 = std::array<Interval, 4>;
using IMatrix4 = std::array<Interval, 16>;  // row-major

// Over [0, s] from a sample, the duty held at `old` before switch_s and at `new` from it:
//   x(s) = phi x(0) + gamma_old old + gamma_new new + (what the rest of the input and any
//          disturbance add, bounded with the maps over [0, s] below).
struct StretchMaps {
  double length_s = 0;  // s
  IMatrix4 phi;         // e^(a s)
  IVector4 gamma_old;   // int over [0, min(switch, s)) of e^(a (s - r)) b dr
  IVector4 gamma_new;   // int over [switch, s] (0 when s <= switch)
  IMatrix4 over;        // e^(a r) for every r in [0, s]
  IVector4 over_b;      // e^(a r) b for every r in [0, s]
  IMatrix4 psi_over;    // int_0^r e^(a r') dr' for every r in [0, s]
  // An upper bound of int_0^s |e^(a r)| dr, entrywise: what a disturbance of radius 1 about its
  // midpoint adds, at most (tighter than s |over| where a mode decays within s, as the arm's does).
  std::array<double, 16> abs_integral{};
  // The same for int_0^s |e^(a r) b| dr (the input's column, so that its entries' cancellations
  // are kept).
  std::array<double, 4> abs_integral_b{};
  // e^(a r) b over the pieces [k, k + 1] s / kPieces of [0, s].
  std::vector<IVector4> b_pieces;
  // e^(a r) b for every r in [from, to] (within [0, s]): how an input error at instants s - r
  // reaches the state at s.
  IVector4 input_effect(double from, double to) const;
  // e^(a r) b for every r in [from, to] exactly (not by pieces), cached by the window; and
  // a e^(a r) b over all of [0, s], which bounds how fast the former changes with r.
  IVector4 effect_at(double from, double to) const;
  // a e^(a r) b for every r in [from, to] (not cached).
  IVector4 slope_at(double from, double to) const;
  Eigen::Matrix4d a_matrix = Eigen::Matrix4d::Zero();
  Eigen::Vector4d b_vector = Eigen::Vector4d::Zero();
  mutable std::map<std::pair<double, double>, IVector4> effect_cache;
  // The maps to every instant r of each piece [k, k + 1] s / kPieces: phi, gamma_old and
  // gamma_new as above with s replaced by r.
  struct Piece {
    IMatrix4 phi;
    IVector4 gamma_old;
    IVector4 gamma_new;
  };
  std::vector<Piece> pieces;
};
constexpr int kPieces = 32;
StretchMaps stretch_maps(const Eigen::Matrix4d& a, const Eigen::Vector4d& b, double switch_s,
                         double s);

IVector4 multiply(const IMatrix4& m, const IVector4& x);

// What a perturbation e of the linear model's matrix adds at s, to first order: with the state x
// at the sample and the duty `old` held until switch_s, `new` after it,
// int_0^s e^(a (s - r)) e x_lin(r) dr = x_part x + old_part old + new_part new (the blocks of the
// exponential of [[a, 0, b], [e, a, 0], [0, 0, 0]]).
struct SourceMaps {
  IMatrix4 x_part;
  IVector4 old_part;
  IVector4 new_part;
};
SourceMaps source_maps(const Eigen::Matrix4d& a, const Eigen::Vector4d& b, const Eigen::Matrix4d& e,
                       double switch_s, double s);

// For an instant s in (0, period] and each piece [k, k + 1] period / kPieces of the period (as
// stretch_maps makes them): what a disturbance over the piece's part before s adds to the state at
// s, int over the piece and [0, s] of e^(a (s - r)) dr (zero for a piece after s), and an upper
// bound of the same integral of |e^(a (s - r))| entrywise (for a disturbance that varies).
struct PieceIntegrals {
  std::vector<IMatrix4> psi;
  std::vector<std::array<double, 16>> abs;
};
PieceIntegrals piece_integrals(const Eigen::Matrix4d& a, double period_s, double s);

// The plant in momentum coordinates, z = [q1, q2 - pi, p1, p2] with p = M(q2) dq (docs/control.md):
// dq = M^-1 p, dp1/dt = kd u - (kw + fv1) dq1, dp2/dt = dq' (dM/dq2) dq / 2 - mug sin q2 - fv2 dq2.
// The duty enters with the constant kd and the arm's fast transient stays out of the nonlinear
// terms: these multiply the momenta by how far M^-1 is from its upright value, not the
// accelerations (thousands of rad/s^2 while the arm follows a new duty).
struct MomentumPlant {
  Eigen::Matrix4d a = Eigen::Matrix4d::Zero();  // the linearisation about upright at the centre
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
  Eigen::Matrix2d mass = Eigen::Matrix2d::Zero();     // M at upright, centre parameters
  Eigen::Matrix2d inverse = Eigen::Matrix2d::Zero();  // its inverse
  model::Parameters<double> centre;
  double kd = 0;
  double kw = 0;
};
// Linearised about upright with `inverse` as M's inverse there (the parameter box's midpoint of
// it), mass its inverse.
MomentumPlant momentum_plant(const model::Parameters<double>& centre, double kd, double kw,
                             const Eigen::Matrix2d& inverse);

// M's inverse at upright, v = [v11, v12; v12, v22], over the parameter box: its value at the
// box's midpoint, its change per radius of mu1, mu3, mu4 there (entries 11, 12, 22), and a bound
// of the rest: v = centre + sum_k eta_k per_parameter[k] + rest for eta_k = (mu_k - mid) / radius
// in [-1, 1]. The plant's a is linear in v: a(v) = a(centre) + sum_e (v_e - centre_e)
// inverse_direction(e).
struct UprightInverse {
  Eigen::Matrix2d centre = Eigen::Matrix2d::Zero();
  std::array<std::array<double, 3>, 3> per_parameter{};
  std::array<double, 3> rest{};
};
UprightInverse upright_inverse(const model::Parameters<Interval>& p);
// a's change for v's entry e (11, 12, 22) by one.
Eigen::Matrix4d inverse_direction(std::size_t k, double damping, double pendulum_friction);
// a's change for v's change dv (11, 12, 22).
Eigen::Matrix4d a_direction(const std::array<double, 3>& dv, double damping,
                            double pendulum_friction);

// M(q2)^-1 - inverse over the pendulum's angles `error` (q2 - pi) and the parameter box.
std::array<Interval, 4> inverse_excess(const MomentumPlant& plant,
                                       const model::Parameters<Interval>& p, const Interval& error);
// M(q2) - mass over the same.
std::array<Interval, 4> mass_excess(const MomentumPlant& plant,
                                    const model::Parameters<Interval>& p, const Interval& error);

// The rates M(q2)^-1 p - inverse p over the angles `error`, from `rates` enclosing inverse p:
// -M(q2)^-1 (M(q2) - mass) inverse p, a small matrix computed without cancellation on the rates.
std::array<Interval, 2> rate_excess(const MomentumPlant& plant,
                                    const model::Parameters<Interval>& p, const Interval& error,
                                    const std::array<Interval, 2>& rates);

// The field minus the linearisation, d = f(z, u) - a z - b u, over every z in `z`, duty in `u`,
// parameter and drive constant in their boxes, with `rates` enclosing inverse p (the rates the
// linearisation gives) over the same states: M(q2)^-1 p - inverse p = -M(q2)^-1 (M(q2) - mass)
// inverse p multiplies those rates (tight when taken from the affine forms, where p1 and p2 are
// strongly correlated) by a small matrix computed without cancellation.
IVector4 momentum_remainder(const MomentumPlant& plant, const model::Parameters<Interval>& p,
                            const Interval& kd, const Interval& kw, const IVector4& z,
                            const std::array<Interval, 2>& rates, const Interval& u);

}  // namespace furuta::verification::detail
