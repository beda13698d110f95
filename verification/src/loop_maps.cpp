#include "loop_maps.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "furuta/validated/matrix_exponential.hpp"

namespace furuta::verification::detail {

namespace {

// The top-right block (rows 0..3, columns 4..4+cols) of the exponential of [[a, b], [0, 0]] s:
// int_0^s e^(a r) dr b.
std::vector<Interval> integral_block(const Eigen::Matrix4d& a, const Eigen::MatrixXd& b,
                                     const Interval& s) {
  const auto cols = b.cols();
  Eigen::MatrixXd big = Eigen::MatrixXd::Zero(4 + cols, 4 + cols);
  big.topLeftCorner(4, 4) = a;
  big.topRightCorner(4, cols) = b;
  const std::vector<Interval> e = validated::exp_enclosure(big, s);
  std::vector<Interval> out;
  const auto n = static_cast<std::size_t>(4 + cols);
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = 0; j < static_cast<std::size_t>(cols); ++j)
      out.push_back(e[i * n + 4 + j]);
  }
  return out;
}

IMatrix4 to_matrix(const std::vector<Interval>& v) {
  IMatrix4 out;
  std::copy_n(v.begin(), 16, out.begin());
  return out;
}

IVector4 to_vector(const std::vector<Interval>& v) {
  IVector4 out;
  std::copy_n(v.begin(), 4, out.begin());
  return out;
}

}  // namespace

IVector4 StretchMaps::input_effect(double from, double to) const {
  if (b_pieces.empty() || !(length_s > 0)) return over_b;
  const double n = static_cast<double>(b_pieces.size());
  // One piece more on each side than the fractions say: the pieces' own ends were rounded.
  const double first = std::clamp(std::floor(from / length_s * n) - 1, 0.0, n - 1);
  const double last = std::clamp(std::ceil(to / length_s * n), first, n - 1);
  IVector4 out;
  out.fill(Interval::empty());
  for (auto k = static_cast<std::size_t>(first); k <= static_cast<std::size_t>(last); ++k) {
    for (std::size_t i = 0; i < 4; ++i) out[i] = hull(out[i], b_pieces[k][i]);
  }
  return out;
}

namespace {

IVector4 interval_vector(const Eigen::Vector4d& v) {
  IVector4 out;
  for (std::size_t i = 0; i < 4; ++i) out[i] = Interval(v(static_cast<Eigen::Index>(i)));
  return out;
}

IMatrix4 interval_matrix(const Eigen::Matrix4d& m) {
  IMatrix4 out;
  for (std::size_t e = 0; e < 16; ++e) {
    out[e] = Interval(m(static_cast<Eigen::Index>(e / 4), static_cast<Eigen::Index>(e % 4)));
  }
  return out;
}

// e^(a r) b for every r in [from, to].
IVector4 effect_over(const Eigen::Matrix4d& a, const Eigen::Vector4d& b, double from, double to) {
  return multiply(to_matrix(validated::exp_enclosure(a, Interval(from, to))), interval_vector(b));
}

}  // namespace

IVector4 StretchMaps::effect_at(double from, double to) const {
  const auto key = std::make_pair(from, to);
  const auto found = effect_cache.find(key);
  if (found != effect_cache.end()) return found->second;
  const IVector4 out = effect_over(a_matrix, b_vector, from, to);
  effect_cache.emplace(key, out);
  return out;
}

IVector4 StretchMaps::slope_at(double from, double to) const {
  return multiply(interval_matrix(a_matrix), effect_over(a_matrix, b_vector, from, to));
}

IVector4 multiply(const IMatrix4& m, const IVector4& x) {
  IVector4 out;
  for (std::size_t i = 0; i < 4; ++i) {
    Interval sum(0.0);
    for (std::size_t j = 0; j < 4; ++j) sum += m[i * 4 + j] * x[j];
    out[i] = sum;
  }
  return out;
}

StretchMaps stretch_maps(const Eigen::Matrix4d& a, const Eigen::Vector4d& b, double switch_s,
                         double s) {
  StretchMaps out;
  out.length_s = s;
  out.a_matrix = a;
  out.b_vector = b;
  out.phi = to_matrix(validated::exp_enclosure(a, Interval(s)));
  const IVector4 whole = to_vector(integral_block(a, b, Interval(s)));
  // The new duty acts over [switch, s]: e^(a (s - r)) b integrated there is the integral over
  // r' in [0, s - switch]; the old one over the rest.
  const double after = std::max(0.0, s - switch_s);
  const IVector4 late = after > 0
                            ? to_vector(integral_block(a, b, Interval(after)))
                            : IVector4{Interval(0.0), Interval(0.0), Interval(0.0), Interval(0.0)};
  for (std::size_t i = 0; i < 4; ++i) {
    out.gamma_new[i] = late[i];
    out.gamma_old[i] = whole[i] - late[i];
  }
  const IVector4 bi = interval_vector(b);
  out.psi_over = to_matrix(integral_block(a, Eigen::Matrix4d::Identity(), Interval(0.0, s)));
  // Per piece of [0, s], one interval exponential over the piece: its hull makes e^(a r) over
  // [0, s] (one exponential over all of [0, s] squares intervals of time and spreads far wider),
  // its length times its largest |entry| sums to the integral of |e^(a r)|, and it gives the
  // piece's maps.
  std::array<Interval, 16> sum;
  sum.fill(Interval(0.0));
  std::array<Interval, 4> sum_b;
  sum_b.fill(Interval(0.0));
  out.over = to_matrix(validated::exp_enclosure(a, Interval(0.0)));
  std::fill(out.over_b.begin(), out.over_b.end(), Interval::empty());
  for (int k = 0; k < kPieces && s > 0; ++k) {
    const double from = s * k / kPieces;
    const double to = k + 1 == kPieces ? s : s * (k + 1) / kPieces;
    // A piece's maps hold slightly beyond its ends: the instants piece_integrals attributes to it
    // (through s - r in double) may lie a rounding outside.
    const double slack = 1e-12 * s;
    const Interval whole_r = Interval(from - slack, to + slack);
    const IMatrix4 piece = to_matrix(validated::exp_enclosure(a, whole_r));
    const Interval length = Interval(to) - Interval(from);
    for (std::size_t e = 0; e < 16; ++e) {
      sum[e] += length * Interval(piece[e].mag());
      out.over[e] = hull(out.over[e], piece[e]);
    }
    const IVector4 piece_b = multiply(piece, bi);
    for (std::size_t i = 0; i < 4; ++i) {
      sum_b[i] += length * Interval(piece_b[i].mag());
      out.over_b[i] = hull(out.over_b[i], piece_b[i]);
    }
    out.b_pieces.push_back(piece_b);
    StretchMaps::Piece maps;
    maps.phi = piece;
    const IVector4 upto = to_vector(integral_block(a, b, whole_r));
    const double late_from = std::max(0.0, from - switch_s);
    const double late_to = std::max(0.0, to - switch_s);
    const IVector4 late_r =
        late_to > 0 ? to_vector(integral_block(a, b, Interval(late_from, late_to)))
                    : IVector4{Interval(0.0), Interval(0.0), Interval(0.0), Interval(0.0)};
    for (std::size_t i = 0; i < 4; ++i) {
      maps.gamma_new[i] = late_r[i];
      maps.gamma_old[i] = upto[i] - late_r[i];
    }
    out.pieces.push_back(maps);
  }
  for (std::size_t e = 0; e < 16; ++e) out.abs_integral[e] = sum[e].hi();
  for (std::size_t i = 0; i < 4; ++i) out.abs_integral_b[i] = sum_b[i].hi();
  if (!(s > 0)) out.over_b = bi;

  return out;
}

SourceMaps source_maps(const Eigen::Matrix4d& a, const Eigen::Vector4d& b, const Eigen::Matrix4d& e,
                       double switch_s, double s) {
  Eigen::MatrixXd big = Eigen::MatrixXd::Zero(9, 9);
  big.topLeftCorner(4, 4) = a;
  big.block(0, 8, 4, 1) = b;
  big.block(4, 0, 4, 4) = e;
  big.block(4, 4, 4, 4) = a;
  // The blocks (x part, duty part) at t: rows 4..7, columns 0..3 and 8.
  const auto blocks = [&](double t) {
    std::pair<IMatrix4, IVector4> out;
    if (!(t > 0)) {
      out.first.fill(Interval(0.0));
      out.second.fill(Interval(0.0));
      return out;
    }
    const std::vector<Interval> x = validated::exp_enclosure(big, Interval(t));
    for (std::size_t i = 0; i < 4; ++i) {
      for (std::size_t j = 0; j < 4; ++j) out.first[i * 4 + j] = x[(4 + i) * 9 + j];
      out.second[i] = x[(4 + i) * 9 + 8];
    }
    return out;
  };
  const auto whole = blocks(s);
  const auto late = blocks(s - switch_s);
  SourceMaps out;
  out.x_part = whole.first;
  for (std::size_t i = 0; i < 4; ++i) {
    out.new_part[i] = late.second[i];
    out.old_part[i] = whole.second[i] - late.second[i];
  }
  return out;
}

PieceIntegrals piece_integrals(const Eigen::Matrix4d& a, double period_s, double s) {
  PieceIntegrals out;
  const auto integral_to = [&](double t) {
    return to_matrix(integral_block(a, Eigen::Matrix4d::Identity(), Interval(t)));
  };
  IMatrix4 zero;
  zero.fill(Interval(0.0));
  for (int k = 0; k < kPieces; ++k) {
    const double from = period_s * k / kPieces;
    const double to = std::min(s, k + 1 == kPieces ? period_s : period_s * (k + 1) / kPieces);
    std::array<double, 16> abs{};
    if (!(from < to)) {
      out.psi.push_back(zero);
      out.abs.push_back(abs);
      continue;
    }
    // int_from^to e^(a (s - r)) dr = int_(s - to)^(s - from) e^(a u) du.
    const IMatrix4 upper = integral_to(s - from);
    const IMatrix4 lower = integral_to(s - to);
    IMatrix4 psi;
    for (std::size_t e = 0; e < 16; ++e) psi[e] = upper[e] - lower[e];
    out.psi.push_back(psi);
    const IMatrix4 over = to_matrix(validated::exp_enclosure(a, Interval(s - to, s - from)));
    const Interval length = Interval(to) - Interval(from);
    for (std::size_t e = 0; e < 16; ++e) abs[e] = (length * Interval(over[e].mag())).hi();
    out.abs.push_back(abs);
  }
  return out;
}

MomentumPlant momentum_plant(const model::Parameters<double>& centre, double kd, double kw,
                             const Eigen::Matrix2d& inverse) {
  MomentumPlant out;
  out.centre = centre;
  out.kd = kd;
  out.kw = kw;
  out.inverse = inverse;
  out.mass = inverse.inverse();
  const Eigen::Matrix2d& v = out.inverse;
  out.a.block<2, 2>(0, 2) = v;
  out.a.block<1, 2>(2, 2) = -(kw + centre.fv1) * v.row(0);
  out.a(3, 1) = centre.mug;  // -mug sin(pi + e) = mug sin e
  out.a.block<1, 2>(3, 2) = -centre.fv2 * v.row(1);
  out.b(2) = kd;
  return out;
}

namespace {

struct MassOver {
  Interval m11, m12, m22, det;
};

MassOver mass_over(const model::Parameters<Interval>& p, const Interval& error) {
  const Interval q2 = Interval::pi() + error;
  const Interval s = interval::sin(q2);
  const Interval c = interval::cos(q2);
  MassOver m;
  m.m11 = p.mu1 + p.mu2 * interval::sqr(s);
  m.m12 = p.mu3 * c;
  m.m22 = p.mu4;
  m.det = m.m11 * m.m22 - interval::sqr(m.m12);
  return m;
}

}  // namespace

std::array<Interval, 4> inverse_excess(const MomentumPlant& plant,
                                       const model::Parameters<Interval>& p,
                                       const Interval& error) {
  const MassOver m = mass_over(p, error);
  const Eigen::Matrix2d& v = plant.inverse;
  return {m.m22 / m.det - v(0, 0), -(m.m12 / m.det) - v(0, 1), -(m.m12 / m.det) - v(1, 0),
          m.m11 / m.det - v(1, 1)};
}

std::array<Interval, 4> mass_excess(const MomentumPlant& plant,
                                    const model::Parameters<Interval>& p, const Interval& error) {
  const MassOver m = mass_over(p, error);
  const Eigen::Matrix2d& w = plant.mass;
  return {m.m11 - w(0, 0), m.m12 - w(0, 1), m.m12 - w(1, 0), m.m22 - w(1, 1)};
}

std::array<Interval, 2> rate_excess(const MomentumPlant& plant,
                                    const model::Parameters<Interval>& p, const Interval& error,
                                    const std::array<Interval, 2>& rates) {
  const MassOver m = mass_over(p, error);
  const std::array<Interval, 4> dm = mass_excess(plant, p, error);
  // (M - mass) rates, then -M^-1 = -[m22, -m12; -m12, m11] / det times it.
  const Interval w1 = dm[0] * rates[0] + dm[1] * rates[1];
  const Interval w2 = dm[2] * rates[0] + dm[3] * rates[1];
  return {-((m.m22 * w1 - m.m12 * w2) / m.det), -((m.m11 * w2 - m.m12 * w1) / m.det)};
}

UprightInverse upright_inverse(const model::Parameters<Interval>& p) {
  // At q2 = pi: M = [mu1, -mu3; -mu3, mu4], v = M^-1 = [mu4, mu3; mu3, mu1] / det; dv/dq =
  // -v (dM/dq) v for q = mu1, mu3, mu4 (dM/dq: e11, -(e12 + e21), e22).
  const auto inverse_of = [](const Interval& mu1, const Interval& mu3, const Interval& mu4) {
    const Interval det = mu1 * mu4 - interval::sqr(mu3);
    return std::array<Interval, 3>{mu4 / det, mu3 / det, mu1 / det};  // v11, v12, v22
  };
  const auto derivatives = [](const std::array<Interval, 3>& v) {
    // -v e11 v, v (e12 + e21) v, -v e22 v as (11, 12, 22).
    const Interval& a = v[0];
    const Interval& b = v[1];
    const Interval& c = v[2];
    return std::array<std::array<Interval, 3>, 3>{
        {{-(a * a), -(a * b), -(b * b)},
         {Interval(2.0) * a * b, a * c + b * b, Interval(2.0) * b * c},
         {-(b * b), -(b * c), -(c * c)}}};
  };
  const Interval mu1c(p.mu1.mid());
  const Interval mu3c(p.mu3.mid());
  const Interval mu4c(p.mu4.mid());
  const std::array<Interval, 3> at_centre = inverse_of(mu1c, mu3c, mu4c);
  const std::array<Interval, 3> over_box = inverse_of(p.mu1, p.mu3, p.mu4);
  const auto d_centre = derivatives(at_centre);
  const auto d_box = derivatives(over_box);
  const std::array<Interval, 3> radius{Interval(p.mu1.rad()), Interval(p.mu3.rad()),
                                       Interval(p.mu4.rad())};
  UprightInverse out;
  out.centre << at_centre[0].mid(), at_centre[1].mid(), at_centre[1].mid(), at_centre[2].mid();
  // v(q) = centre + sum_k eta_k radius_k dv/dq_k(centre) + rest, eta_k = (q_k - mid) / radius_k:
  // by the mean value theorem rest = sum_k (dv/dq_k(xi) - dv/dq_k(centre)) (q_k - mid), plus the
  // centre's rounding.
  for (std::size_t e = 0; e < 3; ++e) {
    Interval rest = at_centre[e] - Interval(at_centre[e].mid());
    for (std::size_t k = 0; k < 3; ++k) {
      const double slope = d_centre[k][e].mid();
      out.per_parameter[k][e] = slope * radius[k].mid();
      rest += (d_box[k][e] - Interval(slope)) * Interval(-radius[k].hi(), radius[k].hi()) +
              (Interval(slope) * radius[k] - Interval(out.per_parameter[k][e]));
    }
    out.rest[e] = rest.mag();
  }
  return out;
}

Eigen::Matrix4d a_direction(const std::array<double, 3>& dv, double damping,
                            double pendulum_friction) {
  Eigen::Matrix4d out = Eigen::Matrix4d::Zero();
  for (std::size_t e = 0; e < 3; ++e) {
    out += dv[e] * inverse_direction(e, damping, pendulum_friction);
  }
  return out;
}

Eigen::Matrix4d inverse_direction(std::size_t k, double damping, double pendulum_friction) {
  // a's entries in v: rows 0 and 1 (the kinematics) v p, row 2 -damping v row 0, row 3
  // -pendulum_friction v row 1.
  Eigen::Matrix4d e = Eigen::Matrix4d::Zero();
  if (k == 0) {
    e(0, 2) = 1;
    e(2, 2) = -damping;
  } else if (k == 1) {
    e(0, 3) = 1;
    e(1, 2) = 1;
    e(2, 3) = -damping;
    e(3, 2) = -pendulum_friction;
  } else {
    e(1, 3) = 1;
    e(3, 3) = -pendulum_friction;
  }
  return e;
}

IVector4 momentum_remainder(const MomentumPlant& plant, const model::Parameters<Interval>& p,
                            const Interval& kd, const Interval& kw, const IVector4& z,
                            const std::array<Interval, 2>& rates, const Interval& u) {
  const std::array<Interval, 2> excess = rate_excess(plant, p, z[1], rates);
  const Interval extra1 = excess[0];
  const Interval extra2 = excess[1];
  const Interval linear1 = rates[0];
  const Interval linear2 = rates[1];
  const Interval dq1 = linear1 + extra1;
  const Interval dq2 = linear2 + extra2;
  const model::Parameters<double>& c = plant.centre;
  const Interval damping = kw + p.fv1;
  const Interval damping_centre = Interval(plant.kw) + Interval(c.fv1);
  IVector4 d;
  d[0] = extra1;
  d[1] = extra2;
  d[2] = (kd - Interval(plant.kd)) * u - damping * extra1 - (damping - damping_centre) * linear1;
  // dq' (dM/dq2) dq / 2 = mu2 s c dq1^2 - mu3 s dq1 dq2; -mug sin(pi + e) = mug sin e, and
  // |sin e - e| <= |e|^3 / 6.
  const Interval q2 = Interval::pi() + z[1];
  const Interval s = interval::sin(q2);
  const Interval co = interval::cos(q2);
  const double e = z[1].mag();
  const Interval cubic =
      Interval(-1.0, 1.0) * (Interval(e) * Interval(e) * Interval(e) / Interval(6.0));
  d[3] = p.mu2 * s * co * interval::sqr(dq1) - p.mu3 * s * dq1 * dq2 + p.mug * cubic +
         (p.mug - Interval(c.mug)) * z[1] - p.fv2 * extra2 - (p.fv2 - Interval(c.fv2)) * linear2;
  return d;
}

}  // namespace furuta::verification::detail
