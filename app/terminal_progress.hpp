#pragma once
// SIVIA's and the scenarios' progress on stderr, one line rewritten in place (identify, simulate
// and the trigger show it when stderr is a terminal).

#include <cstdio>
#include <string>

#include "furuta/pipeline/pipeline.hpp"
#include "furuta/report/tables.hpp"

namespace furuta::app {

class TerminalProgress : public pipeline::Progress {
 public:
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
};

}  // namespace furuta::app
