// The set of solutions at a step boundary (see doubleton.hpp).

#include "doubleton.hpp"

#include <algorithm>
#include <optional>
#include <stdexcept>

#include "lohner_frame.hpp"
#include "quadratic_form.hpp"

namespace furuta::validated::detail {

Doubleton initial_doubleton(const Box& x0, const IntegratorOptions& options) {
  const std::size_t n = x0.size();
  const auto en = static_cast<Eigen::Index>(n);
  Doubleton start;
  start.t = options.t_start;
  start.origin = x0.mid();
  start.r0.resize(n);
  for (std::size_t v = 0; v < n; ++v) start.r0[v] = x0[v] - Interval(start.origin[v]);
  start.m = start.origin;
  start.c = Matrix::Identity(en, en);
  start.b = Matrix::Identity(en, en);
  start.r.assign(n, Interval(0.0));
  start.x = x0;
  start.h_next = std::min(options.h_initial, options.h_max);
  return start;
}

Doubleton restart_doubleton(const std::vector<Tape>& tapes, const Tube& tube, std::size_t step,
                            const Box& piece, const IntegratorOptions& options) {
  const std::size_t n = piece.size();
  const TubeStep& at = tube.steps[step];
  const auto en = static_cast<Eigen::Index>(n);

  // The restart state: the doubleton of step `step` at its t0, re-centred on the piece. With
  // o' = mid(piece) and rho' = x0 - o' = rho - (o' - o): m + C rho = (m + C (o' - o)) + C rho',
  // the new centre's rounding goes to r through an enclosure of B^-1.
  Doubleton state;
  state.t = at.t0;
  state.origin = piece.mid();
  state.r0.resize(n);
  state.c = Matrix(en, en);
  state.b = Matrix(en, en);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      state.c(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = at.c[i * n + j];
      state.b(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = at.b[i * n + j];
    }
  }
  std::vector<Interval> shift(n);
  for (std::size_t v = 0; v < n; ++v) {
    state.r0[v] = piece[v] - Interval(state.origin[v]);
    shift[v] = Interval(state.origin[v]) - Interval(at.origin[v]);
  }
  const std::vector<Interval> moved = from_point(state.c) * shift;
  std::vector<Interval> residual(n);
  state.m.resize(n);
  for (std::size_t v = 0; v < n; ++v) {
    const Interval centre = at.centre[v] + moved[v];
    state.m[v] = centre.mid();
    residual[v] = centre - Interval(state.m[v]);
  }
  // The quadratic part: P(rho' + shift) = P(rho') + (the terms with shift), the latter enclosed
  // over the piece's r0 and put into r with the centre's rounding.
  if (!at.quad.empty()) {
    state.p = at.quad;
    const std::size_t pairs = pair_count(n);
    for (std::size_t v = 0; v < n; ++v) {
      std::size_t k = 0;
      for (std::size_t a = 0; a < n; ++a) {
        for (std::size_t bb = a; bb < n; ++bb, ++k) {
          const double coefficient = at.quad[v * pairs + k];
          if (coefficient == 0.0) continue;
          const Interval terms =
              state.r0[a] * shift[bb] + shift[a] * state.r0[bb] + shift[a] * shift[bb];
          residual[v] += Interval(coefficient) * terms;
        }
      }
    }
  }
  // Constant components (method step 9) keep the confined form: such a component is x0_v at
  // every time, so with its row of C a unit row, its row of P zero and no error part it is
  // exactly origin'_v + rho'_v: the centre origin'_v, no residual. The live components' residual
  // then goes to r_L through B_LL^-1 alone (r_K stays exactly 0).
  const std::vector<std::size_t> live = live_components(tapes, n);
  std::vector<bool> is_live(n, false);
  for (std::size_t v : live) is_live[v] = true;
  bool confined = live.size() < n && confined_to_live(state.b, at.r, is_live);
  const std::size_t pairs = pair_count(n);
  for (std::size_t v = 0; v < n && confined; ++v) {
    if (is_live[v]) continue;
    for (std::size_t j = 0; j < n; ++j)
      confined = confined && at.c[v * n + j] == (v == j ? 1.0 : 0.0);
    for (std::size_t a = 0; a < pairs && !at.quad.empty(); ++a) {
      confined = confined && at.quad[v * pairs + a] == 0.0;
    }
  }
  state.r = at.r;
  if (confined) {
    const auto el = static_cast<Eigen::Index>(live.size());
    Matrix b_live(el, el);
    for (std::size_t a = 0; a < live.size(); ++a) {
      for (std::size_t col = 0; col < live.size(); ++col) {
        b_live(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(col)) =
            state.b(static_cast<Eigen::Index>(live[a]), static_cast<Eigen::Index>(live[col]));
      }
    }
    const std::optional<IMatrix> b_inv = frame_inverse(b_live);
    if (!b_inv) throw std::invalid_argument("integrate_sub_box: the step's frame is singular");
    std::vector<Interval> residual_live(live.size());
    for (std::size_t a = 0; a < live.size(); ++a) residual_live[a] = residual[live[a]];
    const std::vector<Interval> residual_r = *b_inv * residual_live;
    for (std::size_t a = 0; a < live.size(); ++a) state.r[live[a]] += residual_r[a];
    for (std::size_t v = 0; v < n; ++v) {
      if (!is_live[v]) state.m[v] = state.origin[v];
    }
  } else {
    const std::optional<IMatrix> b_inv = frame_inverse(state.b);
    if (!b_inv) throw std::invalid_argument("integrate_sub_box: the step's frame is singular");
    const std::vector<Interval> residual_r = *b_inv * residual;
    for (std::size_t v = 0; v < n; ++v) state.r[v] += residual_r[v];
  }
  // The box: the re-centred doubleton, inside the parent's box at t0.
  const std::vector<Interval> part0 = from_point(state.c) * state.r0;
  const std::vector<Interval> part1 = from_point(state.b) * state.r;
  const std::vector<Interval> part2 = forms_range(state.p, state.r0);
  const Box& parent_box = step == 0 ? tube.initial : tube.steps[step - 1].end;
  state.x = Box(n);
  for (std::size_t v = 0; v < n; ++v) {
    state.x[v] = (Interval(state.m[v]) + part0[v] + part2[v] + part1[v]) & parent_box[v];
  }
  if (step == 0) state.x = intersect(state.x, piece);
  state.h_next = std::min(at.h.hi(), options.h_max);
  return state;
}

}  // namespace furuta::validated::detail
