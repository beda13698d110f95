// A message on RIG_COMMAND_SIGNED, as the daemon's raw handler takes it: any bytes from anyone on
// the group. Decoded (or refused) without an exception; then checked by the verifier twice: as it
// came (its tag is checked against the rig's key, so it is refused), and tagged anew with that key
// (so the checks behind the tag run: sizes, the command's bytes, the time, the memory). Every
// reason must be bounded printable ASCII, and nothing is accepted that the rules refuse.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "furuta/command_auth/command_auth.hpp"
#include "furuta/rig_signed_command_t.hpp"

namespace {

namespace auth = furuta::command_auth;

void check(bool condition) {
  if (!condition) std::abort();  // an invariant broken: libFuzzer reports it as a crash
}

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kNow = 1'800'000'000 * kSecond;

auth::CommandKey fuzz_key() {
  auth::CommandKey key{};
  for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(3 * i + 1);
  return key;
}

void check_reason(const auth::Verdict& verdict) {
  if (verdict.accepted) return;
  check(!verdict.reason.empty());
  check(verdict.reason.size() <= 400);
  for (char c : verdict.reason) {
    const auto byte = static_cast<unsigned char>(c);
    check(byte >= 0x20 && byte < 0x7f);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 1 << 16) return 0;  // the daemon decodes nothing above 2048 bytes
  const std::vector<std::uint8_t> bytes(data, data + size);
  furuta::rig_signed_command_t message{};
  if (message.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) return 0;

  static auth::CommandVerifier verifier(fuzz_key(), "", auth::VerifierSettings{}, kNow, 0);
  static std::int64_t step = 0;
  ++step;  // time moves a millisecond an input, so the window and the memory are exercised
  const std::int64_t wall = kNow + step * 1'000'000;
  const std::int64_t monotonic = step * 1'000'000;

  const auth::CommandTag genuine = auth::command_tag(fuzz_key(), message);
  const bool tag_ok = std::equal(genuine.begin(), genuine.end(), message.tag);
  const auth::Verdict as_sent = verifier.verify(message, wall, monotonic);
  check_reason(as_sent);
  check(!as_sent.accepted || tag_ok);

  std::copy(genuine.begin(), genuine.end(), message.tag);
  const auth::Verdict tagged = verifier.verify(message, wall, monotonic);
  check_reason(tagged);
  if (tagged.accepted) {
    const auth::VerifierSettings limits;
    check(message.sender.size() <= limits.max_sender_bytes);
    check(message.command.size() <= limits.max_command_bytes);
    if (auth::moves_motor(tagged.command)) {
      check(message.signed_wall_ns <= wall + limits.max_ahead.count());
      check(message.signed_wall_ns >= wall - limits.window.count());
      // Taken once: the same bytes again are refused.
      check(!verifier.verify(message, wall, monotonic).accepted);
    }
  }
  return 0;
}
