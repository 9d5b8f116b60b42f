#include "livo/datasets/conversion.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

namespace livo {

namespace {
std::string formatBytes(std::uint64_t b) {
  char buf[64];
  if (b >= (1ull << 20))
    std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(b) / (1 << 20));
  else
    std::snprintf(buf, sizeof buf, "%.1f KiB", static_cast<double>(b) / (1 << 10));
  return buf;
}
std::string formatTime(Utime t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", toSeconds(t));
  return buf;
}
}  // namespace

std::string ConversionSummary::describe() const {
  std::ostringstream os;
  os << "wrote " << output_path << " (" << formatBytes(file_bytes) << ", " << events << " events";
  if (events > 0)
    os << ", " << formatTime(first_utime) << " .. " << formatTime(last_utime) << " s, span "
       << toSeconds(last_utime - first_utime) << " s";
  os << ")\n";
  for (const auto& [channel, s] : channels) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-16s %8llu events  %12s  %.6f .. %.6f s\n", channel.c_str(),
                  static_cast<unsigned long long>(s.events), formatBytes(s.bytes).c_str(),
                  toSeconds(s.first_utime), toSeconds(s.last_utime));
    os << line;
  }
  return os.str();
}

SummaryLogWriter::SummaryLogWriter(const std::string& path) {
  summary_.output_path = path;
  try {
    writer_ = std::make_unique<LogWriter>(path);
  } catch (const std::exception& e) {
    throw DatasetError(path + ": cannot create the output log (" + e.what() + ")");
  }
}

SummaryLogWriter::~SummaryLogWriter() {
  if (committed_) return;
  writer_.reset();
  std::error_code ec;
  std::filesystem::remove(summary_.output_path, ec);  // partial output of a failed conversion
}

void SummaryLogWriter::writeRaw(const std::string& channel, Utime utime, const std::vector<std::uint8_t>& data) {
  if (summary_.events > 0 && utime < summary_.last_utime)
    throw DatasetError(summary_.output_path + ": internal error: events out of time order on " + channel);
  writer_->write(channel, utime, data.data(), data.size());
  ChannelStats& c = summary_.channels[channel];
  if (c.events == 0) c.first_utime = utime;
  c.last_utime = utime;
  ++c.events;
  c.bytes += data.size();
  if (summary_.events == 0) summary_.first_utime = utime;
  summary_.last_utime = utime;
  ++summary_.events;
}

ConversionSummary SummaryLogWriter::commit() {
  writer_->flush();
  writer_.reset();
  committed_ = true;
  std::error_code ec;
  summary_.file_bytes = std::filesystem::file_size(summary_.output_path, ec);
  return summary_;
}

}  // namespace livo
