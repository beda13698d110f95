#pragma once
// What the reader, the writer and the recovery share about LCM event logs, and the POSIX handles
// they hold. Internal to the module.

#include <lcm/lcm.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>

namespace furuta::session_log::detail {

inline constexpr std::uint32_t kSyncWord = 0xEDA1DA01;
// sync word (4) + event number (8) + utime (8) + channel length (4) + data length (4)
inline constexpr std::size_t kHeaderBytes = 28;

// The reader accepts any channel LCM's own event-log reader accepts (lcm/eventlog.c rejects a
// channel length of 0 or >= 1000), so no log lcm-logplayer plays is refused here; the tighter
// publishing limit is the writer's.
inline constexpr std::uint32_t kMaxChannelBytes = 999;
// What LCM can carry at all (lcm.h); longer channels could never have come off an LCM bus.
inline constexpr std::uint32_t kMaxWriterChannelBytes = LCM_MAX_CHANNEL_NAME_LENGTH;
// LCM's largest message (lcm.h, 256 MiB): a longer data length is damage, not data.
inline constexpr std::uint32_t kMaxDataBytes = LCM_MAX_MESSAGE_SIZE;

inline std::uint32_t load_u32_be(std::span<const std::uint8_t, 4> b) {
  return (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) | (std::uint32_t{b[2]} << 8) |
         std::uint32_t{b[3]};
}

inline std::uint64_t load_u64_be(std::span<const std::uint8_t, 8> b) {
  std::uint64_t v = 0;
  for (std::uint8_t byte : b) v = (v << 8) | byte;
  return v;
}

// Owns a file descriptor.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}
  ~UniqueFd() { reset(); }
  UniqueFd(UniqueFd&& other) noexcept : fd_(other.release()) {}
  UniqueFd& operator=(UniqueFd&& other) noexcept {
    if (this != &other) {
      reset();
      fd_ = other.release();
    }
    return *this;
  }
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1;
};

// Where a session's log is while it is written, and what it is called before and after.
inline constexpr const char* kPartialDir = ".partial";
inline constexpr const char* kPartSuffix = ".lcmlog.part";
inline constexpr const char* kFinalSuffix = ".lcmlog";
inline constexpr const char* kIncompleteSuffix = ".incomplete.lcmlog";

// A rename or a new entry lives in the directory, not in the file: without this a power cut may
// forget it even though the file's own data was synced. Returns 0 or the errno.
int fsync_directory(const std::filesystem::path& dir);

// Whether a live writer holds `part` (its flock, taken when it created the file and held while it
// writes): a session running now, not one a crash left.
bool held_by_a_writer(const std::filesystem::path& part);

// rename(2) that never replaces an existing file (where the file system supports it; elsewhere a
// plain rename). Returns 0 or the errno, EEXIST when `to` exists.
int rename_no_replace(const std::filesystem::path& from, const std::filesystem::path& to);

}  // namespace furuta::session_log::detail
