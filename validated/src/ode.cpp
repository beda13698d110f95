#include "furuta/validated/ode.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace furuta::validated {

model::Parameters<Interval> interval_parameters(const model::Parameters<double>& p) {
  return parameters_around(p, 0.0);
}

model::Parameters<Interval> parameters_around(const model::Parameters<double>& p, double relative) {
  if (!(relative >= 0.0)) throw std::invalid_argument("parameters_around: relative < 0");
  const Interval factor = Interval(1.0) + Interval(-relative, relative);
  return p.map([&](double v) { return relative == 0.0 ? Interval(v) : Interval(v) * factor; });
}

std::vector<InputPiece> checked_pieces(std::vector<InputPiece> pieces) {
  if (pieces.empty()) throw std::invalid_argument("Furuta dynamics: no input piece");
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (!std::isfinite(pieces[i].t_start) || pieces[i].tau.is_empty() ||
        !pieces[i].tau.is_bounded()) {
      throw std::invalid_argument("Furuta dynamics: piece with a non-finite time or torque");
    }
    if (i > 0 && !(pieces[i].t_start > pieces[i - 1].t_start)) {
      throw std::invalid_argument("Furuta dynamics: pieces not in increasing time order");
    }
  }
  return pieces;
}

std::vector<double> piece_switch_times(const std::vector<InputPiece>& pieces) {
  std::vector<double> times;
  for (std::size_t i = 1; i < pieces.size(); ++i) times.push_back(pieces[i].t_start);
  return times;
}

FurutaDynamics::FurutaDynamics(const Interval& tau) : pieces_{InputPiece{0.0, tau}} {}

FurutaDynamics::FurutaDynamics(std::vector<InputPiece> pieces)
    : pieces_(checked_pieces(std::move(pieces))) {}

FurutaStateDynamics::FurutaStateDynamics(const model::Parameters<Interval>& p, const Interval& tau)
    : FurutaStateDynamics(p, std::vector<InputPiece>{InputPiece{0.0, tau}}) {}

FurutaStateDynamics::FurutaStateDynamics(const model::Parameters<Interval>& p,
                                         std::vector<InputPiece> pieces)
    : p_(p), pieces_(checked_pieces(std::move(pieces))) {
  for (const Interval* v : {&p.mu1, &p.mu2, &p.mu3, &p.mu4, &p.mug, &p.fv1, &p.fv2}) {
    if (v->is_empty() || !v->is_bounded()) {
      throw std::invalid_argument("FurutaStateDynamics: empty or unbounded parameter");
    }
  }
}

FurutaRampedDynamics::FurutaRampedDynamics(std::vector<InputPiece> rate_pieces)
    : pieces_(checked_pieces(std::move(rate_pieces))) {}

Box FurutaRampedDynamics::initial_box(const Box& state, const model::Parameters<Interval>& p,
                                      const Interval& u0) {
  const Box x = FurutaDynamics::initial_box(state, p);
  std::vector<Interval> components(x.begin(), x.end());
  components.push_back(u0);
  return Box(std::move(components));
}

Box FurutaDynamics::initial_box(const Box& state, const model::Parameters<Interval>& p) {
  if (state.size() != 4) throw std::invalid_argument("FurutaDynamics::initial_box: state size 4");
  return Box{state[0], state[1], state[2], state[3], p.mu1, p.mu2,
             p.mu3,    p.mu4,    p.mug,    p.fv1,    p.fv2};
}

}  // namespace furuta::validated
