// A session log proves its own integrity (session_log's seal): every command that reads one finds
// a log joined with another, cut, reordered, with a sample repeated or a value changed, says so,
// and does not use it as a whole session; one log is never fitted twice.
#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <sstream>
#include <string>

#include "commands.hpp"
#include "furuta/rig_sample_t.hpp"
#include "furuta/rig_session_t.hpp"
#include "furuta/session_log/session_log.hpp"
#include "log_events.hpp"
#include "simulated_logs.hpp"
#include "temp_dir.hpp"

namespace furuta::app::log_seal_test {
namespace {

namespace fs = std::filesystem;
using furuta::testing::Event;
using furuta::testing::events_of;
using furuta::testing::TempDir;
using furuta::testing::write_events;

struct Outcome {
  int status = -1;
  std::string out, err;
  bool says(const std::string& words) const {
    return out.find(words) != std::string::npos || err.find(words) != std::string::npos;
  }
};

Outcome log_info(const fs::path& log) {
  std::ostringstream out, err;
  const int status = run_log_info_command(log, out, err);
  return {status, out.str(), err.str()};
}

Outcome replay(const fs::path& log) {
  std::ostringstream out, err;
  const int status = run_replay_command(log, {}, out, err);
  return {status, out.str(), err.str()};
}

Outcome identify(IdentifyCommandOptions options) {
  std::ostringstream out, err;
  const int status = run_identify_command(options, out, err);
  return {status, out.str(), err.str()};
}

rig_sample_t decode_sample(const Event& e) {
  rig_sample_t s;
  EXPECT_EQ(s.decode(e.data.data(), 0, static_cast<int>(e.data.size())),
            static_cast<int>(e.data.size()));
  return s;
}

std::vector<std::uint8_t> encode_sample(const rig_sample_t& s) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(s.getEncodedSize()));
  s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// The events as a version before seals wrote them: no seal, and that version in the start record.
void as_written_before_seals(std::vector<Event>& events) {
  ASSERT_EQ(events.back().channel, session_log::kChannelSeal);
  events.pop_back();
  ASSERT_EQ(events.front().channel, session_log::kChannelSession);
  rig_session_t start;
  Event& e = events.front();
  ASSERT_GT(start.decode(e.data.data(), 0, static_cast<int>(e.data.size())), 0);
  start.software_version = "furuta 0.1.0 (git 114f8895c6d5)";
  e.data.assign(static_cast<std::size_t>(start.getEncodedSize()), 0);
  start.encode(e.data.data(), 0, static_cast<int>(e.data.size()));
}

class LogSeal : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    made_ = std::make_unique<TempDir>("furuta-log-seal");
    log_ = furuta::testing::simulated_session_log(made_->path(), "fit", 11, 6.0);
    other_ = furuta::testing::simulated_session_log(made_->path(), "fit", 12, 6.0);
  }
  static void TearDownTestSuite() { made_.reset(); }

  // The session's events changed by `change`, written to a file of their own.
  template <typename Change>
  fs::path changed(const std::string& name, Change change) const {
    std::vector<Event> events = events_of(log_);
    const std::vector<std::size_t> samples =
        furuta::testing::events_on(events, session_log::kChannelSample);
    change(events, samples);
    return write_events(dir_.path() / (name + ".lcmlog"), events);
  }
  // One sample's pendulum angle replaced, the message still well formed: a flipped exponent bit.
  fs::path altered_angle() const {
    return changed("altered", [](std::vector<Event>& e, const std::vector<std::size_t>& s) {
      rig_sample_t sample = decode_sample(e[s[40]]);
      sample.pendulum_angle_rad = -8.1e307;
      e[s[40]].data = encode_sample(sample);
    });
  }

  static std::unique_ptr<TempDir> made_;
  static fs::path log_, other_;
  TempDir dir_{"furuta-log-seal-case"};
};

std::unique_ptr<TempDir> LogSeal::made_;
fs::path LogSeal::log_, LogSeal::other_;

TEST_F(LogSeal, AWholeSessionIsProvedByItsSeal) {
  const Outcome o = log_info(log_);
  EXPECT_EQ(o.status, 0) << o.out << o.err;
  EXPECT_TRUE(o.says("as sealed")) << o.out;
  EXPECT_TRUE(o.says("integrity intact")) << o.out;
}

TEST_F(LogSeal, LogInfoNeverCallsAChangedLogIntact) {
  using Events = std::vector<Event>;
  using At = const std::vector<std::size_t>&;
  const std::pair<fs::path, const char*> cases[] = {
      {altered_angle(), "altered"},
      {changed("joined",
               [](Events& e, At) {
                 const Events copy = e;
                 e.insert(e.end(), copy.begin(), copy.end());
               }),
       "joined"},
      {changed("head_cut",
               [](Events& e, At s) {
                 e.erase(e.begin() + static_cast<std::ptrdiff_t>(s[0]),
                         e.begin() + static_cast<std::ptrdiff_t>(s[300]));
               }),
       "missing (sequence numbers 0-"},
      {changed("no_samples",
               [](Events& e, At) {
                 std::erase_if(
                     e, [](const Event& x) { return x.channel == session_log::kChannelSample; });
               }),
       "count mismatch"},
      {changed("duplicated",
               [](Events& e, At s) {
                 e.insert(e.begin() + static_cast<std::ptrdiff_t>(s[100]), e[s[100]]);
               }),
       "a sample repeated"},
      {changed("time_back",
               [](Events& e, At s) {
                 rig_sample_t sample = decode_sample(e[s[200]]);
                 sample.monotonic_ns -= 4'300'000'000;
                 e[s[200]].data = encode_sample(sample);
               }),
       "time goes back"},
  };
  for (const auto& [path, words] : cases) {
    const Outcome o = log_info(path);
    EXPECT_EQ(o.status, 1) << path.filename() << "\n" << o.out << o.err;
    EXPECT_TRUE(o.says("not intact")) << path.filename() << "\n" << o.out;
    EXPECT_TRUE(o.says(words)) << path.filename() << ": no '" << words << "' in\n" << o.out;
  }
}

TEST_F(LogSeal, ALogWrittenBeforeSealsIsReadWithANote) {
  const fs::path unsealed =
      changed("unsealed", [](std::vector<Event>& e, auto&) { as_written_before_seals(e); });
  const Outcome o = log_info(unsealed);
  EXPECT_EQ(o.status, 0) << o.out << o.err;
  EXPECT_TRUE(o.says("no seal: written before session logs were sealed")) << o.out;
}

// A version that seals every log: a whole log of it without a seal lost it.
TEST_F(LogSeal, ALogWhoseSealWasRemovedIsNotIntact) {
  const fs::path stripped = changed("stripped", [](std::vector<Event>& e, auto&) { e.pop_back(); });
  const Outcome o = log_info(stripped);
  EXPECT_EQ(o.status, 1) << o.out << o.err;
  EXPECT_TRUE(o.says("seal missing")) << o.out;
  IdentifyCommandOptions options;
  options.logs = {stripped};
  options.use_intact_part = true;
  options.output_dir = dir_.path() / "out";
  const Outcome i = identify(options);
  EXPECT_EQ(i.status, 2) << i.out << i.err;
  EXPECT_TRUE(i.says("--use-intact-part cannot use it either")) << i.err;
}

TEST_F(LogSeal, ReplayComparesEveryFieldAndNamesTheFirstThatDiffers) {
  const Outcome same = replay(log_);
  EXPECT_EQ(same.status, 0) << same.out << same.err;
  EXPECT_TRUE(same.says("identical")) << same.out;

  // The angle is not among what the replay used to compare: the altered value passed as identical.
  const Outcome o = replay(altered_angle());
  EXPECT_EQ(o.status, 1) << o.out << o.err;
  EXPECT_TRUE(o.says("1 differ (first at seq 40, in pendulum_angle_rad)")) << o.out;
  EXPECT_TRUE(o.says("altered")) << o.err;

  const Outcome repeated = replay(changed("dup", [](std::vector<Event>& e, auto& s) {
    e.insert(e.begin() + static_cast<std::ptrdiff_t>(s[10]), e[s[10]]);
  }));
  EXPECT_EQ(repeated.status, 1) << repeated.out << repeated.err;
  EXPECT_TRUE(repeated.says("a sample repeated")) << repeated.err;
}

TEST_F(LogSeal, IdentifyRefusesOneLogTwiceByItsDigestWhateverItsName) {
  const fs::path copy = dir_.path() / "copy.lcmlog";
  fs::copy_file(log_, copy);
  IdentifyCommandOptions twice;
  twice.logs = {log_, copy};
  twice.output_dir = dir_.path() / "twice";
  const Outcome o = identify(twice);
  EXPECT_EQ(o.status, 2) << o.out << o.err;
  EXPECT_TRUE(o.says("is the same log as")) << o.err;
  EXPECT_FALSE(fs::exists(twice.output_dir));

  IdentifyCommandOptions held_out_fitted;
  held_out_fitted.logs = {log_};
  held_out_fitted.validate = copy;
  held_out_fitted.output_dir = dir_.path() / "held_out";
  const Outcome h = identify(held_out_fitted);
  EXPECT_EQ(h.status, 2) << h.out << h.err;
  EXPECT_TRUE(h.says("the held-out")) << h.err;
  EXPECT_TRUE(h.says("hold out a session the fit does not see")) << h.err;
}

TEST_F(LogSeal, IdentifyUsesNoPartOfAChangedLog) {
  IdentifyCommandOptions options;
  options.logs = {altered_angle(), other_};
  options.use_intact_part = true;
  options.output_dir = dir_.path() / "out";
  const Outcome o = identify(options);
  EXPECT_EQ(o.status, 2) << o.out << o.err;
  EXPECT_TRUE(o.says("altered")) << o.err;
  EXPECT_TRUE(o.says("--use-intact-part cannot use it either")) << o.err;
}

// Without a seal, a changed value is still found where it enters the fit: each angle must be its
// counts through the log's encoder geometry, each duty within [-1, 1].
TEST_F(LogSeal, IdentifyChecksEveryValueOfALogWrittenBeforeSeals) {
  const fs::path unsealed_altered =
      changed("unsealed_altered", [](std::vector<Event>& e, const std::vector<std::size_t>& s) {
        rig_sample_t sample = decode_sample(e[s[40]]);
        sample.pendulum_angle_rad = -8.1e307;
        e[s[40]].data = encode_sample(sample);
        as_written_before_seals(e);
      });
  EXPECT_EQ(log_info(unsealed_altered).status, 0);  // nothing in the log's structure shows it
  IdentifyCommandOptions options;
  options.logs = {unsealed_altered};
  options.output_dir = dir_.path() / "out";
  const Outcome o = identify(options);
  EXPECT_EQ(o.status, 2) << o.out << o.err;
  EXPECT_TRUE(o.says("sample seq 40: pendulum_angle_rad -8.1e+307 is not its pendulum_counts"))
      << o.err;

  const fs::path duty =
      changed("duty", [](std::vector<Event>& e, const std::vector<std::size_t>& s) {
        rig_sample_t sample = decode_sample(e[s[7]]);
        sample.applied_duty = std::numeric_limits<double>::quiet_NaN();
        e[s[7]].data = encode_sample(sample);
        as_written_before_seals(e);
      });
  options.logs = {duty};
  const Outcome d = identify(options);
  EXPECT_EQ(d.status, 2) << d.out << d.err;
  EXPECT_TRUE(d.says("sample seq 7: duty")) << d.err;
}

}  // namespace
}  // namespace furuta::app::log_seal_test
