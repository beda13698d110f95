// A message on RIG_STATUS as `furuta start|stop|estop|status` take it: any bytes from anyone on the
// group. The tool's decode drops what is too large or malformed; a status that decodes is checked
// against the daemon's public key (one that passes fails once changed) and printed. Every printed
// byte is printable ASCII or a newline, and the printed text is bounded whatever the message held;
// once bounded, a status encodes within kMaxStatusBytes.
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "daemon_channel.hpp"
#include "furuta/command_auth/status_signature.hpp"

namespace {

namespace auth = furuta::command_auth;

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 1 << 16) return 0;
  furuta::rig_status_t status{};
  if (!furuta::app::decode_status(data, size, status)) return 0;
  check(size <= auth::kMaxStatusBytes);

  // The key fuzz_make_seeds signs its seed statuses with: a status that checks out is one of
  // them, and any change to what it says makes it fail.
  static const auth::StatusSigner daemon(auth::CommandKey{42});
  if (auth::check_status(status, daemon.public_key()) ==
      auth::StatusAuthenticity::signed_by_daemon) {
    furuta::rig_status_t changed = status;
    changed.request_accepted = !changed.request_accepted;
    check(auth::check_status(changed, daemon.public_key()) ==
          auth::StatusAuthenticity::wrongly_signed);
    changed = status;
    changed.request_reason += "x";
    check(auth::check_status(changed, daemon.public_key()) ==
          auth::StatusAuthenticity::wrongly_signed);
  }

  std::ostringstream printed;
  furuta::app::print_status(status, printed);
  const std::string text = printed.str();
  check(text.size() <= 8192);
  for (char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    check(c == '\n' || (byte >= 0x20 && byte < 0x7f));
  }

  auth::bound_status_text(status);
  daemon.sign(status);
  check(static_cast<std::size_t>(status.getEncodedSize()) <= auth::kMaxStatusBytes);
  check(auth::check_status(status, daemon.public_key()) ==
        auth::StatusAuthenticity::signed_by_daemon);
  return 0;
}
