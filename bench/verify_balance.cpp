// What the balance controller designed from the main job's output-error estimate is proven to do:
// `furuta controller verify` on it, for the parameter box of the estimate +- 3 and +- 30 standard
// deviations, from the start (the pendulum within 2 deg and 10 deg/s of upright) and with
// the largest certified start; per case whether it is certified, why not, the pieces of the
// parameter box, the sampled check's counts and the command's wall time (the proof, the start
// region's bisection, the sampled check and the report).
//
//   verify_balance [--results tests/data/golden/results.json] [--horizon 10] [--sd 3,30]
//                  [--max-pieces 32] [--start-region]
//
// Figures, never pass/fail: docs/control.md keeps the table with this command.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  using furuta::app::kExitNotDone;
  CLI::App app("The balance controller's verification: certified or why not, and how long");
  std::string results = FURUTA_SOURCE_DIR "/tests/data/golden/results.json";
  double horizon_s = 10;
  std::vector<double> sds{3, 30};
  std::size_t max_pieces = 32;
  bool start_region = false;
  app.add_option("--results", results, "The identification whose output-error estimate is used");
  app.add_option("--horizon", horizon_s, "Seconds to prove");
  app.add_option("--sd", sds, "Standard deviations each side, one case each")->delimiter(',');
  app.add_option("--max-pieces", max_pieces, "Pieces of the parameter box at most");
  app.add_flag("--start-region", start_region, "Also bisect the largest certified start");
  CLI11_PARSE(app, argc, argv);

  const fs::path dir = fs::temp_directory_path() / ("verify_balance-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  furuta::app::ControllerDesignOptions design;
  design.results = results;
  design.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  design.output = dir / "controller.toml";
  std::ostringstream design_text;
  if (furuta::app::run_controller_design_command(design, design_text, std::cerr) != 0) {
    return kExitNotDone;
  }
  std::cout << "controller: output-error parameters of " << results << ", horizon " << horizon_s
            << " s\n";
  for (const double sd : sds) {
    furuta::app::ControllerVerifyOptions verify;
    verify.controller = design.output;
    verify.parameters = results;
    verify.sd = sd;
    verify.config_path = design.config_path;
    verify.horizon_s = horizon_s;
    verify.max_pieces = max_pieces;
    verify.start_region = start_region;
    verify.output_dir = dir / ("sd" + std::to_string(static_cast<int>(sd)));
    std::ostringstream text;
    const auto began = std::chrono::steady_clock::now();
    const int status = furuta::app::run_controller_verify_command(verify, text, std::cerr);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
    std::cout << "\n+- " << sd << " sd: exit " << status << ", " << seconds << " s wall\n"
              << text.str();
  }
  fs::remove_all(dir);
  return 0;
}
