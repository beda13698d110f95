#pragma once
// The Taylor-model flow's step, resumable from any state (internal to the validated library):
// integrate_taylor_models runs it from x0 to t_end; the splitting flow
// (taylor_model_split.cpp) restarts it from a saved state restricted to a part of one variable.

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "a_priori.hpp"
#include "furuta/validated/taylor_model_flow.hpp"
#include "interval_matrix.hpp"
#include "jets.hpp"
#include "lohner_frame.hpp"

namespace furuta::validated::detail {

// What every run from one x0 shares, read only: the checked arguments and the models' spaces
// (every state's models live in `space`).
struct TaylorModelFlowSetup {
  TaylorModelFlowSetup(const std::vector<Tape>& tapes, const std::vector<double>& switches,
                       const Box& x0, const TaylorModelFlowOptions& options);

  const std::vector<Tape>& tapes;
  const std::vector<double>& switches;
  TaylorModelFlowOptions options;
  std::size_t n;
  std::shared_ptr<const MonomialSpace> space;
  std::shared_ptr<const MonomialSpace> jacobian_space;
  std::vector<std::size_t> wrap_slots;  // the start variables the error part may be wrapped into
};

// The set at time t: every solution is in p(z) + B r for some z in [-1, 1]^n and r in r. p's
// models are polynomials on the live components; on the constant ones (the carried parameters)
// they may keep a remainder (a restriction's rounding), and B r is zero there.
struct TaylorModelFlowState {
  std::vector<TaylorModel> p;
  Matrix b;
  std::vector<Interval> r;
  LiveSet live;
  double t = 0.0;
  double h_next = 0.0;
  bool wrapped = false;  // the last step's error part went into p (r holds only rounding)
};

TaylorModelFlowState initial_flow_state(const TaylorModelFlowSetup& setup, const Box& x0);

// The scratch of the Taylor runs (one per thread).
struct TaylorModelFlowRunners {
  TaylorRunner<Interval> intervals;
  TaylorRunner<TaylorModel> models;
  TaylorRunner<Grad<kMaxDimension>> gradients;
  TaylorRunner<Grad<kMaxDimension, TaylorModel>> model_gradients;
};

struct TaylorModelFlowFailure {
  IntegrationResult::Status status;
  std::string reason;
  std::optional<WidthStop> width = std::nullopt;
};

// One step from state.t (< t_end): appends the step to result (steps, rejected, shrink_wraps,
// partial_wraps) and advances the state, or returns why it cannot (state and steps unchanged).
std::optional<TaylorModelFlowFailure> taylor_model_flow_step(const TaylorModelFlowSetup& setup,
                                                             TaylorModelFlowRunners& runners,
                                                             TaylorModelFlowState& state,
                                                             TaylorModelFlowResult& result);

}  // namespace furuta::validated::detail
