// A board kind the project does not ship, added as docs/adding-a-board.md says: an adapter
// registered under a name, that name as the configuration's model, and this test. Nothing else in
// the tree changes: the loop, the log and the identification take its readings by role.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "furuta/firmware_bridge/board_roles.hpp"
#include "furuta/session_log/session_log.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app {
namespace {

namespace fs = std::filesystem;

// The adapter: an encoder board mounted the other way round, counting down where the 1047 counts
// up (it reads the simulated 1047's reports and negates what they say).
class ReversedEncoderBoard final : public bridge::EncoderBoard {
 public:
  ReversedEncoderBoard(const bridge::DeviceInfo& device, int channel)
      : inner_(bridge::make_encoder_board("1047", device, channel)) {}
  std::optional<bridge::EncoderReading> read(std::span<const std::uint8_t> report,
                                             std::int64_t host_ns) noexcept override {
    std::optional<bridge::EncoderReading> r = inner_->read(report, host_ns);
    if (r) r->delta_counts = -r->delta_counts;
    return r;
  }
  std::size_t enable(std::span<std::uint8_t> report) const noexcept override {
    return inner_->enable(report);
  }
  void restart() noexcept override { inner_->restart(); }

 private:
  std::unique_ptr<bridge::EncoderBoard> inner_;
};

// Found on the bus where the board it wraps is.
const bool registered = bridge::register_encoder_board(
    "reversed-test-encoder", {.make =
                                  [](const bridge::DeviceInfo& device, int channel) {
                                    return std::unique_ptr<bridge::EncoderBoard>(
                                        std::make_unique<ReversedEncoderBoard>(device, channel));
                                  },
                              .usb = bridge::encoder_board_kind("1047").usb});

// The project's rig.toml with the encoder board's model replaced.
fs::path config_with_encoder_model(const fs::path& dir, const std::string& model) {
  std::ifstream in(FURUTA_SOURCE_DIR "/config/rig.toml");
  std::stringstream text;
  text << in.rdbuf();
  std::string toml = text.str();
  const std::string line = "model = \"1047\"";
  const auto at = toml.find(line);
  EXPECT_NE(at, std::string::npos) << "config/rig.toml: no `" << line << "`";
  if (at != std::string::npos) toml.replace(at, line.size(), "model = \"" + model + "\"");
  const fs::path path = dir / "rig.toml";
  std::ofstream(path) << toml;
  return path;
}

TEST(NewBoard, ARegisteredEncoderAdapterNamedInTheConfigurationIsTheOneTheLoopReads) {
  ASSERT_TRUE(registered);
  furuta::testing::TempDir dir;
  const fs::path shipped =
      furuta::testing::simulated_session_log(dir.path() / "shipped", "board", 3, 2.0);
  const fs::path reversed = furuta::testing::simulated_session_log(
      dir.path() / "reversed", "board", 3, 2.0, {}, {},
      config_with_encoder_model(dir.path(), "reversed-test-encoder"));
  ASSERT_FALSE(shipped.empty());
  ASSERT_FALSE(reversed.empty());
  const session_log::SessionLog a = session_log::load_session_log(shipped);
  const session_log::SessionLog b = session_log::load_session_log(reversed);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  ASSERT_GT(a.samples.size(), 100u);
  int moved = 0;
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(b.samples[i].pendulum_counts, -a.samples[i].pendulum_counts) << i;
    EXPECT_EQ(b.samples[i].arm_counts, a.samples[i].arm_counts) << i;
    ASSERT_EQ(b.samples[i].n_encoder_reports, a.samples[i].n_encoder_reports) << i;
    for (int k = 0; k < a.samples[i].n_encoder_reports; ++k) {
      EXPECT_EQ(b.samples[i].encoder_delta_counts[k], -a.samples[i].encoder_delta_counts[k]);
    }
    moved += a.samples[i].pendulum_counts != 0;
  }
  EXPECT_GT(moved, 50);  // the pendulum swung: the comparison says something

  // A model no adapter is registered for is refused by the configuration (file, line, key),
  // naming the known ones, before anything runs.
  std::ostringstream out, err;
  RunOptions options;
  options.config_path = config_with_encoder_model(dir.path(), "no-such-board");
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = dir.path() / "refused";
  options.lcm_url = "memq://";
  try {
    run_session_command(options, out, err);
    FAIL() << "a configuration naming no known board was run";
  } catch (const std::exception& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("rig.toml:"), std::string::npos) << what;
    EXPECT_NE(what.find(": boards.encoder.model: 'no-such-board' is not a board this build has an "
                        "adapter for (1047"),
              std::string::npos)
        << what;
  }
  EXPECT_FALSE(fs::exists(options.logs_dir));
}

}  // namespace
}  // namespace furuta::app
