// The CSV importer (and its import spec parser) on arbitrary input. An input is
//   <import spec TOML>\n%%\n<CSV>
// or, without the %% line, a CSV read with one of a few fixed specs chosen by its length. Either it
// imports a series that is uniform, finite and as long as promised, or it throws CsvImportError /
// ConfigError; any other exception, a crash, UB or a hang is a finding.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/csv_import.hpp"

using namespace furuta::identification;

namespace {

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

const std::filesystem::path& temp_csv() {
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("furuta-fuzz-csv-" + std::to_string(getpid()) + ".csv");
  return path;
}

// The shapes the importer's tests use: header names, column numbers, degrees, counts, a voltage
// rig.
constexpr const char* kSpecs[] = {
    "[csv]\ntime = \"t\"\narm_angle = \"q1\"\npendulum_angle = \"q2\"\ninput = \"u\"\n"
    "time_unit = \"s\"\nangle_unit = \"rad\"\npendulum_zero = \"down\"\ninput_kind = \"duty\"\n",
    "[csv]\nhas_header = false\ndelimiter = \";\"\ntime = \"1\"\narm_angle = \"2\"\n"
    "pendulum_angle = \"3\"\ninput = \"4\"\ntime_unit = \"ms\"\nangle_unit = \"deg\"\n"
    "pendulum_zero = \"up\"\ninput_kind = \"torque\"\n",
    "[csv]\ntime = \"t\"\narm_angle = \"a\"\npendulum_angle = \"b\"\ninput = \"v\"\n"
    "time_unit = \"us\"\nangle_unit = \"counts\"\narm_counts_per_rev = 4096\n"
    "pendulum_counts_per_rev = 2000\npendulum_zero = \"up\"\ninput_kind = \"voltage\"\n"
    "[motor]\ntorque_constant_nm_per_a = 0.05\nback_emf_v_s_per_rad = 0.05\nresistance_ohm = 2.5\n",
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);
  CsvImportSpec spec;
  std::string_view csv = input;
  const std::size_t split = input.find("\n%%\n");
  try {
    if (split != std::string_view::npos) {
      spec = parse_csv_import_spec(std::string(input.substr(0, split)), "fuzz.toml");
      csv = input.substr(split + 4);
    } else {
      spec = parse_csv_import_spec(kSpecs[size % std::size(kSpecs)], "fixed.toml");
    }
  } catch (const furuta::config::ConfigError& e) {
    check(e.file() == "fuzz.toml");
    return 0;
  }
  {
    std::ofstream out(temp_csv(), std::ios::binary | std::ios::trunc);
    out.write(csv.data(), static_cast<std::streamsize>(csv.size()));
  }
  try {
    const ImportedSeries s = import_csv(temp_csv(), spec);
    check(s.t_s.size() == s.q1_rad.size() && s.t_s.size() == s.q2_rad.size() &&
          s.t_s.size() == s.input.size());
    check(s.t_s.size() >= 2);
    check(std::isfinite(s.sample_period_s) && s.sample_period_s > 0);
    for (std::size_t i = 0; i < s.t_s.size(); ++i) {
      check(std::isfinite(s.t_s[i]));
      if (i > 0) check(s.t_s[i] >= s.t_s[i - 1]);
    }
  } catch (const CsvImportError& e) {
    check(e.file() == temp_csv().string());
  }
  return 0;
}
