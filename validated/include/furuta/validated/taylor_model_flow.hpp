#pragma once
// Validated integration with the set as a Taylor model: every solution
// from x0 = mid(x0) + rad(x0) z (z in [-1, 1]^n; the parameters carried as state are variables
// like the rest) is at time t in p(z) + B r for some r in the interval vector r, where p is a
// polynomial of order `space_order` in z. One step: the Taylor map of p computed in Taylor-model
// arithmetic (TaylorRunner<TaylorModel>), the error part carried through the map's Jacobian over
// the set (as Taylor models of order `jacobian_order` in z) in Lohner's frame (parallelepiped or
// QR, as the doubleton integrator), the models' remainders and the Lagrange remainder going into
// the error part; then, when it can be done, the error part shrink-wrapped into p (the start
// variables widened, Makino and Berz), so that it is carried with the flow's dependence on z.
//
// It carries the start's and the parameters' influence to order `space_order` exactly, where the
// doubleton integrator (integrator.hpp) stops at order 2; it does not split (split.hpp splits
// the doubleton integrator's runs).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/validated/integrator.hpp"
#include "furuta/validated/taylor.hpp"
#include "furuta/validated/taylor_model.hpp"

namespace furuta::validated {

struct TaylorModelFlowOptions {
  // Steps (order = the Taylor order in time, tolerance, h_min, h_max, h_initial), max_width,
  // max_inflation (1: the QR frame), t_start, t_end; quadratic_* and max_excess are not used.
  IntegratorOptions integrator;
  int space_order = 3;  // the models' order in z (1..4 for 11 variables: MonomialSpace's limit)
  // The order in z of the Taylor models the error part's Jacobian is computed in (0: over the
  // set's box in intervals only; at most space_order).
  int jacobian_order = 1;
  // Shrink wrapping after each step when the start variables need widening by at most this
  // (0: never): the error part goes into the polynomial (shrink_wrap.hpp).
  double shrink_wrap_max_delta = 1.0;
  // When the whole error part cannot be wrapped, wrap it with one start variable left out (the
  // one whose column has collapsed onto the others, found as the one whose leaving out needs the
  // least widening) and keep the error along that variable's own component in the error part.
  // For a stiff, damped direction (the Furuta arm's velocity, whose start column ends in the
  // pendulum's slow directions: the Furuta tubes go much further with it); the pendulum's tube is
  // shorter with it (docs/measurements/taylor-model-flow.md, "Taylor models IV").
  bool wrap_without_collapsed = false;
  // Shrink wrapping's preconditioner as a function of the whole start point, not only of the
  // carried parameters (shrink_wrap.hpp): tighter where the start box is narrow against the
  // parameters' spread (the Furuta tubes: docs/measurements/taylor-model-flow.md, "Taylor models
  // V"), looser where the slots' derivatives vary much over the start box (the pendulum with its
  // stiffness carried).
  bool wrap_at_base_point = false;
  // Keep each step's end set as models (TaylorModelFlowStep::end_models): what set inversion
  // tests data against. Costs a copy of the polynomials per step.
  bool keep_end_models = false;
};

struct TaylorModelFlowStep {
  double t0 = 0.0;
  double t1 = 0.0;
  Box over;                      // every solution over [t0, t1]
  Box end;                       // every solution at t1
  double remainder_width = 0.0;  // the widest component of the error part B r at t1
  // With keep_end_models: component v at t1 is in end_models[v] for some z in [-1, 1]^n: the
  // polynomial with the error part (B r)_v in its remainder. The variables of the carried
  // parameters keep their meaning (parameter = mid + rad z) through the whole flow; the start
  // variables do until the first shrink wrap, which widens them into the error they absorb, so
  // after it they only range over [-1, 1].
  std::vector<TaylorModel> end_models;
  // The error part was wrapped into the start variables at t1: the steps after this one have
  // start variables of their own (the parameters' are the same).
  bool wrapped = false;
  // With `wrapped`, per variable: a solution represented by variables z before the wrap is
  // represented after it by z' with wrap_scale[v] z'_v - z_v in [-wrap_delta[v], wrap_delta[v]]
  // (1 and 0 for the variables the wrap left alone, the parameters' among them): how the start
  // variables of the steps after the wrap are tied to those before.
  std::vector<double> wrap_scale, wrap_delta;
};

struct TaylorModelFlowResult {
  std::vector<TaylorModelFlowStep> steps;
  Box initial;
  double t_start = 0.0;
  IntegrationResult::Status status = IntegrationResult::Status::ok;
  std::string reason;                   // why it ended early
  std::optional<WidthStop> width_stop;  // when max_width ended it: its numbers
  std::size_t rejected = 0;
  std::size_t shrink_wraps = 0;   // steps whose error part was wrapped into the polynomial
  std::size_t partial_wraps = 0;  // of them, with a start variable left out
  double seconds = 0.0;

  bool ok() const { return status == IntegrationResult::Status::ok; }
  double t_reached() const { return steps.empty() ? t_start : steps.back().t1; }
  // The step's end box at a step's end, its box over the step inside it; empty outside.
  Box enclosure_at(double t) const;
};

// Invalid arguments (as integrate_tapes, plus space_order outside 1..12 or too many monomials)
// throw std::invalid_argument; an integration that cannot go on is a status.
TaylorModelFlowResult integrate_taylor_models(const std::vector<Tape>& tapes,
                                              const std::vector<double>& switches, const Box& x0,
                                              const TaylorModelFlowOptions& options);

template <class System>
TaylorModelFlowResult integrate_taylor_models(const System& system, const Box& x0,
                                              const TaylorModelFlowOptions& options) {
  return integrate_taylor_models(record_system(system), switch_times(system), x0, options);
}

// The flow's steps as a Tube (integrator.hpp) of the same enclosures: each step's box over it and
// at its end, no Taylor form (inside a step the enclosure is its box over the step), `order` 0.
// What the doubleton's tubes are read with (coverage.hpp) then reads the flow's.
Tube as_tube(const TaylorModelFlowResult& result);

}  // namespace furuta::validated
