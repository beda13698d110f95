// One step of the validated integrator once its a priori enclosure is accepted (see step.hpp).

#include "step.hpp"

#include "jets.hpp"
#include "quadratic_form.hpp"
#include "taylor_form.hpp"

namespace furuta::validated::detail {

TaylorMap taylor_map(const Tape& tape, const Doubleton& set, const std::vector<std::size_t>& live,
                     const StepEnclosure& enclosure, const IntegratorOptions& options,
                     TubeStep& step) {
  const std::size_t n = set.m.size();
  const int k = options.order;
  const auto uk = static_cast<std::size_t>(k);
  const std::size_t pairs = pair_count(n);
  const Interval& hi = enclosure.hi;
  TaylorMap out;

  // 3. Taylor coefficients at the centre m and their Jacobian V_[i](m) (thin: m is a point).
  centre_coefficients(tape, set.m, k, step.centre, step.jacobian);
  // 4. The second-order term over the set: coefficient s^2 of x_[i](y + s delta) over y in the
  // box (with the centre) and delta in C r0 + B r.
  const IMatrix bi = from_point(set.b);
  // The set at t is m + C rho + P(rho) + B r: the direction's interval part e holds P(r0) and
  // B r (P is zero without the quadratic model).
  out.p_range = forms_range(set.p, set.r0);
  const std::vector<Interval>& p_range = out.p_range;
  std::vector<Interval> forms;
  std::vector<Interval> d2e;
  {
    std::vector<Interval> e = bi * set.r;
    for (std::size_t v = 0; v < n; ++v) e[v] += p_range[v];
    Box y = set.x;
    for (std::size_t v = 0; v < n; ++v) y[v] = y[v] | Interval(set.m[v]);
    if (options.quadratic_model && n + live.size() <= kMaxExtended) {
      second_order_extended(tape, y, set.c, set.b, live, set.r0, set.r, p_range, e, k,
                            options.quadratic_order, step.second, forms, d2e);
    } else {
      second_order_coefficients(tape, y, set.c, set.r0, e, k, options.quadratic_order, step.second,
                                options.quadratic_model ? &forms : nullptr,
                                options.quadratic_model ? &d2e : nullptr);
    }
  }
  // J = sum_i h^i V_[i](m).
  out.j = jacobian_series(step.jacobian, n, k, hi);
  const IMatrix& j = out.j;
  // T(x0) = T(m) + J (C rho + P(rho) + e) + S(rho) + R, S the second-order term. Without the
  // quadratic model S is enclosed by sum_i h^i q_i (its range) and P = 0. With it, S(rho) =
  // Q(rho) + D, Q the quadratic form sum_i h^i forms_i (interval coefficients) and D the
  // interval sum_i h^i d2e_i; the new quadratic part is P'(rho) = mid(J P + Q)(rho) and the
  // coefficients' rest ((J P + Q) - P')(rho) over r0, with D, goes to the error part.
  out.p_next.assign(n * pairs, 0.0);
  std::vector<double>& p_next = out.p_next;
  std::vector<Interval> second_rest(n, Interval(0.0));
  if (options.quadratic_model) {
    std::vector<Interval> coefficients(n * pairs, Interval(0.0));
    for (std::size_t v = 0; v < n; ++v) {
      for (std::size_t a = 0; a < pairs; ++a) {
        Interval sum = forms[(uk * n + v) * pairs + a];
        for (std::size_t i = uk; i-- > 0;) sum = sum * hi + forms[(i * n + v) * pairs + a];
        for (std::size_t w = 0; w < n; ++w) {
          if (set.p[w * pairs + a] != 0.0) sum += j(v, w) * Interval(set.p[w * pairs + a]);
        }
        p_next[v * pairs + a] = sum.is_bounded() ? sum.mid() : 0.0;
        coefficients[v * pairs + a] = sum - Interval(p_next[v * pairs + a]);
      }
      second_rest[v] =
          form_range(coefficients.data() + v * pairs, set.r0) + horner(d2e, n, v, k, hi);
    }
  } else {
    // P is zero unless the run was restarted (integrate_sub_box) from a tube that carried it:
    // then J P(rho) goes into the error part too.
    const std::vector<Interval> image = j * p_range;
    for (std::size_t v = 0; v < n; ++v) {
      second_rest[v] = horner(step.second, n, v, k, hi) + image[v];
    }
  }
  // z: the image of the centre, with what the second-order term leaves and the remainder.
  out.z.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    out.z[v] = horner(step.centre, n, v, k, hi) + second_rest[v] + enclosure.remainder[v];
  }
  return out;
}

LohnerStep lohner_step(const Doubleton& set, const TaylorMap& map, const TubeStep& step,
                       const StepEnclosure& enclosure, LiveSet& live,
                       const IntegratorOptions& options) {
  const std::size_t n = set.m.size();
  const int k = options.order;
  const Interval& hi = enclosure.hi;
  const IMatrix& j = map.j;
  const std::vector<Interval>& z = map.z;
  const std::vector<Interval>& r0 = set.r0;

  const IMatrix jc = j * from_point(set.c);
  const IMatrix jb = j * from_point(set.b);
  const Matrix c_next = mid(jc);
  // m' = mid(z); the rest of z, with the rounding of C' = mid(J C), goes to the r part.
  std::vector<double> m_next(n);
  std::vector<Interval> rest(n);
  IMatrix jc_error = jc;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t col = 0; col < n; ++col) {
      jc_error(i, col) -=
          Interval(c_next(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(col)));
    }
  }
  const std::vector<Interval> jc_error_r0 = jc_error * r0;
  for (std::size_t v = 0; v < n; ++v) {
    m_next[v] = z[v].mid();
    rest[v] = z[v] - Interval(m_next[v]) + jc_error_r0[v];
  }
  // B' and r' = (B'^-1 J B) r + B'^-1 rest (the parallelepiped: r is not wrapped, only the rest
  // is, through B'^-1; or QR), on the live block.
  Frame frame = choose_frame(j, jb, set.r, rest, live, options.max_inflation);
  // The tight enclosure: the new doubleton, intersected with the direct image.
  LohnerStep out;
  out.qr = frame.qr;
  out.exact = from_point(c_next) * r0;
  out.exact_quadratic = forms_range(map.p_next, r0);
  out.error = std::move(frame.box);
  const std::vector<Interval> old0 = jc * r0;
  const std::vector<Interval> old_quadratic = j * map.p_range;
  const std::vector<Interval> old1 = jb * set.r;
  Box end(n);
  for (std::size_t v = 0; v < n; ++v) {
    const Interval direct = horner(step.centre, n, v, k, hi) + horner(step.second, n, v, k, hi) +
                            enclosure.remainder[v] + old0[v] + old_quadratic[v] + old1[v];
    end[v] = (Interval(m_next[v]) + out.exact[v] + out.exact_quadratic[v] + out.error[v]) & direct;
  }

  Doubleton& next = out.set;
  next.t = enclosure.t1;
  next.origin = set.origin;
  next.r0 = set.r0;
  next.m = std::move(m_next);
  next.c = c_next;
  next.p = map.p_next;
  next.b = std::move(frame.b);
  next.r = std::move(frame.r);
  next.x = std::move(end);
  next.h_next = set.h_next;
  return out;
}

}  // namespace furuta::validated::detail
