// SHA-256 from GLib's GChecksum: a well-kept implementation the project links already (LCM
// brings GLib), rather than one of our own.
#include "log_digest.hpp"

#include <glib.h>

namespace furuta::session_log::detail {

namespace {

void put_be(GChecksum* checksum, std::uint64_t value, int bytes) {
  std::array<std::uint8_t, 8> out{};
  for (int i = 0; i < bytes; ++i) {
    out[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(value >> (8 * (bytes - 1 - i)));
  }
  g_checksum_update(checksum, out.data(), bytes);
}

}  // namespace

struct LogDigest::Checksum {
  struct Free {
    void operator()(GChecksum* c) const { g_checksum_free(c); }
  };
  std::unique_ptr<GChecksum, Free> state{g_checksum_new(G_CHECKSUM_SHA256)};
};

LogDigest::LogDigest() : checksum_(std::make_unique<Checksum>()) {}

LogDigest::~LogDigest() = default;

void LogDigest::add(std::int64_t event_number, std::int64_t utime, std::string_view channel,
                    std::span<const std::uint8_t> data) {
  GChecksum* c = checksum_->state.get();
  put_be(c, static_cast<std::uint64_t>(event_number), 8);
  put_be(c, static_cast<std::uint64_t>(utime), 8);
  put_be(c, channel.size(), 4);
  g_checksum_update(c, reinterpret_cast<const guchar*>(channel.data()),
                    static_cast<gssize>(channel.size()));
  put_be(c, data.size(), 4);
  g_checksum_update(c, data.data(), static_cast<gssize>(data.size()));
  ++events_;
}

Digest LogDigest::value() const {
  // Reading a GChecksum closes it: the value comes from a copy, so the running state goes on.
  const std::unique_ptr<GChecksum, Checksum::Free> copy(g_checksum_copy(checksum_->state.get()));
  Digest out{};
  gsize length = out.size();
  g_checksum_get_digest(copy.get(), out.data(), &length);
  return out;
}

std::string hex(std::span<const std::uint8_t> bytes) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(2 * bytes.size());
  for (const std::uint8_t b : bytes) {
    out += kHex[b >> 4];
    out += kHex[b & 0x0F];
  }
  return out;
}

}  // namespace furuta::session_log::detail
