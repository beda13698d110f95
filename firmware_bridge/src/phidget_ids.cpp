#include "furuta/firmware_bridge/phidget_ids.hpp"

#include "furuta/firmware_bridge/codec_1047.hpp"
#include "furuta/firmware_bridge/codec_1065.hpp"
#include "furuta/firmware_bridge/transport.hpp"

namespace furuta::bridge {

std::string_view phidget_product_name(std::uint16_t product_id) {
  switch (product_id) {
    case kProductMotorControl1065:
      return "1065 MotorControl 1-Motor";
    case kProductEncoder1047:
      return "1047 Encoder HighSpeed 4-input";
    case kProductEncoder1057:
      return "1057 Encoder HighSpeed 1-input";
    case kProductMotorControl1064:
      return "1064 MotorControl HC";
    case kProductMotorControl1060:
      return "1060 MotorControl LV";
    default:
      return "unknown Phidget";
  }
}

std::optional<FirmwareRange> known_firmware(std::uint16_t product_id, bool vendor_class_interface) {
  switch (product_id) {
    case kProductMotorControl1065:
      if (vendor_class_interface) return std::nullopt;
      return FirmwareRange{100, 199};
    case kProductEncoder1047:
      return vendor_class_interface ? FirmwareRange{200, 299} : FirmwareRange{100, 199};
    default:
      return std::nullopt;
  }
}

bool firmware_known(std::uint16_t product_id, bool vendor_class_interface, int version) {
  const std::optional<FirmwareRange> range = known_firmware(product_id, vendor_class_interface);
  return range && version >= range->first && version <= range->last;
}

std::size_t minimum_input_report_bytes(std::uint16_t product_id) {
  switch (product_id) {
    case kProductMotorControl1065:
      return k1065InputReportMinBytes;
    case kProductEncoder1047:
      return k1047InputReportMinBytes;
    default:
      return 0;
  }
}

std::string_view to_string(TransportStatus status) {
  switch (status) {
    case TransportStatus::ok:
      return "ok";
    case TransportStatus::timeout:
      return "timeout";
    case TransportStatus::not_found:
      return "not_found";
    case TransportStatus::access_denied:
      return "access_denied";
    case TransportStatus::busy:
      return "busy";
    case TransportStatus::disconnected:
      return "disconnected";
    case TransportStatus::short_report:
      return "short_report";
    case TransportStatus::io_error:
      return "io_error";
    case TransportStatus::not_open:
      return "not_open";
    case TransportStatus::invalid_argument:
      return "invalid_argument";
    case TransportStatus::replay_mismatch:
      return "replay_mismatch";
    case TransportStatus::replay_exhausted:
      return "replay_exhausted";
  }
  return "unknown";
}

}  // namespace furuta::bridge
