#pragma once
// Private to the firmware bridge: RAII owners for libusb's handles and small helpers shared by the
// libusb transport and discovery. Not installed, not part of the public headers.

#include <libusb.h>

#include <array>
#include <chrono>
#include <climits>
#include <cstdint>
#include <memory>
#include <string>

namespace furuta::bridge::detail {

struct ContextDeleter {
  void operator()(libusb_context* context) const { libusb_exit(context); }
};
using ContextPtr = std::unique_ptr<libusb_context, ContextDeleter>;

struct HandleDeleter {
  void operator()(libusb_device_handle* handle) const { libusb_close(handle); }
};
using HandlePtr = std::unique_ptr<libusb_device_handle, HandleDeleter>;

struct ConfigDeleter {
  void operator()(libusb_config_descriptor* config) const { libusb_free_config_descriptor(config); }
};
using ConfigPtr = std::unique_ptr<libusb_config_descriptor, ConfigDeleter>;

// The list owns a reference to each device; freeing it with unref=1 drops them. A device we keep
// (an open handle) holds its own reference, so dropping the list after libusb_open is safe.
class DeviceList {
 public:
  explicit DeviceList(libusb_context* context) {
    libusb_device** list = nullptr;
    const ssize_t count = libusb_get_device_list(context, &list);
    if (count < 0) {
      error_ = static_cast<int>(count);
      return;
    }
    list_ = list;
    count_ = static_cast<std::size_t>(count);
  }
  ~DeviceList() {
    if (list_ != nullptr) libusb_free_device_list(list_, 1);
  }
  DeviceList(const DeviceList&) = delete;
  DeviceList& operator=(const DeviceList&) = delete;

  int error() const { return error_; }  // a libusb_error, 0 when the list was read
  libusb_device** begin() const { return list_; }
  libusb_device** end() const { return list_ == nullptr ? nullptr : list_ + count_; }

 private:
  libusb_device** list_ = nullptr;
  std::size_t count_ = 0;
  int error_ = 0;
};

// libusb_init, as a status and an owner: nullptr and the libusb error when it fails (a machine or
// container without usbfs).
inline ContextPtr make_context(int& error) {
  libusb_context* context = nullptr;
  error = libusb_init(&context);
  if (error != LIBUSB_SUCCESS) return nullptr;
  return ContextPtr(context);
}

// "bus 1 port 3", or "bus 1 port 1.4" behind a hub: what a user can match to a physical socket.
inline std::string bus_path(libusb_device* device) {
  std::array<std::uint8_t, 7> ports{};  // USB 3 allows at most 7 tiers below the root
  const int depth = libusb_get_port_numbers(device, ports.data(), static_cast<int>(ports.size()));
  std::string path = "bus " + std::to_string(libusb_get_bus_number(device));
  if (depth <= 0) return path + " address " + std::to_string(libusb_get_device_address(device));
  path += " port ";
  for (int i = 0; i < depth; ++i) {
    if (i > 0) path += '.';
    path += std::to_string(ports[static_cast<std::size_t>(i)]);
  }
  return path;
}

// The iSerialNumber string (decimal ASCII on the Phidgets); empty when the device has none or the
// request fails. Needs an open handle: string descriptors are fetched from the device.
inline std::string read_serial(libusb_device_handle* handle, std::uint8_t serial_index) {
  if (serial_index == 0) return {};
  std::array<unsigned char, 128> text{};
  const int length = libusb_get_string_descriptor_ascii(handle, serial_index, text.data(),
                                                        static_cast<int>(text.size()));
  if (length <= 0) return {};
  return std::string(reinterpret_cast<const char*>(text.data()), static_cast<std::size_t>(length));
}

// Milliseconds for libusb, rounded up so a sub-millisecond wait still waits. libusb reads 0 as
// "wait forever", so the shortest wait it can express, 1 ms, stands in for a poll.
inline unsigned int timeout_ms_at_least_one(std::chrono::nanoseconds timeout) {
  const auto ms = std::chrono::ceil<std::chrono::milliseconds>(timeout).count();
  if (ms < 1) return 1;
  if (ms > INT_MAX) return INT_MAX;
  return static_cast<unsigned int>(ms);
}

}  // namespace furuta::bridge::detail
