#pragma once
// Validated integration by splitting the initial box (state and parameters carried as state)
// where one tube would blow up (see validated/README.md, "Splitting").
//
//   SplitResult r = integrate_split(FurutaDynamics(tau), x0, options, split_options);
//   if (!r.ok()) ... r.t_reached, r.reason
//   Box at_1s = r.enclosure_at(1.0);          // the hull over the pieces
//   coverage(r.tubes());                       // every piece's tube, each sound on its own
//
// A run that fails (or whose error part outgrows the exactly carried part, options.max_excess)
// is bisected: the halves of its initial box restart, in parallel, from the last step of its tube
// where the set was still tight (the doubleton's fixed box r0 is cut in two and re-centred, see
// integrate_sub_box), down to a cap on pieces and depth. The result is deterministic (it does not
// depend on the threads' schedule) and its pieces are in the order of the bisection tree.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "furuta/interval/box.hpp"
#include "furuta/validated/integrator.hpp"

namespace furuta::validated {

struct SplitOptions {
  std::size_t max_pieces = 64;  // the most pieces the run may end with
  int max_depth = 12;           // the most bisections between x0 and a piece
  // A failed piece's halves restart from the last step of its tube where, in every component,
  // the error part of the set was at most this times the exactly carried part (else from the
  // start): the halves inherit that step's accumulated error, so it must still be small.
  double restart_excess = 0.5;
  int threads = 0;  // TBB threads (0: every core)
  // Planned splitting, before any failure: the run goes to `planned_split_s` as one tube, then
  // its initial box is bisected `planned_depth` times (2^depth pieces, each bisection in the
  // direction with the largest share of the moving components' spread at that time, from the
  // tube's first-order coefficients C) and the pieces continue from
  // there. Each piece's second-order leftovers (third order in its box) shrink with it, while
  // the error part inherited at the split is still small; the failure-driven splitting above
  // then works on the pieces. 0: none.
  int planned_depth = 0;
  double planned_split_s = 0.0;  // absolute time, in [t_start, t_end)
};

struct SplitResult {
  // The pieces' tubes; their initial boxes cover x0 (pieces of a bisection tree) and each tube
  // encloses every solution from its own initial box over [t_start, its t_end()].
  std::vector<Tube> pieces;
  IntegrationResult::Status status = IntegrationResult::Status::ok;  // ok when all reached t_end
  double t_reached = 0.0;               // the smallest t_end() over the pieces
  std::string reason;                   // the first failed piece's reason (in piece order)
  std::optional<WidthStop> width_stop;  // that piece's, when max_width ended it
  std::size_t splits = 0;               // bisections done
  std::size_t runs = 0;                 // integrations run (pieces and their ancestors)
  std::size_t steps = 0;                // steps over all runs (the shared prefixes counted once)
  double seconds = 0.0;                 // wall time

  bool ok() const { return status == IntegrationResult::Status::ok; }
  // The pieces' tubes, for code that takes a list of tubes (coverage).
  std::vector<const Tube*> tubes() const;
  // The hull of the pieces' enclosures at t; a box of empty intervals outside
  // [t_start, t_reached] (there some piece has no enclosure, the hull would not hold).
  Box enclosure_at(double t) const;
  // The hull over [ta, tb] intersected with [t_start, t_reached] (empty when that is empty).
  Box enclosure_over(double ta, double tb) const;
};

// The splitting integrator on recorded fields (integrate_tapes's arguments). Invalid arguments
// throw std::invalid_argument (also max_pieces = 0, max_depth < 0, restart_excess < 0).
SplitResult integrate_split_tapes(const std::vector<Tape>& tapes,
                                  const std::vector<double>& switches, const Box& x0,
                                  const IntegratorOptions& options, const SplitOptions& split);

template <class System>
SplitResult integrate_split(const System& system, const Box& x0, const IntegratorOptions& options,
                            const SplitOptions& split = {}) {
  return integrate_split_tapes(record_system(system), switch_times(system), x0, options, split);
}

}  // namespace furuta::validated
