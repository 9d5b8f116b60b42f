#include "livo/io/log.hpp"

#include <lcm/lcm-cpp.hpp>

#include <cerrno>
#include <cstring>

namespace livo {

namespace {
constexpr std::uint32_t kSyncWord = 0xEDA1DA01u;
constexpr std::size_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;
constexpr std::uint32_t kMaxChannelBytes = 256;

std::uint64_t readBe(const std::uint8_t* p, int n) {
  std::uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}
}  // namespace

// ---------------- writer ----------------
LogWriter::LogWriter(const std::string& path) : path_(path) {
  log_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!log_->good()) throw LogError(path + ": cannot open log for writing: " + std::strerror(errno));
}

LogWriter::~LogWriter() = default;

void LogWriter::write(const std::string& channel, Utime timestamp, const void* data, std::size_t size) {
  if (channel.empty() || channel.size() > kMaxChannelBytes) throw LogError(path_ + ": invalid channel name '" + channel + "'");
  lcm::LogEvent ev;
  ev.eventnum = static_cast<std::int64_t>(events_);
  ev.timestamp = timestamp;
  ev.channel = channel;
  ev.datalen = static_cast<std::int32_t>(size);
  ev.data = const_cast<void*>(data);
  if (log_->writeEvent(&ev) != 0) throw LogError(path_ + ": write failed: " + std::strerror(errno));
  ++events_;
}

void LogWriter::flush() {
  if (std::FILE* f = log_->getFilePtr()) std::fflush(f);
}

// ---------------- reader ----------------
LogReader::LogReader(const std::string& path) : path_(path) {
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) throw LogError(path + ": cannot open log: " + std::strerror(errno));
  std::fseek(file_, 0, SEEK_END);
  size_ = static_cast<std::uint64_t>(std::ftell(file_));
  std::fseek(file_, 0, SEEK_SET);
}

LogReader::~LogReader() {
  if (file_) std::fclose(file_);
}

std::uint64_t LogReader::position() const { return pos_; }

bool LogReader::next(LogEvent& ev) {
  if (pos_ == size_) return false;  // clean end of file
  const auto where = [&](const std::string& what) {
    return LogError(path_ + ": " + what + " at byte " + std::to_string(pos_) + " (after " + std::to_string(events_) +
                    " good events)");
  };
  std::uint8_t h[kHeaderBytes];
  if (size_ - pos_ < kHeaderBytes) throw where("truncated log: incomplete event header");
  if (std::fread(h, 1, kHeaderBytes, file_) != kHeaderBytes) throw where("read error");
  if (readBe(h, 4) != kSyncWord) throw where("corrupt log: bad sync word");
  const std::uint32_t channel_len = static_cast<std::uint32_t>(readBe(h + 20, 4));
  const std::uint32_t data_len = static_cast<std::uint32_t>(readBe(h + 24, 4));
  if (channel_len == 0 || channel_len > kMaxChannelBytes)
    throw where("corrupt log: channel name length " + std::to_string(channel_len));
  if (data_len > kMaxEventBytes) throw where("corrupt log: event data length " + std::to_string(data_len));
  if (size_ - pos_ - kHeaderBytes < std::uint64_t(channel_len) + data_len)
    throw where("truncated log: event declares " + std::to_string(channel_len + data_len) + " bytes, " +
                std::to_string(size_ - pos_ - kHeaderBytes) + " remain");
  ev.eventnum = static_cast<std::int64_t>(readBe(h + 4, 8));
  ev.timestamp = static_cast<std::int64_t>(readBe(h + 12, 8));
  ev.channel.resize(channel_len);
  ev.data.resize(data_len);
  if (std::fread(&ev.channel[0], 1, channel_len, file_) != channel_len ||
      (data_len > 0 && std::fread(ev.data.data(), 1, data_len, file_) != data_len))
    throw where("read error");
  for (char c : ev.channel)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e)
      throw where("corrupt log: non-printable channel name");
  pos_ += kHeaderBytes + channel_len + data_len;
  ++events_;
  return true;
}

}  // namespace livo
