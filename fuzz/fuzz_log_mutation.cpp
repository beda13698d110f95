// A sealed session log changed by a script of up to six operations (bits flipped, bytes
// overwritten, cut or truncated, events duplicated, swapped or deleted, a sample's time or a
// double moved, the log joined to itself; tests/support/log_mutation.hpp reads the input as that
// script). Neither `log info` (integrity_problems, integrity_notes) nor `identify`
// (pipeline::load_batch) may call the changed log intact without a problem or a note saying that
// nothing proves it whole.
//
// The log is one short session of the simulated rig in virtual time, made once in this process
// (as `furuta run --sim --virtual-time` makes it), so no log is kept in the corpus; the corpus
// holds scripts.
#include <stdlib.h>  // mkdtemp

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "furuta/pipeline/intake.hpp"
#include "log_mutation.hpp"

namespace {

namespace fs = std::filesystem;

struct Base {
  fs::path dir;
  std::vector<std::uint8_t> bytes;
};

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_log_mutation: %s\n", what.c_str());
  std::abort();
}

// The sealed log the scripts change, and the directory (under TMPDIR) the changed logs go to.
Base make_base() {
  std::string pattern = (fs::temp_directory_path() / "fuzz-log-mutation-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) fail("mkdtemp " + pattern);
  Base base{pattern, {}};
  furuta::app::RunOptions options;
  options.config_path = FURUTA_SOURCE_DIR "/config/rig.toml";
  options.simulated = true;
  options.virtual_time = true;
  options.logs_dir = base.dir / "logs";
  options.lcm_url = "memq://";
  options.session.label = "fit";
  options.session.seed = 23;
  // Long enough for identify to accept it unchanged, so that its half of the check runs.
  options.session.duration_s = 1.5;
  std::ostringstream out, err;
  if (furuta::app::run_session_command(options, out, err) != 0) fail(out.str() + err.str());
  const std::string text = out.str();
  const auto at = text.find("; log ");
  if (at == std::string::npos) fail("no log in: " + text);
  const fs::path log = text.substr(at + 6, text.find('\n', at) - at - 6);
  std::ifstream in(log, std::ios::binary);
  base.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());

  // The unchanged log is intact and accepted whole: otherwise every check below is empty.
  const auto loaded = furuta::session_log::load_session_log(log);
  if (!loaded.seal || !furuta::session_log::integrity_problems(loaded).empty()) {
    fail("the base log is not sealed and intact");
  }
  furuta::pipeline::BatchRequest request;
  request.logs = {log};
  if (!furuta::pipeline::load_batch(request).batch) fail("identify refuses the base log");
  return base;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Six operations take at most 84 bytes; longer inputs only repeat shorter ones.
  if (size > 256) return 0;
  static const Base base = make_base();
  std::string done;
  const std::vector<std::uint8_t> mutated =
      furuta::testing::mutate_log(base.bytes, {data, size}, &done);
  if (const auto violation =
          furuta::testing::changed_log_called_intact(base.bytes, mutated, base.dir)) {
    fail(*violation + "\nafter:\n" + done);
  }
  return 0;
}
