// HID boards through the kernel's hidraw driver, via hidapi (the hidraw flavour, 0.13 on Debian
// 12). The kernel keeps usbhid bound, so the board stays visible to other tools and nothing is
// detached; the cost is that only HID-class boards appear here (a 1047 with vendor-class firmware
// 2xx does not enumerate as hidraw, so open() says not_found and the libusb backend must be used).

#include <hidapi/hidapi.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <cwchar>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "furuta/firmware_bridge/clock.hpp"
#include "furuta/firmware_bridge/usb_backends.hpp"

namespace furuta::bridge {

namespace {

// hidapi keeps process-wide state between hid_init and hid_exit; several transports (the 1065 and
// the 1047, possibly on different threads) share it, so the first user initialises it and the last
// one tears it down.
class HidapiLibraryRef {
 public:
  HidapiLibraryRef() {
    const std::scoped_lock lock(mutex());
    if (users()++ == 0) initialised() = hid_init() == 0;
  }
  ~HidapiLibraryRef() {
    const std::scoped_lock lock(mutex());
    if (--users() == 0 && initialised()) {
      hid_exit();
      initialised() = false;
    }
  }
  HidapiLibraryRef(const HidapiLibraryRef&) = delete;
  HidapiLibraryRef& operator=(const HidapiLibraryRef&) = delete;

  bool ok() const {
    const std::scoped_lock lock(mutex());
    return initialised();
  }

 private:
  // Function-local statics: constructed on first use, so a transport built during static
  // initialisation elsewhere cannot see them unconstructed.
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static int& users() {
    static int count = 0;
    return count;
  }
  static bool& initialised() {
    static bool done = false;
    return done;
  }
};

struct DeviceCloser {
  void operator()(hid_device* device) const { hid_close(device); }
};
using DevicePtr = std::unique_ptr<hid_device, DeviceCloser>;

struct EnumerationFreer {
  void operator()(hid_device_info* list) const { hid_free_enumeration(list); }
};
using EnumerationPtr = std::unique_ptr<hid_device_info, EnumerationFreer>;

// The kernel's limit for a report descriptor (HID_MAX_DESCRIPTOR_SIZE).
constexpr std::size_t kMaxDescriptorBytes = 4096;

// hidapi hands serial numbers over as wchar_t (UTF-32 on Linux); the rig configuration holds UTF-8.
// Phidget serials are decimal ASCII, for which this is the identity; other text is encoded properly
// so a comparison can never match by accident.
std::string wide_to_utf8(const wchar_t* wide) {
  std::string out;
  if (wide == nullptr) return out;
  for (; *wide != L'\0'; ++wide) {
    const auto c = static_cast<std::uint32_t>(*wide);
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else if (c < 0x800) {
      out += static_cast<char>(0xC0 | (c >> 6));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
      out += static_cast<char>(0xE0 | (c >> 12));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else {
      out += static_cast<char>(0xF0 | ((c >> 18) & 0x07));
      out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    }
  }
  return out;
}

// hidapi 0.13 has no call for the report descriptor (hid_get_report_descriptor came in 0.14), but
// the kernel publishes it: /dev/hidrawN -> /sys/class/hidraw/hidrawN/device/report_descriptor.
std::optional<std::vector<std::uint8_t>> read_sysfs_report_descriptor(const std::string& node) {
  const std::filesystem::path file = std::filesystem::path("/sys/class/hidraw") /
                                     std::filesystem::path(node).filename() / "device" /
                                     "report_descriptor";
  std::ifstream in(file, std::ios::binary);
  if (!in) return std::nullopt;
  std::vector<std::uint8_t> bytes;
  bytes.reserve(kMaxDescriptorBytes);
  std::istreambuf_iterator<char> it(in);
  const std::istreambuf_iterator<char> end;
  for (; it != end && bytes.size() < kMaxDescriptorBytes; ++it) {
    bytes.push_back(static_cast<std::uint8_t>(*it));
  }
  if (in.bad() || bytes.empty()) return std::nullopt;
  return bytes;
}

// Rounded up, so a 0.5 ms wait does not become a poll; 0 stays 0, which hidapi treats as a poll.
int timeout_ms_round_up(std::chrono::nanoseconds timeout) {
  if (timeout <= std::chrono::nanoseconds::zero()) return 0;
  const auto ms = std::chrono::ceil<std::chrono::milliseconds>(timeout).count();
  return ms > INT_MAX ? INT_MAX : static_cast<int>(ms);
}

class HidapiTransport final : public Transport {
 public:
  ~HidapiTransport() override { close(); }

  TransportStatus open(const DeviceMatch& match) override;
  TransportStatus read_report(UsbReport& report, std::chrono::nanoseconds timeout) override;
  TransportStatus write_report(std::span<const std::uint8_t> report) override;
  void close() override {
    device_.reset();
    info_ = DeviceInfo{};
  }
  bool is_open() const override { return device_ != nullptr; }
  const DeviceInfo& device_info() const override { return info_; }

 private:
  // Called after a failed read or write; `saved_errno` is errno right after the hidapi call.
  bool device_gone(int saved_errno) const;

  HidapiLibraryRef library_;  // declared first: outlives device_
  DevicePtr device_;
  DeviceInfo info_;
};

TransportStatus HidapiTransport::open(const DeviceMatch& match) {
  close();
  if (!library_.ok()) return TransportStatus::io_error;

  // hid_enumerate treats 0 as "any"; an exact match is wanted here, so filter again below.
  const EnumerationPtr list(hid_enumerate(match.vendor_id, match.product_id));
  const hid_device_info* chosen = nullptr;
  for (const hid_device_info* entry = list.get(); entry != nullptr; entry = entry->next) {
    if (entry->vendor_id != match.vendor_id || entry->product_id != match.product_id) continue;
    if (entry->path == nullptr) continue;
    if (match.serial && wide_to_utf8(entry->serial_number) != *match.serial) continue;
    chosen = entry;
    break;
  }
  if (chosen == nullptr) return TransportStatus::not_found;

  // hidapi reports failures as text only (hid_error). In the 0.13 series' linux/hid.c (read from
  // its source, not tried against a denied node: no board here) hid_open_path fails only when its
  // open(2) of the node fails, and afterwards calls only strerror, mbstowcs, calloc and free, which
  // with glibc leave errno alone when they succeed: errno still holds open()'s EACCES / EPERM when
  // the udev rule is missing. That is an implementation detail, so access(2) on the node confirms
  // it independently (as root access() always succeeds, but then open() cannot be refused either).
  errno = 0;
  hid_device* raw = hid_open_path(chosen->path);
  const int open_errno = errno;
  if (raw == nullptr) {
    const bool denied =
        open_errno == EACCES || open_errno == EPERM ||
        (::access(chosen->path, R_OK | W_OK) != 0 && (errno == EACCES || errno == EPERM));
    return denied ? TransportStatus::access_denied : TransportStatus::io_error;
  }
  device_.reset(raw);

  // Without the descriptor the report lengths are unknown, and then a short (lossy) report could
  // not be told from a whole one: refuse rather than guess.
  const auto descriptor = read_sysfs_report_descriptor(chosen->path);
  if (!descriptor) {
    close();
    return TransportStatus::io_error;
  }
  const HidReportLengths lengths = parse_hid_report_lengths(*descriptor);
  if (lengths.input_bytes == 0 || lengths.input_bytes > kMaxReportBytes ||
      lengths.output_bytes > kMaxReportBytes) {
    close();
    return TransportStatus::io_error;
  }

  info_.vendor_id = chosen->vendor_id;
  info_.product_id = chosen->product_id;
  info_.serial = wide_to_utf8(chosen->serial_number);
  info_.firmware_version = firmware_version_hid(chosen->release_number);
  info_.product_name = std::string(phidget_product_name(chosen->product_id));
  info_.path = chosen->path;
  info_.input_report_bytes = lengths.input_bytes;
  info_.output_report_bytes = lengths.output_bytes;
  info_.vendor_class_interface = false;  // hidraw only ever shows HID interfaces
  return TransportStatus::ok;
}

bool HidapiTransport::device_gone(int saved_errno) const {
  // Three independent signs, because hidapi's own error reporting differs between versions:
  // - ENODEV: what hidraw's write() returns once the device is removed;
  // - errno untouched (0): in hidapi 0.13.1 hid_read_timeout returns -1 without setting errno or
  //   an error text only when poll() flags POLLERR/POLLHUP, which hidraw raises exactly when its
  //   device has gone (0.14 adds the text "device disconnected");
  // - the node itself has gone (devtmpfs removes /dev/hidrawN on unplug).
  if (saved_errno == ENODEV || saved_errno == 0) return true;
  const wchar_t* text = hid_error(device_.get());
  if (text != nullptr && std::wcsstr(text, L"disconnected") != nullptr) return true;
  struct stat node {};
  return ::stat(info_.path.c_str(), &node) != 0 && (errno == ENOENT || errno == ENODEV);
}

TransportStatus HidapiTransport::read_report(UsbReport& report, std::chrono::nanoseconds timeout) {
  report.length = 0;
  if (!device_) return TransportStatus::not_open;

  // hidraw returns one whole report per read (without a report-id byte for unnumbered reports),
  // truncated to the buffer; open() checked the report fits kMaxReportBytes.
  errno = 0;
  const int count = hid_read_timeout(device_.get(), report.bytes.data(), report.bytes.size(),
                                     timeout_ms_round_up(timeout));
  const int saved_errno = errno;
  report.host_time_ns = MonotonicClock{}.now_ns();

  if (count == 0) return TransportStatus::timeout;
  if (count > 0) {
    report.length = static_cast<std::size_t>(count);
    return report.length < info_.input_report_bytes ? TransportStatus::short_report
                                                    : TransportStatus::ok;
  }
  // poll() interrupted by a signal: nothing was read, the caller simply reads again.
  if (saved_errno == EINTR) return TransportStatus::timeout;
  return device_gone(saved_errno) ? TransportStatus::disconnected : TransportStatus::io_error;
}

TransportStatus HidapiTransport::write_report(std::span<const std::uint8_t> report) {
  if (!device_) return TransportStatus::not_open;
  const std::size_t length = info_.output_report_bytes;
  if (report.empty() || report.size() > length) return TransportStatus::invalid_argument;

  // hid_write wants the report-id byte first (0x00: the boards use unnumbered reports), then the
  // report zero-padded to the descriptor's length, as the boards expect.
  std::array<std::uint8_t, kMaxReportBytes + 1> buffer{};
  std::copy(report.begin(), report.end(), buffer.begin() + 1);
  // Note: hidraw writes block in the kernel (usbhid's own timeout); hidapi cannot shorten it.
  errno = 0;
  const int written = hid_write(device_.get(), buffer.data(), length + 1);
  const int saved_errno = errno;
  if (written == static_cast<int>(length + 1)) return TransportStatus::ok;
  if (written < 0) {
    if (saved_errno == ETIMEDOUT) return TransportStatus::timeout;
    // A failed write always sets errno, so 0 is no sign of disconnection here.
    if (saved_errno != 0 && device_gone(saved_errno)) return TransportStatus::disconnected;
  }
  return TransportStatus::io_error;
}

}  // namespace

std::unique_ptr<Transport> make_hidapi_transport() {
  return std::make_unique<HidapiTransport>();
}

}  // namespace furuta::bridge
