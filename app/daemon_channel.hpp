#pragma once
// How `furuta start|stop|estop|status` reach the daemon: commands out on RIG_COMMAND
// (RIG_COMMAND_SIGNED for those that move the motor), every status the daemon publishes in (its
// replies to anyone and its periodic one). Over LCM in `furuta`; tests put a daemon of their own,
// in virtual time, behind it.

#include <chrono>
#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>

#include "furuta/rig_command_t.hpp"
#include "furuta/rig_signed_command_t.hpp"
#include "furuta/rig_status_t.hpp"

namespace furuta::app {

class DaemonChannel {
 public:
  virtual ~DaemonChannel() = default;
  virtual void send(const furuta::rig_command_t& command) = 0;
  // A command that moves the motor, signed (RIG_COMMAND_SIGNED).
  virtual void send_signed(const furuta::rig_signed_command_t& command) = 0;
  // The next status published, or nothing within `wait`.
  virtual std::optional<furuta::rig_status_t> receive(std::chrono::milliseconds wait) = 0;
  // Where the daemon is expected, for messages ("udpm://...").
  virtual std::string where() const = 0;
};

// A status as it arrived on RIG_STATUS: false for one larger than any the daemon sends
// (command_auth::kMaxStatusBytes) or one that does not decode.
bool decode_status(const void* data, std::size_t size, furuta::rig_status_t& status);
// One line (scripts read "state X", "cycles N," and "last fault: reason"); every text in it is
// bounded and escaped, since a status may quote a stranger's bytes.
void print_status(const furuta::rig_status_t& status, std::ostream& out);

struct RemoteOptions;
struct StartOptions;
enum class RemoteKind;
// run_remote_command over a given channel.
int run_remote_command(RemoteKind kind, DaemonChannel& channel, const RemoteOptions& remote,
                       const StartOptions& start, std::ostream& out, std::ostream& err);

}  // namespace furuta::app
