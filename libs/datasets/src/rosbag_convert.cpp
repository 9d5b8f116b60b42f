// ROS 1 bag -> LCM log (rules in rosbag.hpp and ros_input.hpp): select topics, decide the IMU acceleration
// unit from the first samples, then decode every message (RosDecoder, shared with livo-ros-bridge) and write
// the events in time order through a reorder window.
#include "livo/datasets/rosbag.hpp"
#include "livo/io/convert.hpp"

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <limits>
#include <variant>

namespace livo {

namespace {

std::string seconds(Utime t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", toSeconds(t));
  return buf;
}

/// Decoded events held until no earlier event can still arrive (utime <= newest - window), then written
/// in (utime, arrival) order. Events older than the last written one are dropped and counted. A stamp more
/// than kJumpUs ahead of the newest moves the window only once a second such event confirms the jump (a
/// real gap, or a topic on another clock, whose other events are then dropped as late and counted): a
/// single glitched stamp cannot flush, and so drop, everything else; it waits in the buffer for its turn.
class ReorderBuffer {
 public:
  using Payload = RosPayload;
  static constexpr Utime kJumpUs = 10'000'000;
  ReorderBuffer(SummaryLogWriter& out, Utime window) : out_(out), window_(window) {}

  void push(const std::string* channel, Utime utime, Payload p) {
    if (written_any_ && utime < last_written_) {
      ++late_[*channel];
      return;
    }
    if (!started_ || utime <= newest_ + kJumpUs) {
      newest_ = started_ ? std::max(newest_, utime) : utime;
      started_ = true;
      if (jump_pending_ && newest_ >= jump_utime_) jump_pending_ = false;  // caught up with it
    } else if (jump_pending_) {  // a second event beyond the jump: the stream really moved on
      newest_ = std::max(newest_, std::min(utime, jump_utime_));
      jump_pending_ = false;
    } else {
      jump_pending_ = true;
      jump_utime_ = utime;
    }
    events_.emplace(std::make_pair(utime, seq_++), Event{channel, std::move(p)});
    while (!events_.empty() && events_.begin()->first.first <= newest_ - window_) writeFirst();
  }
  void flushAll() {
    while (!events_.empty()) writeFirst();
  }
  const std::map<std::string, std::uint64_t>& late() const { return late_; }

 private:
  struct Event {
    const std::string* channel;
    Payload payload;
  };
  void writeFirst() {
    auto it = events_.begin();
    std::visit([&](const auto& v) { out_.write(*it->second.channel, toMsg(v)); }, it->second.payload);
    last_written_ = it->first.first;
    written_any_ = true;
    events_.erase(it);
  }
  SummaryLogWriter& out_;
  Utime window_;
  Utime newest_ = 0;
  Utime last_written_ = 0;
  Utime jump_utime_ = 0;
  bool started_ = false, written_any_ = false, jump_pending_ = false;
  std::uint64_t seq_ = 0;
  std::map<std::pair<Utime, std::uint64_t>, Event> events_;
  std::map<std::string, std::uint64_t> late_;
};

/// Messages skipped as malformed (--skip-bad), for the warnings; the scan rules count in RosDecodeCounts.
struct Skipped {
  std::uint64_t bad_messages = 0;
  std::string long_example, bad_example;  ///< with the message's context
};

std::string messageContext(const std::string& bag, const BagMessage& m) {
  return bag + ": topic " + *m.topic + ", message " + std::to_string(m.index) + " (record time " +
         seconds(m.bag_time) + " s): ";
}

void checkOptions(const RosbagOptions& opt) {
  if (!(opt.reorder_window_s >= 0) || !std::isfinite(opt.reorder_window_s))
    throw DatasetError("--reorder-window must be a non-negative number of seconds");
  checkRosInputOptions(opt);
}

/// The IMU unit from the bag's first samples (ImuUnitGate, as the live bridge decides it).
void decideAccelUnit(RosbagReader& bag, const std::string& imu_topic, const RosbagOptions& opt, RosbagSummary& summary) {
  ImuUnitGate gate(opt);
  std::vector<ImuSample> released;  // only the decision is needed here
  if (!gate.decided()) {
    try {
      bag.forEach({imu_topic}, [&](const BagMessage& m) {
        try {
          gate.push(decodeRosImu(m.data->data(), m.data->size()), released);
        } catch (const DatasetError&) {  // reported by the main pass
        }
        return !gate.decided();
      });
    } catch (const BagReadError&) {  // a corrupt chunk among the first samples: the main pass reports it
    }
    gate.finish(released);
  }
  summary.accel_scale = gate.scale();
  summary.accel_note = gate.note();
}

/// The main pass: decodes each message of the chosen topics (RosDecoder) into the reorder buffer. A
/// malformed message stops the pass (DatasetError naming it) unless skip_bad_messages.
class MessageConverter {
 public:
  MessageConverter(const std::string& bag_path, const RosbagOptions& opt, ReorderBuffer& buffer,
                   RosbagSummary& summary, std::uint64_t total)
      : bag_path_(bag_path), opt_(opt), sel_(summary.topics), decoder_(opt), buffer_(buffer), summary_(summary),
        total_(total) {}

  /// One message; true: go on (the RosbagReader::forEach callback).
  bool onMessage(const BagMessage& m) {
    ++summary_.messages_read;
    try {
      decode(m);
    } catch (const BagReadError&) {
      throw;
    } catch (const DatasetError& e) {
      if (!opt_.skip_bad_messages) throw DatasetError(messageContext(bag_path_, m) + e.what());
      if (skipped_.bad_messages++ == 0) skipped_.bad_example = messageContext(bag_path_, m) + e.what();
    }
    if (opt_.progress) opt_.progress(summary_.messages_read, total_);
    return true;
  }
  const Skipped& skipped() const { return skipped_; }
  const RosDecodeCounts& counts() const { return decoder_.counts(); }

 private:
  void decode(const BagMessage& m) {
    const bool imu = *m.topic == sel_.imu, lidar = *m.topic == sel_.lidar;
    const RosType type = imu ? RosType::Imu : lidar ? sel_.lidar_type : sel_.image_type;
    const std::uint64_t long_before = decoder_.counts().long_scans;
    std::optional<RosPayload> p = decoder_.decode(type, m.data->data(), m.data->size());
    if (long_before == 0 && decoder_.counts().long_scans == 1)
      skipped_.long_example = messageContext(bag_path_, m) + decoder_.counts().long_example;
    if (!p) return;
    if (auto* s = std::get_if<ImuSample>(&*p)) s->accel *= summary_.accel_scale;
    const std::string* channel = imu ? &opt_.imu_channel : lidar ? &opt_.lidar_channel : &opt_.camera_channel;
    const Utime t = payloadUtime(*p);
    buffer_.push(channel, t, std::move(*p));
  }

  const std::string& bag_path_;
  const RosbagOptions& opt_;
  const RosbagTopics& sel_;
  RosDecoder decoder_;
  ReorderBuffer& buffer_;
  RosbagSummary& summary_;
  const std::uint64_t total_;  ///< messages on the chosen topics, for the progress callback
  Skipped skipped_;
};

void addWarnings(RosbagSummary& summary, const ReorderBuffer& buffer, const Skipped& skipped,
                 const RosDecodeCounts& counts, const RosbagOptions& opt) {
  auto warn = [&](std::uint64_t count, const std::string& what) {
    if (count > 0) summary.warnings.push_back(std::to_string(count) + " " + what);
  };
  for (const auto& [channel, count] : buffer.late())
    warn(count, channel + " events arrived later than the reorder window (" + std::to_string(opt.reorder_window_s) +
                    " s) and were dropped (use --reorder-window, or check the stamps)");
  warn(counts.empty_scans, "empty scans skipped");
  warn(counts.long_scans, "scans skipped: point times span more than " + std::to_string(opt.max_scan_span_s) +
                              " s, wrong time unit? First: " + skipped.long_example);
  warn(counts.untimed_scans, "scans without a per-point time field: offsets 0 (undistortion impossible)");
  warn(counts.nonfinite_points, "points with non-finite coordinates dropped");
  warn(skipped.bad_messages, "malformed messages skipped (--skip-bad). First: " + skipped.bad_example);
}

}  // namespace

std::string RosbagSummary::describe() const {
  std::ostringstream os;
  os << conversion.describe();
  os << "  topics: lidar " << (topics.lidar.empty() ? "-" : topics.lidar) << ", imu "
     << (topics.imu.empty() ? "-" : topics.imu) << ", camera " << (topics.image.empty() ? "-" : topics.image) << "\n";
  if (!accel_note.empty()) os << "  imu: " << accel_note << "\n";
  for (const auto& w : warnings) os << "  warning: " << w << "\n";
  if (!error.empty()) os << "  STOPPED EARLY (the log keeps the events before this): " << error << "\n";
  return os.str();
}

RosbagSummary convertRosbag(const std::string& bag_path, const std::string& out_log, const RosbagOptions& opt) {
  checkOptions(opt);

  // 1. Topics (all checks before any output exists).
  RosbagReader bag(bag_path);
  RosbagSummary summary;
  summary.topics = selectRosbagTopics(bag.topics(), opt, bag_path);
  const RosbagTopics& sel = summary.topics;

  // 2. IMU acceleration unit from the first samples.
  if (!sel.imu.empty()) decideAccelUnit(bag, sel.imu, opt, summary);

  // 3. Every message of the chosen topics, in record order, through the reorder buffer.
  std::vector<std::string> wanted;
  for (const std::string* t : {&sel.lidar, &sel.imu, &sel.image})
    if (!t->empty()) wanted.push_back(*t);
  const std::uint64_t total = bag.messageCount(wanted);
  SummaryLogWriter out(out_log);
  ReorderBuffer buffer(out, static_cast<Utime>(std::llround(opt.reorder_window_s * 1e6)));
  MessageConverter converter(bag_path, opt, buffer, summary, total);
  try {
    bag.forEach(wanted, [&](const BagMessage& m) { return converter.onMessage(m); });
  } catch (const DatasetError& e) {
    summary.error = e.what();  // keep what was converted before it
  }
  buffer.flushAll();
  summary.conversion = out.commit();

  // 4. Warnings.
  addWarnings(summary, buffer, converter.skipped(), converter.counts(), opt);
  return summary;
}

}  // namespace livo
