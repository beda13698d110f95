#include "furuta/firmware_bridge/usb_trace.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>

namespace furuta::bridge {

namespace {

constexpr std::string_view kHeader = "# furuta usb trace v1";
constexpr std::string_view kVersionPrefix = "# furuta usb trace v";
constexpr std::string_view kKindIn = "IN";
constexpr std::string_view kKindOut = "OUT";
constexpr std::string_view kKindErr = "ERR";
constexpr std::string_view kKindEnd = "END";

// Built by appending: GCC 12's -Wrestrict misfires on "'" + std::string(s) at -O3 (GCC bug 105329).
std::string quoted(std::string_view s) {
  std::string out;
  out.reserve(s.size() + 2);
  out += '\'';
  out.append(s);
  out += '\'';
  return out;
}

// Splits on runs of spaces and tabs; events align their columns with extra spaces.
std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

template <typename T>
bool parse_integer(std::string_view text, T& value, int base = 10) {
  if (text.empty()) return false;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value, base);
  return ec == std::errc() && ptr == end;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Product names carry spaces, fields are space-separated: spaces travel as underscores.
std::string encode_name(std::string_view name) {
  std::string out(name);
  for (char& c : out) {
    if (c == ' ') c = '_';
  }
  return out;
}

std::string decode_name(std::string_view name) {
  std::string out(name);
  for (char& c : out) {
    if (c == '_') c = ' ';
  }
  return out;
}

class Parser {
 public:
  explicit Parser(const std::string& source) : source_(source) {}

  [[noreturn]] void fail(const std::string& message) const {
    throw TraceFormatError(source_, line_, message);
  }

  UsbTrace parse(const std::string& text) {
    UsbTrace trace;
    std::size_t pos = 0;
    while (pos < text.size()) {
      std::size_t end = text.find('\n', pos);
      if (end == std::string::npos) end = text.size();
      std::string_view line(text.data() + pos, end - pos);
      pos = end + 1;
      ++line_;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      parse_line(line, trace);
    }
    if (!have_device_) fail("missing device line");
    return trace;
  }

  // A device line alone, as a session log carries it: its own source, so any error is on line 1.
  DeviceInfo parse_device_line(std::string_view line) {
    line_ = 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.find_first_of("\r\n") != std::string_view::npos) fail("device line with a line break");
    const std::vector<std::string_view> fields = split_fields(line);
    if (fields.empty() || fields[0] != "device") fail("not a device line");
    DeviceInfo device;
    parse_device(fields, device);
    return device;
  }

 private:
  void parse_line(std::string_view line, UsbTrace& trace) {
    if (line.starts_with('#')) {
      // A future format must not be misread as this one.
      if (line.starts_with(kVersionPrefix) && line != kHeader) {
        fail("unsupported trace version " + quoted(line.substr(kVersionPrefix.size())));
      }
      return;
    }
    const std::vector<std::string_view> fields = split_fields(line);
    if (fields.empty()) return;
    if (fields[0] == "device") {
      parse_device(fields, trace.device);
      return;
    }
    if (!have_device_) fail("missing device line before the first event");
    trace.events.push_back(parse_event(fields));
  }

  void parse_device(const std::vector<std::string_view>& fields, DeviceInfo& device) {
    if (have_device_) fail("second device line");
    if (fields.size() < 2) fail("device line without vendor:product");
    const std::string_view ids = fields[1];
    if (ids.size() != 9 || ids[4] != ':' ||
        !parse_integer(ids.substr(0, 4), device.vendor_id, 16) ||
        !parse_integer(ids.substr(5, 4), device.product_id, 16)) {
      fail("bad vendor:product " + quoted(ids) + " (want e.g. 06c2:003e)");
    }
    for (std::size_t i = 2; i < fields.size(); ++i) {
      const std::string_view field = fields[i];
      const std::size_t eq = field.find('=');
      if (eq == std::string_view::npos) fail("device field without '=': " + quoted(field));
      const std::string_view key = field.substr(0, eq);
      const std::string_view value = field.substr(eq + 1);
      if (key == "serial") {
        device.serial = std::string(value);
      } else if (key == "firmware") {
        if (!parse_integer(value, device.firmware_version)) fail("bad firmware " + quoted(value));
      } else if (key == "in") {
        if (!parse_integer(value, device.input_report_bytes)) fail("bad in " + quoted(value));
      } else if (key == "out") {
        if (!parse_integer(value, device.output_report_bytes)) fail("bad out " + quoted(value));
      } else if (key == "name") {
        device.product_name = decode_name(value);
      } else if (key == "vendor_class") {
        if (value != "0" && value != "1") fail("bad vendor_class " + quoted(value));
        device.vendor_class_interface = value == "1";
      } else {
        fail("unknown device field " + quoted(key));
      }
    }
    have_device_ = true;
  }

  TraceEvent parse_event(const std::vector<std::string_view>& fields) {
    TraceEvent event;
    if (!parse_integer(fields[0], event.time_ns)) fail("bad time " + quoted(fields[0]));
    if (fields.size() < 2) fail("event without a kind (IN, OUT, ERR or END)");
    const std::string_view kind = fields[1];
    if (fields.size() > 3) fail("unexpected text after the event: " + quoted(fields[3]));
    if (kind == kKindIn || kind == kKindOut) {
      event.kind = kind == kKindIn ? TraceEventKind::input : TraceEventKind::output;
      // No payload is a zero-length report (a read that returned nothing but the fact of it).
      if (fields.size() == 3) parse_hex(fields[2], event.bytes);
      if (event.kind == TraceEventKind::input && event.bytes.size() > kMaxReportBytes) {
        fail("input report of " + std::to_string(event.bytes.size()) + " bytes, more than " +
             std::to_string(kMaxReportBytes));
      }
    } else if (kind == kKindErr) {
      event.kind = TraceEventKind::error;
      if (fields.size() < 3) fail("ERR without a status");
      event.status = parse_status(fields[2]);
    } else if (kind == kKindEnd) {
      event.kind = TraceEventKind::end;
      if (fields.size() > 2) fail("unexpected text after END: " + quoted(fields[2]));
    } else {
      fail("unknown event kind " + quoted(kind) + " (want IN, OUT, ERR or END)");
    }
    return event;
  }

  void parse_hex(std::string_view hex, std::vector<std::uint8_t>& bytes) {
    if (hex.size() % 2 != 0) {
      fail("odd hex length " + std::to_string(hex.size()) + " in " + quoted(hex));
    }
    bytes.reserve(hex.size() / 2);
    for (std::size_t i = 0; i < hex.size(); i += 2) {
      const int hi = hex_digit(hex[i]);
      const int lo = hex_digit(hex[i + 1]);
      if (hi < 0 || lo < 0) fail("bad hex digit in " + quoted(hex.substr(i, 2)));
      bytes.push_back(static_cast<std::uint8_t>(hi * 16 + lo));
    }
  }

  TransportStatus parse_status(std::string_view name) {
    const std::optional<TransportStatus> s = transport_status_from_string(name);
    if (!s) fail("unknown status name " + quoted(name));
    if (*s == TransportStatus::ok) fail("ERR with status ok");
    return *s;
  }

  const std::string& source_;
  int line_ = 0;
  bool have_device_ = false;
};

void append_hex(std::string& out, const std::vector<std::uint8_t>& bytes) {
  static constexpr char kDigits[] = "0123456789abcdef";
  for (std::uint8_t b : bytes) {
    out.push_back(kDigits[b >> 4]);
    out.push_back(kDigits[b & 0x0F]);
  }
}

std::string hex4(std::uint16_t v) {
  char buf[5];
  std::snprintf(buf, sizeof buf, "%04x", static_cast<unsigned>(v));
  return buf;
}

[[noreturn]] void throw_io(const std::string& what, const std::filesystem::path& path, int err) {
  throw std::filesystem::filesystem_error(what, path,
                                          std::error_code(err, std::generic_category()));
}

void write_all(int fd, const std::string& data, const std::filesystem::path& path) {
  std::size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw_io("write_usb_trace: write", path, errno);
    }
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace

TraceFormatError::TraceFormatError(const std::string& file, int line, const std::string& what)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + what),
      file_(file),
      line_(line) {}

UsbTrace parse_usb_trace(const std::string& text, const std::string& source_name) {
  return Parser(source_name).parse(text);
}

UsbTrace read_usb_trace(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw TraceFormatError(path.string(), 0, "cannot open the file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw TraceFormatError(path.string(), 0, "cannot read the file");
  return parse_usb_trace(buffer.str(), path.string());
}

std::string format_trace_device_line(const DeviceInfo& d) {
  std::string out = "device " + hex4(d.vendor_id) + ":" + hex4(d.product_id);
  out += " serial=" + d.serial;
  out += " firmware=" + std::to_string(d.firmware_version);
  out += " in=" + std::to_string(d.input_report_bytes);
  out += " out=" + std::to_string(d.output_report_bytes);
  out += " name=" + encode_name(d.product_name);
  if (d.vendor_class_interface) out += " vendor_class=1";
  return out;
}

DeviceInfo parse_trace_device_line(const std::string& line) {
  static const std::string kSource = "device line";
  return Parser(kSource).parse_device_line(line);
}

std::optional<TransportStatus> transport_status_from_string(std::string_view name) {
  // Every value to_string() knows, so a status added to the enum (and, as -Wswitch insists, to
  // to_string) is readable here without a second list to keep in step.
  if (name == "unknown") return std::nullopt;
  for (int value = 0; value <= 0xFF; ++value) {
    const auto s = static_cast<TransportStatus>(value);
    if (to_string(s) == name) return s;
  }
  return std::nullopt;
}

std::string format_usb_trace(const UsbTrace& trace) {
  std::string out;
  out.reserve(128 + trace.events.size() * 80);
  out += kHeader;
  out += '\n';
  out += format_trace_device_line(trace.device);
  out += '\n';
  for (const TraceEvent& e : trace.events) {
    out += std::to_string(e.time_ns);
    switch (e.kind) {
      case TraceEventKind::input:
        out += " IN";
        if (!e.bytes.empty()) out += "  ";
        append_hex(out, e.bytes);
        break;
      case TraceEventKind::output:
        out += " OUT";
        if (!e.bytes.empty()) out += ' ';
        append_hex(out, e.bytes);
        break;
      case TraceEventKind::error:
        out += " ERR ";
        out += to_string(e.status);
        break;
      case TraceEventKind::end:
        out += " END";
        break;
    }
    out += '\n';
  }
  return out;
}

void write_usb_trace(const std::filesystem::path& path, const UsbTrace& trace) {
  const std::string text = format_usb_trace(trace);
  // A reader (or a crash) must see the old file or the new one, never half of one: write a
  // temporary beside the target (same file system, so rename is atomic), make it durable, then
  // rename.
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
  std::string tmp_leaf = ".";
  tmp_leaf += path.filename().string();
  tmp_leaf += ".XXXXXX";
  std::string tmp_name = (dir / tmp_leaf).string();
  const int fd = ::mkstemp(tmp_name.data());
  if (fd < 0) throw_io("write_usb_trace: create temporary", tmp_name, errno);
  try {
    write_all(fd, text, tmp_name);
    if (::fsync(fd) != 0) throw_io("write_usb_trace: fsync", tmp_name, errno);
    // mkstemp creates 0600; a trace is an ordinary data file.
    ::fchmod(fd, 0644);
  } catch (...) {
    ::close(fd);
    ::unlink(tmp_name.c_str());
    throw;
  }
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp_name.c_str());
    throw_io("write_usb_trace: close", tmp_name, err);
  }
  if (::rename(tmp_name.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp_name.c_str());
    throw_io("write_usb_trace: rename", path, err);
  }
  // The rename itself lives in the directory; without this a power cut may forget it.
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
}

}  // namespace furuta::bridge
