#pragma once
// The output-error refinement's, SIVIA's and the scenarios' progress on stderr, one line rewritten
// in place (identify, simulate and the trigger show it when stderr is a terminal).

#include <cstdio>
#include <string>

#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::app {

class TerminalProgress : public pipeline::Progress {
 public:
  void output_error_started(std::size_t experiments) override {
    std::fprintf(stderr, "output error: refining over %zu experiment(s) ...", experiments);
    std::fflush(stderr);
    started_output_error_ = true;
  }
  void fit_done(const identification::Identification& /*id*/,
                const identification::OutputErrorResult* refined) override {
    if (!started_output_error_) return;
    if (refined != nullptr) {
      std::fprintf(stderr, " %d iterations, %s\n", refined->iterations,
                   refined->converged ? "converged" : "not converged");
    } else {
      std::fprintf(stderr, " skipped\n");
    }
  }
  void sivia(std::size_t tested, std::size_t pending) override {
    std::fprintf(stderr, "\rSIVIA: %zu boxes tested, %zu pending   ", tested, pending);
    std::fflush(stderr);
  }
  void sivia_done() override { std::fprintf(stderr, "\n"); }
  void scenario(const validated::Scenario& scenario, const std::string& set) override {
    std::fprintf(stderr, "\rscenario %s, %s parameters: integrating %.1f s ...        ",
                 report::scenario_label(scenario).c_str(), set.c_str(), scenario.duration_s);
    std::fflush(stderr);
  }
  void scenarios_done() override { std::fprintf(stderr, "\r%60s\r", ""); }

 private:
  bool started_output_error_ = false;
};

}  // namespace furuta::app
