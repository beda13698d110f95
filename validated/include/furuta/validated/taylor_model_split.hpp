#pragma once
// The Taylor-model flow (taylor_model_flow.hpp) split where one tube fails: the set, a polynomial
// in z in [-1, 1]^n, is cut in half along one variable z_i (p(z) restricted to z_i in [-1, 0] and
// [0, 1], re-expanded in a new z_i: TaylorModel::restricted) and the halves go on, in parallel.
//
//   TaylorModelSplitResult r = integrate_taylor_models_split(FurutaDynamics(tau), x0, options, {});
//   Box at_1s = r.enclosure_at(1.0);  // the hull over the pieces
//
// A failed piece is cut at one of its own earlier states, the last whose error part (p's
// remainders and the Lohner part B r) is at most 0.1 % of p's spread in every component the field
// reads (there the halves of p are nearly the halves of the whole set) at or before `restart_back`
// of the way back from the failure to the piece's start; else at the piece's start. The variable
// cut is the one with the largest share of the field's read, moving components' spread in that
// state's polynomial (each monomial's coefficient shared among its variables by their exponents):
// after shrink wrapping a start variable stands for the start and the error wrapped into it, so
// this is the direction the set is widest in now, not at t_start.
//
// Sound piece by piece: every solution is at each time in the union of the pieces' enclosures
// (each piece's steps before its cut are its ancestors', which enclose a larger set). Unlike the
// doubleton's split (split.hpp), the pieces are not boxes of x0: a cut after a wrap divides the
// set at that time. Deterministic: a generation's runs do not depend on the threads' schedule.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/validated/taylor_model_flow.hpp"

namespace furuta::validated {

struct TaylorModelSplitOptions {
  std::size_t max_pieces = 16;  // the most pieces the run may end with
  int max_depth = 8;            // the most cuts between x0 and a piece
  // Where a failed piece is cut: its last state with a small error part at or before this fraction
  // of the way back from the failure to the piece's own start (0: the last one; 1: the start).
  double restart_back = 0.25;
  int threads = 0;  // TBB threads (0: every core)
};

struct TaylorModelSplitResult {
  // Each piece's run from t_start (its ancestors' steps before its cut included; its counters,
  // rejected, shrink_wraps, partial_wraps and seconds, its own run's alone), in the order of the
  // cutting tree ('0' the lower half); paths[i] is pieces[i]'s path.
  std::vector<TaylorModelFlowResult> pieces;
  std::vector<std::string> paths;
  IntegrationResult::Status status = IntegrationResult::Status::ok;  // ok when all reached t_end
  double t_reached = 0.0;               // the smallest t_reached() over the pieces
  std::string reason;                   // the first failed piece's reason (in piece order)
  std::optional<WidthStop> width_stop;  // that piece's, when max_width ended it
  std::size_t splits = 0;               // cuts made
  std::vector<std::size_t> cuts;        // cuts per variable (x0's components)
  std::size_t runs = 0;                 // runs (pieces and their ancestors)
  std::size_t steps = 0;                // steps over all runs (shared prefixes counted once)
  double seconds = 0.0;                 // wall time
  // The sum over the cutting tree's generations of their longest run: the wall time with a core
  // for every run of a generation.
  double critical_path_seconds = 0.0;

  bool ok() const { return status == IntegrationResult::Status::ok; }
  // The hull of the pieces' enclosures at t; empty outside [t_start, t_reached].
  Box enclosure_at(double t) const;
};

// Invalid arguments throw std::invalid_argument (integrate_taylor_models's, and max_pieces = 0,
// max_depth < 0, restart_back outside [0, 1]).
TaylorModelSplitResult integrate_taylor_models_split(const std::vector<Tape>& tapes,
                                                     const std::vector<double>& switches,
                                                     const Box& x0,
                                                     const TaylorModelFlowOptions& options,
                                                     const TaylorModelSplitOptions& split);

template <class System>
TaylorModelSplitResult integrate_taylor_models_split(const System& system, const Box& x0,
                                                     const TaylorModelFlowOptions& options,
                                                     const TaylorModelSplitOptions& split = {}) {
  return integrate_taylor_models_split(record_system(system), switch_times(system), x0, options,
                                       split);
}

}  // namespace furuta::validated
