#include "furuta/identification/csv_import.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "furuta/config/rig_config.hpp"
#include "furuta/identification/preprocessing.hpp"  // VoltageMotor
#include "temp_dir.hpp"

namespace furuta::identification {
namespace {

using config::ConfigError;
using ::testing::HasSubstr;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = std::numbers::pi / 180.0;

std::filesystem::path write_file(const testing::TempDir& dir, const std::string& name,
                                 const std::string& text) {
  const std::filesystem::path path = dir.path() / name;
  std::ofstream out(path, std::ios::binary);
  out << text;
  return path;
}

// The smallest spec that names every column and convention; tests add or change keys.
std::string spec_text(const std::string& extra = "") {
  return "[csv]\n"
         "time = \"t\"\n"
         "arm_angle = \"theta\"\n"
         "pendulum_angle = \"alpha\"\n"
         "input = \"u\"\n"
         "time_unit = \"s\"\n"
         "angle_unit = \"rad\"\n"
         "pendulum_zero = \"down\"\n"
         "input_kind = \"duty\"\n" +
         extra;
}

ConfigError spec_error(const std::string& text) {
  try {
    parse_csv_import_spec(text, "spec.toml");
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no ConfigError for:\n" << text;
  return ConfigError("", 0, "", "");
}

CsvImportError import_error(const std::filesystem::path& csv, const CsvImportSpec& spec) {
  try {
    import_csv(csv, spec);
  } catch (const CsvImportError& e) {
    return e;
  }
  ADD_FAILURE() << "no CsvImportError for " << csv;
  return CsvImportError("", 0, "", "");
}

// `rows` rows of t, theta, alpha, u at 10 ms, every value distinct, plus a header line.
std::string simple_csv(int rows) {
  std::ostringstream out;
  out << "t,theta,alpha,u\n";
  for (int k = 0; k < rows; ++k) out << k * 0.01 << "," << 0.1 * k << "," << -0.2 * k << ",0.5\n";
  return out.str();
}

TEST(CsvImport, MatlabStyleExportInDegreesWithUprightZeroMillisecondsAndVolts) {
  testing::TempDir dir;
  // What a MATLAB writetable on Windows looks like after a spreadsheet round trip: BOM, CRLF,
  // quoted names, columns in its own order, columns nobody asked for, blank lines at the end.
  std::ostringstream csv;
  csv << "\xEF\xBB\xBF\"current_A\",\"alpha_deg\",\"u_V\",\"time_ms\",\"theta_deg\",\"note\"\r\n";
  for (int k = 0; k < 20; ++k) {
    csv << 0.1 * k << "," << -10 + k << "," << 0.5 * k - 2 << "," << 16 * k << "," << 2 * k
        << ",\"a, b\"\r\n";
  }
  csv << "\r\n\r\n";
  const auto path = write_file(dir, "matlab.csv", csv.str());
  const CsvImportSpec spec = parse_csv_import_spec(
      "[csv]\n"
      "time = \"time_ms\"\ntime_unit = \"ms\"\n"
      "arm_angle = \"theta_deg\"\npendulum_angle = \"alpha_deg\"\nangle_unit = \"deg\"\n"
      "pendulum_zero = \"up\"\n"
      "input = \"u_V\"\ninput_kind = \"voltage\"\n"
      "[motor]\ntorque_constant_nm_per_a = 0.05\nback_emf_v_s_per_rad = 0.05\n"
      "resistance_ohm = 2.5\n",
      "spec.toml");

  const ImportedSeries s = import_csv(path, spec);
  ASSERT_EQ(s.t_s.size(), 20u);
  ASSERT_EQ(s.q1_rad.size(), 20u);
  ASSERT_EQ(s.q2_rad.size(), 20u);
  ASSERT_EQ(s.input.size(), 20u);
  EXPECT_EQ(s.input_kind, InputKind::voltage);
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_NEAR(s.sample_period_s, 0.016, 1e-15);
  for (int k = 0; k < 20; ++k) {
    SCOPED_TRACE(k);
    EXPECT_DOUBLE_EQ(s.t_s[k], 16 * k * 1e-3);  // kept as recorded, not shifted to zero
    EXPECT_DOUBLE_EQ(s.q1_rad[k], 2 * k * kDeg);
    EXPECT_DOUBLE_EQ(s.q2_rad[k], (-10 + k) * kDeg + kPi);
    EXPECT_DOUBLE_EQ(s.input[k], 0.5 * k - 2);
  }
  EXPECT_DOUBLE_EQ(s.q2_rad[10], kPi);  // alpha = 0 there: upright is q2 = pi
}

TEST(CsvImport, CountsWithPerColumnScalesSemicolonsAndMicroseconds) {
  testing::TempDir dir;
  std::ostringstream csv;
  csv << "time_us;arm;pend;duty_pct\n";
  for (int k = 0; k < 16; ++k) {
    csv << 1'000'000 + 8000 * k << ";" << 100 * k << ";" << 2000 - 50 * k << ";" << 30 - 4 * k
        << "\n";
  }
  const auto path = write_file(dir, "counts.csv", csv.str());
  const CsvImportSpec spec = parse_csv_import_spec(
      "[csv]\ndelimiter = \";\"\n"
      "time = \"time_us\"\ntime_unit = \"us\"\n"
      "arm_angle = \"arm\"\narm_angle_scale = -1\n"
      "pendulum_angle = \"pend\"\nangle_unit = \"counts\"\n"
      "arm_counts_per_rev = 4096\npendulum_counts_per_rev = 2000\n"
      "pendulum_zero = \"down\"\n"
      "input = \"duty_pct\"\ninput_scale = 0.01\ninput_kind = \"duty\"\n",
      "spec.toml");
  EXPECT_EQ(spec.delimiter, ';');
  EXPECT_DOUBLE_EQ(spec.arm_angle.scale, -1.0);

  const ImportedSeries s = import_csv(path, spec);
  ASSERT_EQ(s.t_s.size(), 16u);
  EXPECT_NEAR(s.sample_period_s, 0.008, 1e-12);
  EXPECT_TRUE(s.warnings.empty());
  EXPECT_DOUBLE_EQ(s.t_s[0], 1.0);  // absolute time kept
  for (int k = 0; k < 16; ++k) {
    SCOPED_TRACE(k);
    EXPECT_DOUBLE_EQ(s.q1_rad[k], -2 * kPi * 100 * k / 4096.0);
    EXPECT_DOUBLE_EQ(s.q2_rad[k], 2 * kPi * (2000 - 50 * k) / 2000.0);
    EXPECT_DOUBLE_EQ(s.input[k], (30 - 4 * k) * 0.01);
  }
  EXPECT_DOUBLE_EQ(s.q2_rad[0], 2 * kPi);  // one full turn stays one full turn: not wrapped
}

TEST(CsvImport, FileWithoutHeaderUsesOneBasedIndices) {
  testing::TempDir dir;
  std::ostringstream csv;
  for (int k = 0; k < 16; ++k)
    csv << 0.5 * k << "\t" << k << "\t" << 0.01 * k << "\t" << -k << "\n";
  const auto path = write_file(dir, "plain.tsv", csv.str());
  const CsvImportSpec spec = parse_csv_import_spec(
      "[csv]\ndelimiter = \"\\t\"\nhas_header = false\n"
      "time = \"3\"\narm_angle = \"4\"\npendulum_angle = \"02\"\ninput = \"1\"\n"
      "time_unit = \"s\"\nangle_unit = \"rad\"\npendulum_zero = \"down\"\ninput_kind = "
      "\"torque\"\n",
      "spec.toml");
  EXPECT_EQ(spec.pendulum_angle.name, "2");

  const ImportedSeries s = import_csv(path, spec);
  ASSERT_EQ(s.t_s.size(), 16u);
  EXPECT_EQ(s.input_kind, InputKind::torque);
  for (int k = 0; k < 16; ++k) {
    SCOPED_TRACE(k);
    EXPECT_DOUBLE_EQ(s.t_s[k], 0.01 * k);
    EXPECT_DOUBLE_EQ(s.q1_rad[k], -k);
    EXPECT_DOUBLE_EQ(s.q2_rad[k], k);
    EXPECT_DOUBLE_EQ(s.input[k], 0.5 * k);
  }
}

TEST(CsvImport, IrregularTimeStampsAreResampledWithAWarning) {
  testing::TempDir dir;
  // 10 ms steps, but the sample at 50 ms came 2 ms late and the one at 100 ms is missing.
  std::vector<double> t;
  for (int k = 0; k < 20; ++k) {
    if (k == 10) continue;
    t.push_back(k == 5 ? 0.052 : 0.01 * k);
  }
  auto theta = [](double x) { return x * x * 100; };  // curved: interpolation is visible
  std::ostringstream csv;
  csv.precision(17);
  csv << "t,theta,alpha,u\n";
  for (const double x : t) csv << x << "," << theta(x) << "," << 2 * x << "," << 1 - x << "\n";
  const auto path = write_file(dir, "irregular.csv", csv.str());

  const ImportedSeries s = import_csv(path, parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_NEAR(s.sample_period_s, 0.01, 1e-15);
  ASSERT_EQ(s.t_s.size(), 20u);  // 0 .. 190 ms, the missing sample restored
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_THAT(s.warnings[0], HasSubstr("irregular time stamps"));
  EXPECT_THAT(s.warnings[0], HasSubstr("a step of 20 ms at line 12"));  // 90 -> 110 ms
  EXPECT_THAT(s.warnings[0], HasSubstr("resampled by linear interpolation to 10 ms"));
  for (int k = 0; k < 20; ++k) EXPECT_NEAR(s.t_s[k], 0.01 * k, 1e-15) << k;

  // 50 ms lies between the rows at 40 and 52 ms; 100 ms halfway between 90 and 110 ms.
  const double w = 0.010 / 0.012;
  EXPECT_NEAR(s.q1_rad[5], theta(0.04) + w * (theta(0.052) - theta(0.04)), 1e-12);
  EXPECT_NEAR(s.q1_rad[6], theta(0.06), 1e-12);
  EXPECT_NEAR(s.q1_rad[10], 0.5 * (theta(0.09) + theta(0.11)), 1e-12);
  EXPECT_NEAR(s.q2_rad[10], 0.2, 1e-12);  // linear channels come back exact
  EXPECT_NEAR(s.input[10], 0.9, 1e-12);
  EXPECT_NEAR(s.q1_rad[19], theta(0.19), 1e-12);
}

TEST(CsvImport, JitterWithinOnePercentIsKeptAsRecorded) {
  testing::TempDir dir;
  std::ostringstream csv;
  csv.precision(17);
  csv << "t,theta,alpha,u\n";
  std::vector<double> t;
  for (int k = 0; k < 16; ++k) t.push_back(0.016 * k + (k % 2 ? 0.00005 : 0.0));  // +-0.3 %
  for (const double x : t) csv << x << ",0,0,0\n";
  const ImportedSeries s = import_csv(write_file(dir, "jitter.csv", csv.str()),
                                      parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_TRUE(s.warnings.empty());
  ASSERT_EQ(s.t_s.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_DOUBLE_EQ(s.t_s[i], t[i]);
  EXPECT_NEAR(s.sample_period_s, 0.016, 0.0001);
}

// Each angle and the input at their own times: kept as recorded (a repeated time is the same
// reading, kept once), and at the row times interpolated (angles) or held (the input).
TEST(CsvImport, EachReadingAtItsOwnTime) {
  testing::TempDir dir;
  std::ostringstream csv;
  csv.precision(17);
  csv << "t,theta,t_theta,alpha,t_alpha,u,t_u,vbus\n";
  for (int k = 0; k < 16; ++k) {
    const double t = 0.016 * k;
    // The arm read 4 ms before the row, the pendulum only every second row (copied in between),
    // the input written 1 ms after the row.
    const double t_alpha = 0.032 * (k / 2) - 0.002;
    csv << t << "," << 10 * (t - 0.004) << "," << t - 0.004 << "," << -t_alpha << "," << t_alpha
        << "," << (k % 3 == 0 ? 0.5 : -0.5) << "," << t + 0.001 << "," << 12 + 0.1 * (k % 2)
        << "\n";
  }
  const CsvImportSpec spec = parse_csv_import_spec(
      spec_text("arm_time = \"t_theta\"\npendulum_time = \"t_alpha\"\ninput_time = \"t_u\"\n"
                "input_rate_limit = 62.5\nsupply = \"vbus\"\n"),
      "spec.toml");
  EXPECT_EQ(spec.input_rate_limit_per_s, 62.5);
  const ImportedSeries s = import_csv(write_file(dir, "own.csv", csv.str()), spec);
  const RecordedSeries& r = s.recorded;
  ASSERT_EQ(r.q1_t_s.size(), 16u);
  EXPECT_NEAR(r.q1_t_s[3], 0.048 - 0.004, 1e-15);
  ASSERT_EQ(r.q2_t_s.size(), 8u);  // each pendulum reading once
  EXPECT_NEAR(r.q2_t_s[1], 0.030, 1e-15);
  EXPECT_NEAR(r.q2_rad[1], -0.030, 1e-15);
  ASSERT_EQ(r.input_t_s.size(), 16u);
  EXPECT_NEAR(r.input_t_s[0], 0.001, 1e-15);
  ASSERT_EQ(r.supply_v.size(), 16u);
  EXPECT_NEAR(r.supply_v[1], 12.1, 1e-12);
  EXPECT_EQ(s.input_rate_limit_per_s, 62.5);
  // At the rows: the arm's line through its readings, the pendulum's between its readings, the
  // input in force (row 3's own command comes 1 ms after the row).
  EXPECT_NEAR(s.q1_rad[3], 10 * 0.048, 1e-12);
  EXPECT_NEAR(s.q2_rad[3], -0.048, 1e-12);
  EXPECT_EQ(s.input[3], -0.5);
  EXPECT_EQ(s.input[4], 0.5);
}

TEST(CsvImport, AnOwnTimeThatGoesBackOrTwoValuesAtOneTimeNameTheLine) {
  testing::TempDir dir;
  const CsvImportSpec spec =
      parse_csv_import_spec(spec_text("arm_time = \"t_theta\"\n"), "spec.toml");
  const auto file = [&](int row, double t_theta, double theta) {
    std::ostringstream csv;
    csv << "t,theta,t_theta,alpha,u\n";
    for (int k = 0; k < 16; ++k) {
      csv << 0.01 * k << "," << (k == row ? theta : 0.1 * k) << ","
          << (k == row ? t_theta : 0.01 * k) << ",0,0\n";
    }
    return write_file(dir, "own.csv", csv.str());
  };
  const CsvImportError back = import_error(file(6, 0.03, 0.6), spec);
  EXPECT_EQ(back.line(), 8);
  EXPECT_EQ(back.field(), "t_theta");
  EXPECT_THAT(back.what(), HasSubstr("goes back from 0.05 on line 7"));
  const CsvImportError twice = import_error(file(6, 0.05, 0.7), spec);
  EXPECT_EQ(twice.line(), 8);
  EXPECT_EQ(twice.field(), "theta");
  EXPECT_THAT(twice.what(), HasSubstr("a second value at the same time"));
}

TEST(CsvImportSpec, OwnTimesRateLimitAndSupplyAreChecked) {
  EXPECT_THAT(spec_error(spec_text("input_rate_limit = 0\n")).what(),
              HasSubstr("spec.toml:10: csv.input_rate_limit"));
  EXPECT_THAT(spec_error(spec_text("arm_time = \"t\"\n")).what(),
              HasSubstr("csv.arm_time: same column as time"));
  std::string torque = spec_text("supply = \"v\"\n");
  torque.replace(torque.find("\"duty\""), 6, "\"torque\"");
  EXPECT_THAT(spec_error(torque).what(), HasSubstr("csv.supply: only applies when input_kind"));
}

// A recording's bounds for the guaranteed set: in the angle unit and column scale like the
// angles, each with the spec's file, line and key as its provenance.
TEST(CsvImportSpec, TheGuaranteedTableStatesTheRecordingsBounds) {
  const std::string table =
      "[guaranteed]\n"
      "arm_angle_error = 0.5\n"
      "pendulum_angle_error = 0.5\n"
      "pendulum_zero_error = 2.5\n"
      "lag_ms = [0.5, 3]\n"
      "arm_rest_speed_rad_s = 0.02\n";
  std::string counts = spec_text(
      "arm_counts_per_rev = 1000\npendulum_counts_per_rev = 4000\narm_angle_scale = -2\n"
      "supply = \"v\"\n");
  counts.replace(counts.find("\"rad\""), 5, "\"counts\"");
  const CsvImportSpec spec =
      parse_csv_import_spec(counts + table + "supply_error_v = 0.02\n", "spec.toml");
  ASSERT_TRUE(spec.bounds.has_value());
  const RecordingBounds& b = *spec.bounds;
  EXPECT_DOUBLE_EQ(b.arm_angle_error.value.hi(), 0.5 * 2 * 2 * kPi / 1000);
  EXPECT_DOUBLE_EQ(b.arm_angle_error.value.lo(), -b.arm_angle_error.value.hi());
  EXPECT_DOUBLE_EQ(b.pendulum_angle_error.value.hi(), 0.5 * 2 * kPi / 4000);
  EXPECT_DOUBLE_EQ(b.pendulum_zero.value.hi(), 2.5 * 2 * kPi / 4000);
  EXPECT_TRUE(b.lag.value.contains(0.0005));
  EXPECT_TRUE(b.lag.value.contains(0.003));
  EXPECT_FALSE(b.lag.value.contains(0.0));
  EXPECT_EQ(b.arm_rest_speed_rad_s, 0.02);
  EXPECT_DOUBLE_EQ(b.supply_error.value.hi(), 0.02);
  EXPECT_FALSE(b.supply.has_value());
  EXPECT_EQ(b.lag.source, InputSource::import_spec);
  EXPECT_EQ(b.lag.setting, "spec.toml:18 guaranteed.lag_ms");

  // Without a supply column the supply itself is stated; degrees are degrees.
  std::string degrees = spec_text();
  degrees.replace(degrees.find("\"rad\""), 5, "\"deg\"");
  const CsvImportSpec d =
      parse_csv_import_spec(degrees + table + "supply_v = [11.5, 12.5]\n", "spec.toml");
  EXPECT_DOUBLE_EQ(d.bounds->arm_angle_error.value.hi(), 0.5 * kDeg);
  ASSERT_TRUE(d.bounds->supply.has_value());
  EXPECT_EQ(d.bounds->supply->value.lo(), 11.5);
  EXPECT_FALSE(parse_csv_import_spec(spec_text(), "spec.toml").bounds.has_value());
}

TEST(CsvImportSpec, GuaranteedTableMistakesAreLocated) {
  const std::string base = spec_text() +
                           "[guaranteed]\n"
                           "arm_angle_error = 0.001\n"
                           "pendulum_angle_error = 0.001\n"
                           "pendulum_zero_error = 0.004\n";
  EXPECT_THAT(spec_error(base + "arm_rest_speed_rad_s = 0\nsupply_v = [12, 12]\n").what(),
              HasSubstr("spec.toml:10: guaranteed.lag_ms: missing: [lo, hi] in ms"));
  EXPECT_THAT(
      spec_error(base + "lag_ms = [2, 1]\narm_rest_speed_rad_s = 0\nsupply_v = [12, 12]\n").what(),
      HasSubstr("spec.toml:14: guaranteed.lag_ms: must be [lo, hi] with lo <= hi"));
  EXPECT_THAT(spec_error(base + "lag_ms = [0, 2]\narm_rest_speed_rad_s = 0\n").what(),
              HasSubstr("guaranteed.supply_v: missing: [lo, hi] in V"));
  EXPECT_THAT(spec_error(base + "lag_ms = [0, 2]\narm_rest_speed_rad_s = 0\n"
                                "supply_v = [12, 12]\nsupply_error_v = 0.02\n")
                  .what(),
              HasSubstr("guaranteed.supply_error_v: only applies with a csv.supply column"));
  EXPECT_THAT(spec_error(base + "lag_ms = [0, 2]\narm_rest_speed_rad_s = 0\n"
                                "supply_v = [12, 12]\npendulum_zero = 1\n")
                  .what(),
              HasSubstr("guaranteed.pendulum_zero: unknown key"));
  std::string zero_error = base;
  zero_error.replace(zero_error.find("0.004"), 5, "0");
  EXPECT_THAT(spec_error(zero_error).what(),
              HasSubstr("spec.toml:13: guaranteed.pendulum_zero_error: must be > 0"));
  std::string torque = base + "lag_ms = [0, 2]\narm_rest_speed_rad_s = 0\nsupply_v = [12, 12]\n";
  torque.replace(torque.find("\"duty\""), 6, "\"torque\"");
  EXPECT_THAT(spec_error(torque).what(),
              HasSubstr("spec.toml:10: guaranteed: only applies when csv.input_kind = \"duty\""));
}

// A logger that stamps its first command with the command's own time says what was in force
// before it: the row grid and the refinement's input both start from it.
TEST(CsvImport, TheInputAtStartHoldsBeforeTheFirstInputTime) {
  testing::TempDir dir;
  std::ostringstream csv;
  csv << "t,theta,t_theta,alpha,u,t_u\n";
  for (int k = 0; k < 16; ++k) {
    csv << 0.01 * k << ",0," << 0.01 * k - 0.005 << ",0," << (k < 8 ? 0.5 : -0.5) << ","
        << 0.01 * k + 0.02 << "\n";
  }
  const std::filesystem::path path = write_file(dir, "start.csv", csv.str());
  const std::string columns = "arm_time = \"t_theta\"\ninput_time = \"t_u\"\ninput_scale = 2\n";
  const ImportedSeries held = import_csv(
      path, parse_csv_import_spec(spec_text(columns + "input_at_start = 0.1\n"), "spec.toml"));
  ASSERT_TRUE(held.recorded.input_at_start.has_value());
  EXPECT_EQ(*held.recorded.input_at_start, 0.2);  // scaled like the column
  EXPECT_EQ(held.input[0], 0.2);
  EXPECT_EQ(held.input[1], 0.2);
  EXPECT_EQ(held.input[2], 1.0);
  const ImportedSeries as_first =
      import_csv(path, parse_csv_import_spec(spec_text(columns), "spec.toml"));
  EXPECT_FALSE(as_first.recorded.input_at_start.has_value());
  EXPECT_EQ(as_first.input[0], 1.0);
}

TEST(CsvImport, AGapOfManyPeriodsIsNotInterpolatedAcross) {
  testing::TempDir dir;
  std::ostringstream csv;
  csv << "t,theta,alpha,u\n";
  for (int k = 0; k < 20; ++k) csv << 0.01 * k + (k >= 10 ? 60.0 : 0.0) << ",0,0,0\n";
  const CsvImportError e = import_error(write_file(dir, "joined.csv", csv.str()),
                                        parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_EQ(e.line(), 12);
  EXPECT_THAT(e.what(), HasSubstr("too irregular to resample"));
}

TEST(CsvImport, MissingColumnListsTheHeader) {
  testing::TempDir dir;
  const auto path = write_file(dir, "data.csv", simple_csv(20));
  std::string text = spec_text();
  text.replace(text.find("\"u\""), 3, "\"volts\"");
  const CsvImportError e = import_error(path, parse_csv_import_spec(text, "spec.toml"));
  EXPECT_EQ(e.file(), path.string());
  EXPECT_EQ(e.line(), 1);
  EXPECT_EQ(e.field(), "volts");
  EXPECT_THAT(e.what(), HasSubstr(path.string() + ":1: volts: no such column for input"));
  EXPECT_THAT(e.what(), HasSubstr("\"t\", \"theta\", \"alpha\", \"u\""));
}

TEST(CsvImport, NonNumericCellNamesLineAndColumn) {
  testing::TempDir dir;
  std::string csv = simple_csv(20);
  const std::size_t line5 = csv.find("\n0.03,");  // the fifth line holds t = 0.03
  csv.replace(csv.find(',', line5) + 1, 3, "1.2.3");
  const auto path = write_file(dir, "data.csv", csv);
  const CsvImportError e = import_error(path, parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_EQ(e.line(), 5);
  EXPECT_EQ(e.field(), "theta");
  EXPECT_THAT(e.what(), HasSubstr(path.string() + ":5: theta: '1.2.3"));
}

TEST(CsvImport, NotANumberEmptyCellsAndShortRowsAreRejected) {
  testing::TempDir dir;
  const CsvImportSpec spec = parse_csv_import_spec(spec_text(), "spec.toml");
  auto with_line3 = [&](const std::string& line) {
    std::string csv = simple_csv(20);
    const std::size_t start = csv.find('\n', csv.find('\n') + 1) + 1;  // line 3
    csv.replace(start, csv.find('\n', start) - start, line);
    return import_error(write_file(dir, "data.csv", csv), spec);
  };
  const CsvImportError nan = with_line3("0.02,NaN,0,0");
  EXPECT_EQ(nan.line(), 3);
  EXPECT_EQ(nan.field(), "theta");
  EXPECT_THAT(nan.what(), HasSubstr("not a finite number"));
  const CsvImportError empty = with_line3("0.02,1,,0");
  EXPECT_EQ(empty.field(), "alpha");
  EXPECT_THAT(empty.what(), HasSubstr("empty cell"));
  const CsvImportError signs = with_line3("0.02,+-1,0,0");
  EXPECT_EQ(signs.field(), "theta");
  const CsvImportError short_row = with_line3("0.02,1,2");
  EXPECT_EQ(short_row.field(), "u");
  EXPECT_THAT(short_row.what(), HasSubstr("only 3 fields"));
  const CsvImportError quote = with_line3("0.02,\"1,2,3");
  EXPECT_THAT(quote.what(), HasSubstr("unterminated quote"));
  const CsvImportError blank = with_line3("");
  EXPECT_EQ(blank.line(), 3);
  EXPECT_THAT(blank.what(), HasSubstr("blank line inside the data"));
}

TEST(CsvImport, NumbersWithSignsExponentsAndQuotesParse) {
  testing::TempDir dir;
  std::string csv = "t,theta,alpha,u\n";
  for (int k = 0; k < 16; ++k) {
    csv += std::to_string(k) + "e-2, +1.5E-1 ,\"-2\",.5\n";
  }
  const ImportedSeries s =
      import_csv(write_file(dir, "data.csv", csv), parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_DOUBLE_EQ(s.t_s[3], 0.03);
  EXPECT_DOUBLE_EQ(s.q1_rad[3], 0.15);
  EXPECT_DOUBLE_EQ(s.q2_rad[3], -2.0);
  EXPECT_DOUBLE_EQ(s.input[3], 0.5);
}

TEST(CsvImport, TimeThatDoesNotIncreaseNamesTheLine) {
  testing::TempDir dir;
  std::string csv = simple_csv(20);
  const std::size_t line8 = csv.find("\n0.06,") + 1;  // line 8 holds t = 0.06
  csv.replace(line8, 4, "0.05");
  const auto path = write_file(dir, "data.csv", csv);
  const CsvImportError e = import_error(path, parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_EQ(e.line(), 8);
  EXPECT_EQ(e.field(), "t");
  EXPECT_THAT(e.what(), HasSubstr(path.string() +
                                  ":8: t: time does not increase: 0.05 repeats the time stamp of "
                                  "line 7 (a row written twice?)"));
  csv.replace(line8, 4, "0.04");
  const CsvImportError back = import_error(write_file(dir, "back.csv", csv),
                                           parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_EQ(back.line(), 8);
  EXPECT_THAT(back.what(), HasSubstr(":8: t: time does not increase: 0.04 after 0.05 on line 7 "
                                     "(rows out of order?)"));
}

// A time column read in the wrong unit: before, a 16 ms recording read as seconds went on to the
// filters, which failed with a cut-off message (or, with the cut-off it suggested, fitted
// nonsense).
TEST(CsvImport, ASamplePeriodNoPendulumHasNamesTheTimeUnitAndTheLikelyOne) {
  testing::TempDir dir;
  std::string milliseconds = "t,theta,alpha,u\n";
  for (int k = 0; k < 600; ++k) milliseconds += std::to_string(16 * k) + ",0,0,0.1\n";
  const auto ms_path = write_file(dir, "ms.csv", milliseconds);
  const CsvImportError as_s =
      import_error(ms_path, parse_csv_import_spec(spec_text(), "spec.toml"));
  EXPECT_EQ(as_s.field(), "t");
  EXPECT_THAT(as_s.what(), HasSubstr(ms_path.string() +
                                     ": t: time_unit = \"s\" (spec.toml:6) gives a sample period "
                                     "of 16 s (the median step; 2.66 h in all), outside the 100 us "
                                     "to 100 ms a pendulum recording has: is the column in ms? "
                                     "Then write time_unit = \"ms\" (a period of 16 ms)"));

  std::string spec = spec_text();
  spec.replace(spec.find("time_unit = \"s\""), 15, "time_unit = \"ms\"");
  const auto s_path = write_file(dir, "s.csv", simple_csv(20));  // 10 ms in seconds
  EXPECT_THAT(import_error(s_path, parse_csv_import_spec(spec, "spec.toml")).what(),
              HasSubstr("time_unit = \"ms\" (spec.toml:6) gives a sample period of 10 us"));
  EXPECT_THAT(import_error(s_path, parse_csv_import_spec(spec, "spec.toml")).what(),
              HasSubstr("is the column in s? Then write time_unit = \"s\""));

  // No unit fits: the message says to look at the column itself.
  std::string days = "t,theta,alpha,u\n";  // 11.6 days a step, or 1000 s, or 1 s
  for (int k = 0; k < 20; ++k) days += std::to_string(1'000'000 * k) + ",0,0,0.1\n";
  EXPECT_THAT(import_error(write_file(dir, "days.csv", days),
                           parse_csv_import_spec(spec_text(), "spec.toml"))
                  .what(),
              HasSubstr("check the time column and time_unit"));
}

TEST(CsvImport, SixteenRowsAtLeast) {
  testing::TempDir dir;
  const CsvImportSpec spec = parse_csv_import_spec(spec_text(), "spec.toml");
  const CsvImportError e = import_error(write_file(dir, "short.csv", simple_csv(15)), spec);
  EXPECT_THAT(e.what(), HasSubstr("15 data rows; at least 16 are needed"));
  EXPECT_EQ(import_csv(write_file(dir, "enough.csv", simple_csv(16)), spec).t_s.size(), 16u);
  EXPECT_THAT(import_error(write_file(dir, "empty.csv", "\n\n"), spec).what(),
              HasSubstr("the file is empty"));
  EXPECT_THAT(import_error(dir.path() / "absent.csv", spec).what(),
              HasSubstr("cannot open the file"));
}

TEST(CsvImport, AmbiguousHeaderNamesAreRejected) {
  testing::TempDir dir;
  std::string csv = simple_csv(20);
  csv.replace(0, csv.find('\n'), "t,theta,alpha,u,theta");
  const CsvImportError e =
      import_error(write_file(dir, "data.csv", csv), parse_csv_import_spec(spec_text(), "s"));
  EXPECT_EQ(e.field(), "theta");
  EXPECT_THAT(e.what(), HasSubstr("columns 2 and 5"));
}

// Values are checked where they enter, the first bad one named by its line and column: a duty
// outside [-1, 1] (a percentage, or a column that is not the input) and an angle no rig records
// (which would overflow the filters into NaN) are refused, not fitted.
TEST(CsvImport, ValuesOutOfRangeAreRefusedNamingLineAndColumn) {
  testing::TempDir dir;
  const CsvImportSpec spec = parse_csv_import_spec(spec_text(), "spec.toml");
  std::string pct = "t,theta,alpha,u\n";
  for (int k = 0; k < 16; ++k) pct += std::to_string(0.01 * k) + ",0,0,40\n";
  const CsvImportError duty = import_error(write_file(dir, "pct.csv", pct), spec);
  EXPECT_EQ(duty.line(), 2);
  EXPECT_EQ(duty.field(), "u");
  EXPECT_THAT(duty.what(), HasSubstr("a percentage needs input_scale = 0.01"));

  std::string huge = simple_csv(20);
  const std::size_t line7 = huge.find("\n0.05,");
  huge.replace(huge.find(',', line7) + 1,
               huge.find(',', huge.find(',', line7) + 1) - huge.find(',', line7) - 1, "1e300");
  const CsvImportError angle = import_error(write_file(dir, "huge.csv", huge), spec);
  EXPECT_EQ(angle.line(), 7);
  EXPECT_EQ(angle.field(), "theta");
  EXPECT_THAT(angle.what(), HasSubstr("no rig's angle is beyond 1e6 rad"));

  std::string volts = simple_csv(20);
  volts.replace(volts.rfind("0.5"), 3, "2e9");
  std::string voltage_text = spec_text();
  voltage_text.replace(voltage_text.find("\"duty\""), 6, "\"voltage\"");
  voltage_text +=
      "[motor]\ntorque_constant_nm_per_a = 0.05\nback_emf_v_s_per_rad = 0.06\n"
      "resistance_ohm = 2.5\n";
  const CsvImportError input = import_error(write_file(dir, "volts.csv", volts),
                                            parse_csv_import_spec(voltage_text, "spec.toml"));
  EXPECT_EQ(input.line(), 21);
  EXPECT_THAT(input.what(), HasSubstr("no rig's input is beyond 1e6"));
}

TEST(CsvImportSpec, ParsesDefaultsAndLoadsFromAFile) {
  testing::TempDir dir;
  const auto path = write_file(dir, "import.toml", spec_text("[logger]\nrate_hz = 100\n"));
  const CsvImportSpec spec = load_csv_import_spec(path);
  EXPECT_EQ(spec.delimiter, ',');
  EXPECT_TRUE(spec.has_header);
  EXPECT_EQ(spec.time.name, "t");
  EXPECT_EQ(spec.input.name, "u");
  EXPECT_DOUBLE_EQ(spec.input.scale, 1.0);
  EXPECT_DOUBLE_EQ(spec.time_scale_s, 1.0);
  EXPECT_EQ(spec.angle_unit, AngleUnit::rad);
  EXPECT_EQ(spec.pendulum_zero, PendulumZero::down);
  EXPECT_EQ(spec.input_kind, InputKind::duty);
  EXPECT_EQ(spec.input_between_samples, InputBetweenSamples::linear);
  EXPECT_FALSE(
      spec.voltage_motor.has_value());  // duty input: eq. 4's motor comes from the rig config
  EXPECT_THROW(load_csv_import_spec(dir.path() / "absent.toml"), ConfigError);
}

TEST(CsvImportSpec, UnknownKeyNamesFileLineAndField) {
  const ConfigError e = spec_error(spec_text("colour = \"blue\"\n"));
  EXPECT_EQ(e.file(), "spec.toml");
  EXPECT_EQ(e.line(), 10);
  EXPECT_EQ(e.field(), "csv.colour");
  EXPECT_THAT(e.what(), HasSubstr("spec.toml:10: csv.colour: unknown key"));
  EXPECT_THAT(spec_error("time_unit = \"s\"\n" + spec_text()).what(),
              HasSubstr("spec.toml:1: time_unit: unknown key"));
  EXPECT_THAT(spec_error(spec_text("time_scale = 2\n")).what(), HasSubstr("csv.time_scale"));
}

TEST(CsvImportSpec, BadEnumValuesListTheChoices) {
  std::string text = spec_text();
  text.replace(text.find("\"rad\""), 5, "\"grad\"");
  const ConfigError e = spec_error(text);
  EXPECT_EQ(e.line(), 7);
  EXPECT_EQ(e.field(), "csv.angle_unit");
  EXPECT_THAT(e.what(),
              HasSubstr("spec.toml:7: csv.angle_unit: 'grad' is not one of: rad, deg, counts"));
  text = spec_text();
  text.replace(text.find("\"down\""), 6, "\"sideways\"");
  EXPECT_THAT(spec_error(text).what(), HasSubstr("spec.toml:8: csv.pendulum_zero: 'sideways'"));
  text = spec_text();
  text.replace(text.find("\"duty\""), 6, "\"current\"");
  EXPECT_THAT(spec_error(text).what(), HasSubstr("spec.toml:9: csv.input_kind: 'current'"));
  text = spec_text();
  text.replace(text.find("time_unit = \"s\""), 15, "time_unit = \"min\"");
  EXPECT_THAT(spec_error(text).what(), HasSubstr("csv.time_unit: 'min' is not one of: s, ms, us"));
}

TEST(CsvImportSpec, WhatTheInputDidBetweenSamplesIsOneOfThree) {
  EXPECT_EQ(parse_csv_import_spec(spec_text("input_between_samples = \"held\"\n"), "spec.toml")
                .input_between_samples,
            InputBetweenSamples::held);
  EXPECT_EQ(parse_csv_import_spec(spec_text("input_between_samples = \"cubic\"\n"), "spec.toml")
                .input_between_samples,
            InputBetweenSamples::cubic);
  const ConfigError e = spec_error(spec_text("input_between_samples = \"smooth\"\n"));
  EXPECT_EQ(e.line(), 10);
  EXPECT_THAT(e.what(), HasSubstr("spec.toml:10: csv.input_between_samples: 'smooth' is not one "
                                  "of: held, linear, cubic"));
}

TEST(CsvImportSpec, CountsNeedCountsPerRevolution) {
  std::string text = spec_text();
  text.replace(text.find("\"rad\""), 5, "\"counts\"");
  const ConfigError missing = spec_error(text + "pendulum_counts_per_rev = 2000\n");
  EXPECT_EQ(missing.field(), "csv.arm_counts_per_rev");
  EXPECT_EQ(missing.line(), 1);  // the [csv] line: where to add it
  EXPECT_THAT(missing.what(), HasSubstr("spec.toml:1: csv.arm_counts_per_rev: missing"));
  const ConfigError negative =
      spec_error(text + "arm_counts_per_rev = 4096\npendulum_counts_per_rev = -1\n");
  EXPECT_THAT(negative.what(), HasSubstr("spec.toml:11: csv.pendulum_counts_per_rev: must be > 0"));
  const ConfigError unused = spec_error(spec_text("arm_counts_per_rev = 4096\n"));
  EXPECT_THAT(unused.what(),
              HasSubstr("spec.toml:10: csv.arm_counts_per_rev: only applies when angle_unit"));
  const ConfigError fraction =
      spec_error(text + "arm_counts_per_rev = 1024.5\npendulum_counts_per_rev = 2000\n");
  EXPECT_EQ(fraction.line(), 10);
  EXPECT_THAT(fraction.what(),
              HasSubstr("spec.toml:10: csv.arm_counts_per_rev: must be a whole number of counts "
                        "(e.g. 4096), not 1024.5"));
  EXPECT_EQ(parse_csv_import_spec(
                text + "arm_counts_per_rev = 4096.0\npendulum_counts_per_rev = 2000\n", "s")
                .arm_counts_per_rev,
            4096.0);
}

// Each angle's resolution, the refinement's angle noise: one count with counts; stated in the angle
// unit otherwise (scaled by the column's scale); unsaid is 0; stating it with counts, or a
// resolution that is not positive, is refused where it is written.
TEST(CsvImportSpec, ResolutionIsOneCountOrStatedInTheAngleUnit) {
  std::string counts = spec_text();
  counts.replace(counts.find("\"rad\""), 5, "\"counts\"");
  const CsvImportSpec c = parse_csv_import_spec(
      counts + "arm_counts_per_rev = 4096\npendulum_counts_per_rev = 2000\n", "s");
  EXPECT_DOUBLE_EQ(c.resolution_rad[0], 2 * kPi / 4096);
  EXPECT_DOUBLE_EQ(c.resolution_rad[1], 2 * kPi / 2000);
  EXPECT_EQ(parse_csv_import_spec(spec_text(), "s").resolution_rad, (std::array<double, 2>{0, 0}));
  const CsvImportSpec stated = parse_csv_import_spec(
      spec_text("pendulum_resolution = 7.5e-7\narm_angle_scale = -2\narm_resolution = 1e-3\n"),
      "s");
  EXPECT_DOUBLE_EQ(stated.resolution_rad[0], 2e-3);
  EXPECT_DOUBLE_EQ(stated.resolution_rad[1], 7.5e-7);
  std::string degrees = spec_text("pendulum_resolution = 0.1\n");
  degrees.replace(degrees.find("\"rad\""), 5, "\"deg\"");
  EXPECT_DOUBLE_EQ(parse_csv_import_spec(degrees, "s").resolution_rad[1], 0.1 * kDeg);
  const ConfigError with_counts = spec_error(
      counts + "arm_counts_per_rev = 4096\npendulum_counts_per_rev = 2000\narm_resolution = 1\n");
  EXPECT_THAT(with_counts.what(),
              HasSubstr("spec.toml:12: csv.arm_resolution: not with angle_unit = \"counts\""));
  EXPECT_THAT(spec_error(spec_text("pendulum_resolution = 0\n")).what(),
              HasSubstr("spec.toml:10: csv.pendulum_resolution: must be a number > 0"));
}

TEST(CsvImportSpec, OtherMistakesAreLocated) {
  EXPECT_THAT(spec_error("[other]\nx = 1\n").what(), HasSubstr("spec.toml: csv: missing table"));
  EXPECT_THAT(spec_error("csv = 3\n").what(), HasSubstr("spec.toml:1: csv: must be a table"));
  EXPECT_THAT(spec_error("[csv\n").what(), HasSubstr("spec.toml:1:"));

  std::string no_input = spec_text();
  no_input.erase(no_input.find("input = \"u\"\n"), 12);
  EXPECT_THAT(spec_error(no_input).what(), HasSubstr("spec.toml:1: csv.input: missing"));

  EXPECT_THAT(spec_error(spec_text("delimiter = \";;\"\n")).what(),
              HasSubstr("spec.toml:10: csv.delimiter: must be a single ASCII character"));
  EXPECT_THAT(spec_error(spec_text("delimiter = \".\"\n")).what(),
              HasSubstr("csv.delimiter: '.' cannot separate fields"));
  EXPECT_THAT(spec_error(spec_text("has_header = \"no\"\n")).what(),
              HasSubstr("csv.has_header: must be true or false"));
  EXPECT_THAT(spec_error(spec_text("has_header = false\n")).what(),
              HasSubstr("spec.toml:2: csv.time: 't' is not a 1-based column index"));
  EXPECT_THAT(spec_error(spec_text("input_scale = 0\n")).what(),
              HasSubstr("spec.toml:10: csv.input_scale: must be a unit change or a sign"));
  EXPECT_THAT(spec_error(spec_text("arm_angle_scale = 1e300\n")).what(),
              HasSubstr("spec.toml:10: csv.arm_angle_scale: must be a unit change or a sign: "
                        "1e-6 <= |scale| <= 1e6"));
  EXPECT_THAT(spec_error(spec_text("pendulum_angle_scale = nan\n")).what(),
              HasSubstr("csv.pendulum_angle_scale: must be finite"));
  EXPECT_THAT(spec_error(spec_text("pendulum_angle_scale = \"x\"\n")).what(),
              HasSubstr("csv.pendulum_angle_scale: must be a number"));

  std::string same = spec_text();
  same.replace(same.find("\"alpha\""), 7, "\"theta\"");
  EXPECT_THAT(spec_error(same).what(),
              HasSubstr("spec.toml:4: csv.pendulum_angle: same column as arm_angle ('theta')"));
  std::string number = spec_text();
  number.replace(number.find("\"u\""), 3, "4");
  EXPECT_THAT(spec_error(number).what(), HasSubstr("spec.toml:5: csv.input: must be a string"));
}

// A voltage-input spec (lines 1-9) with a [motor] table from line 10; `motor` is its body.
std::string voltage_spec(const std::string& motor) {
  std::string text = spec_text();
  text.replace(text.find("\"duty\""), 6, "\"voltage\"");
  return text + "[motor]\n" + motor;
}

constexpr const char* kMotorConstants =
    "torque_constant_nm_per_a = 0.05\nback_emf_v_s_per_rad = 0.06\nresistance_ohm = 2.5\n";

TEST(CsvImportSpec, VoltageInputReadsTheMotorTable) {
  const CsvImportSpec spec = parse_csv_import_spec(
      voltage_spec(std::string(kMotorConstants) + "gear_ratio = 4\nefficiency = 0.85\n"),
      "spec.toml");
  EXPECT_EQ(spec.input_kind, InputKind::voltage);
  ASSERT_TRUE(spec.voltage_motor.has_value());
  EXPECT_DOUBLE_EQ(spec.voltage_motor->torque_constant_nm_per_a, 0.05);
  EXPECT_DOUBLE_EQ(spec.voltage_motor->back_emf_v_s_per_rad, 0.06);
  EXPECT_DOUBLE_EQ(spec.voltage_motor->resistance_ohm, 2.5);
  EXPECT_DOUBLE_EQ(spec.voltage_motor->gear_ratio, 4.0);
  EXPECT_DOUBLE_EQ(spec.voltage_motor->efficiency, 0.85);

  const CsvImportSpec defaults = parse_csv_import_spec(voltage_spec(kMotorConstants), "spec.toml");
  ASSERT_TRUE(defaults.voltage_motor.has_value());
  EXPECT_DOUBLE_EQ(defaults.voltage_motor->gear_ratio, 1.0);
  EXPECT_DOUBLE_EQ(defaults.voltage_motor->efficiency, 1.0);
  EXPECT_DOUBLE_EQ(parse_csv_import_spec(voltage_spec("resistance_ohm = 3\n"
                                                      "torque_constant_nm_per_a = 1\n"
                                                      "back_emf_v_s_per_rad = 2\nefficiency = 1\n"),
                                         "spec.toml")
                       .voltage_motor->resistance_ohm,
                   3.0);  // integers are numbers too, and efficiency 1 is allowed
}

TEST(CsvImportSpec, MotorTableMistakesNameFileLineAndField) {
  // A missing constant is reported at the [motor] line (10): where to add it.
  const ConfigError missing =
      spec_error(voltage_spec("torque_constant_nm_per_a = 0.05\nback_emf_v_s_per_rad = 0.06\n"));
  EXPECT_EQ(missing.file(), "spec.toml");
  EXPECT_EQ(missing.line(), 10);
  EXPECT_EQ(missing.field(), "motor.resistance_ohm");
  EXPECT_THAT(missing.what(), HasSubstr("spec.toml:10: motor.resistance_ohm: missing"));
  EXPECT_THAT(
      spec_error(voltage_spec("back_emf_v_s_per_rad = 0.06\nresistance_ohm = 2.5\n")).what(),
      HasSubstr("motor.torque_constant_nm_per_a: missing"));
  EXPECT_THAT(
      spec_error(voltage_spec("torque_constant_nm_per_a = 0.05\nresistance_ohm = 2.5\n")).what(),
      HasSubstr("motor.back_emf_v_s_per_rad: missing"));

  EXPECT_THAT(
      spec_error(voltage_spec(std::string(kMotorConstants) + "resistance_ohm = 0\n")).what(),
      HasSubstr("spec.toml:14:"));  // TOML itself refuses the second one
  std::string zero_r = voltage_spec(kMotorConstants);
  zero_r.replace(zero_r.find("2.5"), 3, "0");
  EXPECT_THAT(spec_error(zero_r).what(),
              HasSubstr("spec.toml:13: motor.resistance_ohm: must be > 0"));
  std::string negative_k = voltage_spec(kMotorConstants);
  negative_k.replace(negative_k.find("0.05"), 4, "-0.05");
  EXPECT_THAT(spec_error(negative_k).what(),
              HasSubstr("spec.toml:11: motor.torque_constant_nm_per_a: must be > 0"));
  EXPECT_THAT(spec_error(voltage_spec(std::string(kMotorConstants) + "efficiency = 1.2\n")).what(),
              HasSubstr("spec.toml:14: motor.efficiency: must be in (0, 1]"));
  EXPECT_THAT(spec_error(voltage_spec(std::string(kMotorConstants) + "efficiency = 0\n")).what(),
              HasSubstr("motor.efficiency: must be in (0, 1]"));
  EXPECT_THAT(spec_error(voltage_spec(std::string(kMotorConstants) + "gear_ratio = -5\n")).what(),
              HasSubstr("spec.toml:14: motor.gear_ratio: must be > 0"));
  EXPECT_THAT(spec_error(voltage_spec(std::string(kMotorConstants) + "gear = 5\n")).what(),
              HasSubstr("spec.toml:14: motor.gear: unknown key"));
  EXPECT_THAT(
      spec_error(voltage_spec(std::string(kMotorConstants) + "resistance = \"2\"\n")).what(),
      HasSubstr("motor.resistance: unknown key"));
  std::string text_r = voltage_spec(kMotorConstants);
  text_r.replace(text_r.find("2.5"), 3, "\"2.5\"");
  EXPECT_THAT(spec_error(text_r).what(), HasSubstr("motor.resistance_ohm: must be a number"));
  EXPECT_THAT(spec_error(voltage_spec("")).what(),
              HasSubstr("spec.toml:10: motor.torque_constant_nm_per_a: missing"));

  std::string not_table = spec_text();
  not_table.replace(not_table.find("\"duty\""), 6, "\"voltage\"");
  EXPECT_THAT(spec_error("motor = 3\n" + not_table).what(),
              HasSubstr("spec.toml:1: motor: must be a table"));
}

TEST(CsvImportSpec, VoltageWithoutMotorTableIsRefusedAtInputKind) {
  std::string text = spec_text();
  text.replace(text.find("\"duty\""), 6, "\"voltage\"");
  const ConfigError e = spec_error(text);
  EXPECT_EQ(e.line(), 9);
  EXPECT_EQ(e.field(), "csv.input_kind");
  EXPECT_THAT(e.what(), HasSubstr("needs a [motor] table"));
}

TEST(CsvImportSpec, MotorTableWithOtherInputKindsIsRefusedNotIgnored) {
  const ConfigError duty = spec_error(spec_text(std::string("[motor]\n") + kMotorConstants));
  EXPECT_EQ(duty.line(), 10);
  EXPECT_EQ(duty.field(), "motor");
  EXPECT_THAT(duty.what(), HasSubstr("only applies when csv.input_kind = \"voltage\""));
  EXPECT_THAT(duty.what(), HasSubstr("rig configuration"));
  std::string torque = spec_text(std::string("[motor]\n") + kMotorConstants);
  torque.replace(torque.find("\"duty\""), 6, "\"torque\"");
  EXPECT_THAT(spec_error(torque).what(), HasSubstr("spec.toml:10: motor: only applies"));
}

}  // namespace
}  // namespace furuta::identification
