// The checked reader. LCM's own reader (lcm/eventlog.c) allocates whatever a length field says and
// gives up at the first damage; a log cut short by a crash or damaged on disk must still yield
// every intact event, so every length here is checked against the bytes that exist before anything
// is allocated or read, and damage is skipped by resynchronising on a later event that proves
// itself.

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>

#include "furuta/session_log/lcm_log.hpp"
#include "lcm_log_format.hpp"

namespace furuta::session_log {

namespace {

using detail::kHeaderBytes;
using detail::kSyncWord;

constexpr std::array<std::uint8_t, 4> kSyncBytes = {0xED, 0xA1, 0xDA, 0x01};

// Random access to the bytes of a log, file or buffer, so one scanner serves both.
class ByteSource {
 public:
  virtual ~ByteSource() = default;
  virtual std::uint64_t size() const = 0;
  // Copies [offset, offset + out.size()); false when those bytes cannot be had (the caller keeps
  // within size(), so for a file this means it shrank or failed under us).
  virtual bool read(std::uint64_t offset, std::span<std::uint8_t> out) = 0;
  // The first offset >= from holding `byte`, or size() when there is none (or reading failed).
  virtual std::uint64_t find_byte(std::uint64_t from, std::uint8_t byte) = 0;
};

class SpanSource final : public ByteSource {
 public:
  explicit SpanSource(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
  std::uint64_t size() const override { return bytes_.size(); }
  bool read(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (offset > bytes_.size() || out.size() > bytes_.size() - offset) return false;
    std::copy_n(bytes_.begin() + static_cast<std::ptrdiff_t>(offset), out.size(), out.begin());
    return true;
  }
  std::uint64_t find_byte(std::uint64_t from, std::uint8_t byte) override {
    if (from >= bytes_.size()) return bytes_.size();
    const void* hit = std::memchr(bytes_.data() + from, byte, bytes_.size() - from);
    if (hit == nullptr) return bytes_.size();
    return static_cast<std::uint64_t>(static_cast<const std::uint8_t*>(hit) - bytes_.data());
  }

 private:
  std::span<const std::uint8_t> bytes_;
};

// pread through a window: headers and the byte-by-byte search after damage are small reads close
// together. The size is fixed at open, so a log still being written is read as it was then; the
// file is never mapped, because a mapping of a file truncated under us (recovery, another process)
// faults with SIGBUS.
class FileSource final : public ByteSource {
 public:
  explicit FileSource(const std::filesystem::path& path) {
    fd_ = detail::UniqueFd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
    if (!fd_.valid()) {
      throw std::runtime_error("cannot open LCM log " + path.string() + ": " +
                               std::strerror(errno));
    }
    struct stat st {};
    if (::fstat(fd_.get(), &st) != 0) {
      throw std::runtime_error("cannot stat LCM log " + path.string() + ": " +
                               std::strerror(errno));
    }
    if (!S_ISREG(st.st_mode)) {
      throw std::runtime_error("LCM log " + path.string() + " is not a regular file");
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }

  std::uint64_t size() const override { return size_; }

  bool read(std::uint64_t offset, std::span<std::uint8_t> out) override {
    if (offset > size_ || out.size() > size_ - offset) return false;
    if (out.size() > window_.size()) return pread_all(offset, out);
    if (!cover(offset, out.size())) return false;
    std::copy_n(window_.begin() + static_cast<std::ptrdiff_t>(offset - window_offset_), out.size(),
                out.begin());
    return true;
  }

  std::uint64_t find_byte(std::uint64_t from, std::uint8_t byte) override {
    while (from < size_) {
      if (!cover(from, 1)) return size_;
      const std::uint8_t* begin = window_.data() + (from - window_offset_);
      const std::size_t n = window_length_ - static_cast<std::size_t>(from - window_offset_);
      const void* hit = std::memchr(begin, byte, n);
      if (hit != nullptr)
        return from + static_cast<std::uint64_t>(static_cast<const std::uint8_t*>(hit) - begin);
      from += n;
    }
    return size_;
  }

 private:
  // Makes [offset, offset + n) part of the window (n <= window size, within the file).
  bool cover(std::uint64_t offset, std::size_t n) {
    if (offset >= window_offset_ && offset + n <= window_offset_ + window_length_) return true;
    const std::size_t want =
        static_cast<std::size_t>(std::min<std::uint64_t>(window_.size(), size_ - offset));
    if (!pread_all(offset, std::span(window_.data(), want))) {
      window_length_ = 0;
      return false;
    }
    window_offset_ = offset;
    window_length_ = want;
    return true;
  }

  bool pread_all(std::uint64_t offset, std::span<std::uint8_t> out) {
    std::size_t done = 0;
    while (done < out.size()) {
      const ssize_t n = ::pread(fd_.get(), out.data() + done, out.size() - done,
                                static_cast<off_t>(offset + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }

  detail::UniqueFd fd_;
  std::uint64_t size_ = 0;
  std::array<std::uint8_t, 64 * 1024> window_{};
  std::uint64_t window_offset_ = 0;
  std::size_t window_length_ = 0;
};

// The reading core, for files and buffers alike.
class Scanner {
 public:
  explicit Scanner(ByteSource& source) : source_(source), size_(source.size()) {}

  bool next(LogEvent& event) {
    while (pos_ < size_) {
      Header header;
      Verdict verdict = examine(pos_, header);
      std::optional<std::uint64_t> resume;
      if (verdict == Verdict::unconfirmed) {
        // In step with the events before it, this one is taken unless its length runs into an
        // event that confirms itself further on: then the length is the damage. Otherwise the
        // damage is what follows it (a burst over the next header, say), found on the next call.
        resume = find_event(pos_ + 1);
        verdict = resume && *resume < header.end ? Verdict::bad : Verdict::event;
      }
      if (verdict == Verdict::event) {
        if (!load(header, event)) {
          finish_at_tail(Verdict::truncated);
          return false;
        }
        pos_ = header.end;
        ++stats_.events;
        if (!damaged_) stats_.readable_prefix_bytes = pos_;
        return true;
      }
      if (!resume) resume = find_event(pos_ + 1);
      if (!resume) {
        finish_at_tail(verdict);
        return false;
      }
      mark_damage(*resume - pos_);
      pos_ = *resume;
    }
    return false;
  }

  const LogReadStats& stats() const { return stats_; }

 private:
  enum class Verdict : std::uint8_t {
    event,        // a whole, plausible event that ends at EOF or before the next sync word
    unconfirmed,  // a whole, plausible event followed by something else
    truncated,    // an event's start whose rest the file does not hold
    bad,          // anything else
  };

  struct Header {
    std::uint64_t offset = 0;
    std::int64_t event_number = 0;
    std::int64_t utime = 0;
    std::uint32_t channel_bytes = 0;
    std::uint32_t data_bytes = 0;
    std::uint64_t end = 0;
  };

  // Decides what starts at `offset`, reading only headers and the four bytes after the event.
  Verdict examine(std::uint64_t offset, Header& header) {
    const std::uint64_t available = size_ - offset;
    std::array<std::uint8_t, 4> sync{};
    if (available < sync.size()) {
      const std::span tail(sync.data(), static_cast<std::size_t>(available));
      if (!source_.read(offset, tail)) return Verdict::truncated;
      return std::equal(tail.begin(), tail.end(), kSyncBytes.begin()) ? Verdict::truncated
                                                                      : Verdict::bad;
    }
    if (!source_.read(offset, sync) || sync != kSyncBytes) return Verdict::bad;
    const Verdict verdict = parse_header(offset, header);
    if (verdict != Verdict::event) return verdict;
    // A header that merely looks right (a sync word inside data, a length off by a flipped bit)
    // rarely also lands exactly on the next event or on the end of the file.
    if (at_boundary(header.end) || damaged_sync_header_at(header.end)) return Verdict::event;
    return Verdict::unconfirmed;
  }

  // The header at `offset`, sync word aside: event when its lengths are plausible and the event
  // fits in the file.
  Verdict parse_header(std::uint64_t offset, Header& header) {
    const std::uint64_t available = size_ - offset;
    std::array<std::uint8_t, kHeaderBytes> h{};
    if (available < kHeaderBytes || !source_.read(offset, h)) return Verdict::truncated;
    header.offset = offset;
    header.event_number =
        static_cast<std::int64_t>(detail::load_u64_be(std::span<const std::uint8_t, 8>(&h[4], 8)));
    header.utime =
        static_cast<std::int64_t>(detail::load_u64_be(std::span<const std::uint8_t, 8>(&h[12], 8)));
    header.channel_bytes = detail::load_u32_be(std::span<const std::uint8_t, 4>(&h[20], 4));
    header.data_bytes = detail::load_u32_be(std::span<const std::uint8_t, 4>(&h[24], 4));
    // Writers number events from 0; a negative number is a header that was never written as one.
    if (header.event_number < 0) return Verdict::bad;
    if (header.channel_bytes == 0 || header.channel_bytes > detail::kMaxChannelBytes) {
      return Verdict::bad;
    }
    if (header.data_bytes > detail::kMaxDataBytes) return Verdict::bad;
    // Both lengths are bounded above, so this cannot overflow.
    const std::uint64_t length =
        kHeaderBytes + std::uint64_t{header.channel_bytes} + header.data_bytes;
    if (length > available) return Verdict::truncated;
    header.end = offset + length;
    return Verdict::event;
  }

  // The end of the file, a sync word, or (fewer than four bytes left) a sync word cut short by a
  // crash.
  bool at_boundary(std::uint64_t offset) {
    std::array<std::uint8_t, 4> next{};
    const std::span bytes(next.data(), static_cast<std::size_t>(
                                           std::min<std::uint64_t>(size_ - offset, next.size())));
    return source_.read(offset, bytes) &&
           std::equal(bytes.begin(), bytes.end(), kSyncBytes.begin());
  }

  // When the damage is the next event's sync word, the event before it is intact: tell the two
  // apart by what follows, a header whole in every other respect that lands on a boundary (a length
  // cut short by damage instead leaves us inside data, where that almost never holds).
  bool damaged_sync_header_at(std::uint64_t offset) {
    Header next;
    return parse_header(offset, next) == Verdict::event && at_boundary(next.end);
  }

  // The first offset >= from where an event confirms itself. After damage only such an event is
  // trusted: a sync word inside data, or in garbage, must also land on a boundary to pass.
  std::optional<std::uint64_t> find_event(std::uint64_t from) {
    // One answer serves every later question from before it: next() asks again from inside the
    // region it has just searched.
    if (found_ && from >= found_from_ && from <= found_at_) return as_result(found_at_);
    found_from_ = from;
    Header header;
    while (from < size_) {
      from = source_.find_byte(from, kSyncBytes[0]);
      if (from >= size_) break;
      if (examine(from, header) == Verdict::event) break;
      ++from;
    }
    found_ = true;
    found_at_ = std::min(from, size_);
    return as_result(found_at_);
  }

  std::optional<std::uint64_t> as_result(std::uint64_t at) const {
    return at < size_ ? std::optional(at) : std::nullopt;
  }

  bool load(const Header& header, LogEvent& event) {
    event.event_number = header.event_number;
    event.utime = header.utime;
    event.file_offset = header.offset;
    // Both sizes were checked against the bytes present (and bounded) by examine().
    event.channel.assign(header.channel_bytes, '\0');
    event.data.resize(header.data_bytes);
    const std::uint64_t channel_at = header.offset + kHeaderBytes;
    return source_.read(channel_at, std::span(reinterpret_cast<std::uint8_t*>(event.channel.data()),
                                              event.channel.size())) &&
           source_.read(channel_at + header.channel_bytes, event.data);
  }

  void mark_damage(std::uint64_t bytes) {
    ++stats_.damaged_regions;
    stats_.bytes_skipped += bytes;
    damaged_ = true;
  }

  // Nothing readable from pos_ to the end. A cut-off event is what a crash leaves, not damage; its
  // bytes still count as skipped, so events' bytes plus bytes_skipped always make up the file.
  void finish_at_tail(Verdict verdict) {
    if (verdict == Verdict::truncated) {
      stats_.truncated_tail = true;
      stats_.bytes_skipped += size_ - pos_;
    } else {
      mark_damage(size_ - pos_);
    }
    pos_ = size_;
  }

  ByteSource& source_;
  std::uint64_t size_;
  std::uint64_t pos_ = 0;
  bool damaged_ = false;
  LogReadStats stats_;
  bool found_ = false;  // find_event's last answer: no confirmed event in [found_from_, found_at_)
  std::uint64_t found_from_ = 0;
  std::uint64_t found_at_ = 0;
};

}  // namespace

class LcmLogReader::Impl {
 public:
  explicit Impl(const std::filesystem::path& path) : source_(path), scanner_(source_) {}
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  FileSource source_;
  Scanner scanner_;
};

LcmLogReader::LcmLogReader(const std::filesystem::path& path)
    : impl_(std::make_unique<Impl>(path)) {}

LcmLogReader::~LcmLogReader() = default;

bool LcmLogReader::next(LogEvent& event) {
  return impl_->scanner_.next(event);
}

const LogReadStats& LcmLogReader::stats() const {
  return impl_->scanner_.stats();
}

std::vector<LogEvent> read_lcm_log_bytes(std::span<const std::uint8_t> bytes, LogReadStats& stats) {
  SpanSource source(bytes);
  Scanner scanner(source);
  std::vector<LogEvent> events;
  LogEvent event;
  while (scanner.next(event)) events.push_back(std::move(event));
  stats = scanner.stats();
  return events;
}

}  // namespace furuta::session_log
