// Shared pieces of the dataset converters: the error type, the summary of a conversion and a log writer
// that keeps per-channel statistics.
#pragma once

#include "livo/common/types.hpp"
#include "livo/io/log.hpp"

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace livo {

/// Bad or missing dataset input. The message names the file and the line (text files), the byte size
/// (binary files) or the key (calibration files).
struct DatasetError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Called during a conversion with the number of input items done and their total.
using ProgressFn = std::function<void(std::uint64_t done, std::uint64_t total)>;

/// Events written to one channel.
struct ChannelStats {
  std::uint64_t events = 0;
  std::uint64_t bytes = 0;  ///< encoded message bytes
  Utime first_utime = 0;
  Utime last_utime = 0;
};

/// What a conversion wrote.
struct ConversionSummary {
  std::string output_path;
  std::map<std::string, ChannelStats> channels;
  std::uint64_t events = 0;
  Utime first_utime = 0;
  Utime last_utime = 0;
  std::uint64_t file_bytes = 0;  ///< size of the log file
  /// Human-readable multi-line summary (events per channel, time span, output size).
  std::string describe() const;
};

/// Writes events to a log in non-decreasing time order (log timestamp = message utime) and counts them.
/// On destruction without commit() the partial output file is removed: a failed conversion leaves no
/// log that looks complete.
class SummaryLogWriter {
 public:
  explicit SummaryLogWriter(const std::string& path);
  ~SummaryLogWriter();
  SummaryLogWriter(const SummaryLogWriter&) = delete;
  SummaryLogWriter& operator=(const SummaryLogWriter&) = delete;

  template <class Msg>
  void write(const std::string& channel, const Msg& m) {
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    writeRaw(channel, m.utime, buf);
  }
  /// Closes the log and returns the summary; the file is kept.
  ConversionSummary commit();

 private:
  void writeRaw(const std::string& channel, Utime utime, const std::vector<std::uint8_t>& data);
  std::unique_ptr<LogWriter> writer_;
  ConversionSummary summary_;
  bool committed_ = false;
};

}  // namespace livo
