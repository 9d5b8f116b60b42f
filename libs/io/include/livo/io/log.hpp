// LCM log files for offline runs: writing events with chosen timestamps (through lcm::LogFile) and
// reading them back in order. Reading uses its own parser of the LCM log format (sync word 0xEDA1DA01,
// eventnum, timestamp, channel length, data length, channel, data; all big-endian) because
// lcm_eventlog_read_next_event asserts on a corrupt channel length and allocates from unchecked data
// lengths. Truncation and corruption are reported as errors (with the byte offset and the number of good
// events before it) instead of a silent end of file or an abort.
#pragma once

#include "livo/common/types.hpp"

#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace lcm {
class LogFile;
}

namespace livo {

struct LogError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// One event of a log.
struct LogEvent {
  std::int64_t eventnum = 0;
  Utime timestamp = 0;  ///< log timestamp, microseconds (the suite writes sensor times here)
  std::string channel;
  std::vector<std::uint8_t> data;
};

/// Writes events to a new LCM log file (overwrites). Throws LogError on I/O failure.
class LogWriter {
 public:
  explicit LogWriter(const std::string& path);
  ~LogWriter();
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  void write(const std::string& channel, Utime timestamp, const void* data, std::size_t size);
  /// Encodes and writes any generated LCM message.
  template <class Msg>
  void write(const std::string& channel, Utime timestamp, const Msg& m) {
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    write(channel, timestamp, buf.data(), buf.size());
  }
  void flush();
  std::uint64_t eventsWritten() const { return events_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> log_;
  std::uint64_t events_ = 0;
};

/// Reads events in file order. next() returns false at a clean end of file and throws LogError
/// (with the byte offset and the number of good events) on a truncated or corrupt file.
class LogReader {
 public:
  /// Largest event accepted (bytes of data); larger declared lengths are reported as corruption.
  static constexpr std::uint32_t kMaxEventBytes = 256u << 20;
  explicit LogReader(const std::string& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  bool next(LogEvent& ev);
  std::uint64_t eventsRead() const { return events_; }
  std::uint64_t fileSize() const { return size_; }
  /// Bytes consumed so far (for progress output).
  std::uint64_t position() const;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
  std::uint64_t pos_ = 0;
  std::uint64_t events_ = 0;
};

}  // namespace livo
