#pragma once
// The output-error refinement's, SIVIA's and the scenarios' progress on stderr, one line rewritten
// in place (identify, simulate and the trigger show it when stderr is a terminal).

#include <chrono>
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
  void windows(std::size_t done, std::size_t total) override {
    if (!started_windows_) {
      started_windows_ = true;
      started_ = std::chrono::steady_clock::now();
    }
    const double s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
    std::fprintf(stderr, "\rguaranteed: %zu of at most %zu window steps, %.0f s   ", done, total,
                 s);
    std::fflush(stderr);
  }
  void windows_done() override {
    if (started_windows_) std::fprintf(stderr, "\n");
  }
  void scenario(const validated::Scenario& scenario, const std::string& set) override {
    std::fprintf(stderr, "\rscenario %s, %s parameters: integrating %.1f s ...        ",
                 report::scenario_label(scenario).c_str(), set.c_str(), scenario.duration_s);
    std::fflush(stderr);
  }
  void scenarios_done() override { std::fprintf(stderr, "\r%60s\r", ""); }

 private:
  bool started_output_error_ = false;
  bool started_windows_ = false;
  std::chrono::steady_clock::time_point started_;
};

}  // namespace furuta::app
