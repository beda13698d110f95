// Our logs against LCM's own tools and library: lcm::LogFile (what lcm-logger writes with),
// lcm-logplayer, and lcm-logger.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>

#include "furuta/session_log/lcm_log.hpp"
#include "test_support.hpp"

namespace furuta::session_log {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::Event;
using testing::TempDir;

// Events 1 ms apart, so lcm-logplayer (which keeps the recorded pace) plays them quickly.
std::vector<Event> compat_events() {
  std::vector<Event> events = testing::pattern_events(30);
  for (Event& e : events) e.utime = 1'700'000'000'000'000 + e.number * 1'000;
  events[4].channel = std::string(63, 'L');  // the longest channel LCM carries
  events[5].data.clear();
  return events;
}

fs::path write_with_our_writer(const fs::path& dir, const std::vector<Event>& events) {
  LcmLogWriter writer({dir, 1000ms}, "ours");
  for (const Event& e : events) {
    EXPECT_EQ(writer.write(e.channel, e.utime, e.data), LogWriteStatus::ok);
  }
  fs::path final_path;
  EXPECT_EQ(writer.finish(&final_path), LogWriteStatus::ok);
  return final_path;
}

bool have_program(const char* name) {
  return std::system(("command -v " + std::string(name) + " >/dev/null 2>&1").c_str()) == 0;
}

// Runs a shell command line; its exit code, or -1 when it did not exit normally.
int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(LcmCompat, LcmLogFileReadsWhatOurWriterWrote) {
  TempDir dir;
  const std::vector<Event> events = compat_events();
  const fs::path path = write_with_our_writer(dir.path(), events);

  lcm::LogFile log(path.string(), "r");
  ASSERT_TRUE(log.good());
  for (const Event& want : events) {
    const lcm::LogEvent* got = log.readNextEvent();
    ASSERT_NE(got, nullptr) << "event " << want.number;
    EXPECT_EQ(got->eventnum, want.number);
    EXPECT_EQ(got->timestamp, want.utime);
    EXPECT_EQ(got->channel, want.channel);
    ASSERT_EQ(got->datalen, static_cast<std::int32_t>(want.data.size()));
    const auto* data = static_cast<const std::uint8_t*>(got->data);
    EXPECT_TRUE(std::equal(want.data.begin(), want.data.end(), data));
  }
  EXPECT_EQ(log.readNextEvent(), nullptr);
}

TEST(LcmCompat, OurReaderReadsWhatLcmLogFileWrote) {
  TempDir dir;
  const std::vector<Event> events = compat_events();
  const fs::path path = dir.path() / "theirs.lcmlog";
  {
    lcm::LogFile log(path.string(), "w");
    ASSERT_TRUE(log.good());
    for (const Event& e : events) {
      std::vector<std::uint8_t> data = e.data;
      lcm::LogEvent event{};
      event.timestamp = e.utime;
      event.channel = e.channel;
      event.datalen = static_cast<std::int32_t>(data.size());
      event.data = data.data();
      ASSERT_EQ(log.writeEvent(&event), 0);
    }
  }
  LogReadStats stats;
  const std::vector<LogEvent> got = testing::read_log(path, stats);
  ASSERT_EQ(got.size(), events.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_TRUE(testing::same_event(got[i], events[i]));
  EXPECT_EQ(stats.damaged_regions, 0u);
  EXPECT_FALSE(stats.truncated_tail);
  EXPECT_EQ(stats.readable_prefix_bytes, fs::file_size(path));
}

// lcm-logplayer -v prints each event it plays: "<time> Channel <name> size <bytes>".
TEST(LcmCompat, LcmLogplayerPlaysOurLogToTheEnd) {
  if (!have_program("lcm-logplayer")) GTEST_SKIP() << "lcm-logplayer not installed (liblcm-bin)";
  TempDir dir;
  const std::vector<Event> events = compat_events();
  const fs::path path = write_with_our_writer(dir.path(), events);
  const fs::path out = dir.path() / "played.txt";
  ASSERT_EQ(run("lcm-logplayer -v --lcm-url=memq:// '" + path.string() + "' > '" + out.string() +
                "' 2>&1"),
            0)
      << read_text(out);

  std::istringstream lines(read_text(out));
  std::string line;
  std::size_t played = 0;
  while (std::getline(lines, line)) {
    std::istringstream fields(line);
    std::string time, channel_word, channel, size_word;
    std::size_t size = 0;
    if (!(fields >> time >> channel_word >> channel >> size_word >> size) ||
        channel_word != "Channel") {
      continue;
    }
    ASSERT_LT(played, events.size()) << line;
    EXPECT_EQ(channel, events[played].channel) << line;
    EXPECT_EQ(size, events[played].data.size()) << line;
    ++played;
  }
  EXPECT_EQ(played, events.size());
}

// The strong check, both ways at once: lcm-logplayer reads our log and publishes it on UDP
// multicast, lcm-logger records it, and our reader reads lcm-logger's file. Runs in a network
// namespace of its own (loopback only, ttl=0), so nothing leaves the machine and no port is shared.
const char* const kRoundTripScript = R"(
OUT="$1"; IN="$2"; PROBE="$3"; DONE="$4"
ip link set lo up || exit 90
ip route add 224.0.0.0/4 dev lo || exit 91
URL="udpm://239.255.76.67:7667?ttl=0"
lcm-logger -q --flush-interval=10 --lcm-url="$URL" "$OUT" &
LOGGER=$!
# Multicast is lost until the logger has joined: probe until it records something.
n=0
until [ -s "$OUT" ]; do
  lcm-logplayer --lcm-url="$URL" "$PROBE" >/dev/null 2>&1
  n=$((n+1)); if [ $n -ge 400 ]; then kill $LOGGER; exit 92; fi
  sleep 0.05
done
lcm-logplayer --lcm-url="$URL" "$IN" >/dev/null 2>&1 || { kill $LOGGER; exit 93; }
# Then a marker until it is recorded: everything played before it has been.
n=0
until grep -q FURUTA_DONE "$OUT"; do
  lcm-logplayer --lcm-url="$URL" "$DONE" >/dev/null 2>&1
  n=$((n+1)); if [ $n -ge 400 ]; then kill $LOGGER; exit 94; fi
  sleep 0.05
done
kill -INT $LOGGER
wait $LOGGER
exit 0
)";

TEST(LcmCompat, LcmLoggerRecordsWhatLcmLogplayerPlaysFromOurLog) {
  if (!have_program("lcm-logplayer") || !have_program("lcm-logger") || !have_program("ip") ||
      !have_program("unshare")) {
    GTEST_SKIP() << "needs lcm-logplayer, lcm-logger, ip and unshare";
  }
  if (run("unshare -rn true >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "no network namespace for an isolated multicast round trip here";
  }
  TempDir dir;
  const std::vector<Event> events = compat_events();
  const fs::path in = write_with_our_writer(dir.path(), events);
  const fs::path probe = dir.path() / "probe.lcmlog";
  const fs::path done = dir.path() / "done.lcmlog";
  testing::write_bytes(probe, testing::encode_log({Event{0, 0, "FURUTA_PROBE", {1}}}));
  testing::write_bytes(done, testing::encode_log({Event{0, 0, "FURUTA_DONE", {2}}}));
  const fs::path script = dir.path() / "round_trip.sh";
  {
    std::ofstream out(script);
    out << kRoundTripScript;
  }
  const fs::path out = dir.path() / "recorded.lcmlog";
  const fs::path log = dir.path() / "round_trip.txt";
  const int code = run("timeout 60 unshare -rn sh '" + script.string() + "' '" + out.string() +
                       "' '" + in.string() + "' '" + probe.string() + "' '" + done.string() +
                       "' > '" + log.string() + "' 2>&1");
  ASSERT_EQ(code, 0) << read_text(log);

  LogReadStats stats;
  const std::vector<LogEvent> recorded = testing::read_log(out, stats);
  EXPECT_EQ(stats.damaged_regions, 0u);
  EXPECT_FALSE(stats.truncated_tail);
  // lcm-logger numbers what it records from 0 and stamps its own receive times.
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    EXPECT_EQ(recorded[i].event_number, static_cast<std::int64_t>(i));
  }
  std::vector<const LogEvent*> played;
  for (const LogEvent& e : recorded) {
    if (e.channel != "FURUTA_PROBE" && e.channel != "FURUTA_DONE") played.push_back(&e);
  }
  ASSERT_EQ(played.size(), events.size());
  for (std::size_t i = 0; i < played.size(); ++i) {
    EXPECT_EQ(played[i]->channel, events[i].channel) << i;
    EXPECT_EQ(played[i]->data, events[i].data) << i;
  }
}

}  // namespace
}  // namespace furuta::session_log
