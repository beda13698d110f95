#pragma once
// A recorded USB conversation with one device, as a line-oriented text file (diffable, greppable):
//
//   # furuta usb trace v1
//   device 06c2:003e serial=300001 firmware=105 in=25 out=4 name=1065_MotorControl_1-Motor
//   <time_ns> IN  <hex bytes>          an input report as read
//   <time_ns> OUT <hex bytes>          an output report as written
//   <time_ns> ERR <status>             a read that failed (e.g. disconnected)
//   <time_ns> END                      the recording stopped (the transport was closed)
//
// Times are the recording Clock's nanoseconds. Parsing errors name the file and line.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "furuta/firmware_bridge/transport.hpp"

namespace furuta::bridge {

enum class TraceEventKind : std::uint8_t { input, output, error, end };

struct TraceEvent {
  std::int64_t time_ns = 0;
  TraceEventKind kind = TraceEventKind::input;
  std::vector<std::uint8_t> bytes;               // input, output
  TransportStatus status = TransportStatus::ok;  // error
};

struct UsbTrace {
  DeviceInfo device;
  std::vector<TraceEvent> events;
};

class TraceFormatError : public std::runtime_error {
 public:
  TraceFormatError(const std::string& file, int line, const std::string& what);
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

UsbTrace read_usb_trace(const std::filesystem::path& path);  // throws TraceFormatError
UsbTrace parse_usb_trace(const std::string& text, const std::string& source_name);
std::string format_usb_trace(const UsbTrace& trace);
void write_usb_trace(const std::filesystem::path& path, const UsbTrace& trace);  // atomic rename

// The "device ..." line alone (without a newline), for logs that carry the device beside the
// reports.
std::string format_trace_device_line(const DeviceInfo& device);
DeviceInfo parse_trace_device_line(const std::string& line);  // throws TraceFormatError (line 1)

// A status by its to_string() name, as ERR lines and logged USB errors carry it; nullopt when no
// status has that name.
std::optional<TransportStatus> transport_status_from_string(std::string_view name);

}  // namespace furuta::bridge
