#pragma once
// The running digest a session log's seal carries (rig_log_seal_t): SHA-256 over each event's
// number, time, channel and data, in the order written. The writer feeds it every event it
// writes; the loader feeds it every event it reads before the seal, and compares. Internal to the
// module.

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

namespace furuta::session_log::detail {

inline constexpr const char* kDigestAlgorithm = "sha256";
inline constexpr std::size_t kDigestBytes = 32;
using Digest = std::array<std::uint8_t, kDigestBytes>;

class LogDigest {
 public:
  LogDigest();
  ~LogDigest();
  LogDigest(const LogDigest&) = delete;
  LogDigest& operator=(const LogDigest&) = delete;

  void add(std::int64_t event_number, std::int64_t utime, std::string_view channel,
           std::span<const std::uint8_t> data);
  // The digest of everything added so far (the running state goes on).
  Digest value() const;
  std::uint64_t events() const { return events_; }

 private:
  struct Checksum;
  std::unique_ptr<Checksum> checksum_;
  std::uint64_t events_ = 0;
};

std::string hex(std::span<const std::uint8_t> bytes);

}  // namespace furuta::session_log::detail
