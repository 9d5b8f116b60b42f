#include "report.hpp"

#include <cstdio>
#include <sstream>

namespace livo_bridge {

namespace {
using Clock = std::chrono::steady_clock;
}

Reporter::Reporter(const BridgeOptions& opt, std::vector<SensorInput*> inputs, EstimatorOutputs& outputs,
                   RosSession& session, livo::LcmNode& lcm, BridgeLog& log)
    : opt_(opt), inputs_(std::move(inputs)), outputs_(outputs), session_(session), lcm_(lcm), log_(log) {
  next_report_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(opt.stats_s));
  next_status_ = Clock::now();
}

std::string Reporter::streams(std::uint64_t& problems) {
  session_.collectQueueDrops();
  std::ostringstream os;
  problems = 0;
  for (SensorInput* in : inputs_) {
    if (in->wanted() == "none") continue;
    const StreamStats s = in->stats();
    const std::string topic = in->topic();
    os << "  " << livo::roleName(in->role()) << " " << (topic.empty() ? "(no topic yet)" : topic) << " -> "
       << in->channel() << ": " << s.describe() << "\n";
    if (!in->unitNote().empty()) os << "    imu: " << in->unitNote() << "\n";
    problems += s.rejected + s.dropped;
  }
  const auto& lcm_counters = lcm_.counters();
  for (auto [channel, s] : outputs_.stats()) {
    const auto it = lcm_counters.find(channel);
    if (it != lcm_counters.end()) {  // the LCM side's validation rejects
      s.rejected += it->second.rejected;
      s.bytes = it->second.bytes;
      if (s.last_error.empty()) s.last_error = it->second.last_error;
    }
    os << "  " << channel << " -> ROS: " << s.describe() << "\n";
    problems += s.rejected + s.dropped;
  }
  return os.str();
}

void Reporter::poll() {
  const auto now = Clock::now();
  if (now >= next_status_) {
    next_status_ = now + std::chrono::seconds(1);
    session_.collectQueueDrops();
    std::vector<std::pair<std::string, std::string>> values;
    std::uint64_t problems = 0;
    for (SensorInput* in : inputs_) {
      if (in->wanted() == "none") continue;
      const StreamStats s = in->stats();
      char buf[160];
      std::snprintf(buf, sizeof buf, "%llu in, %llu rejected, %llu dropped, latency p99 %.2f ms",
                    static_cast<unsigned long long>(s.received), static_cast<unsigned long long>(s.rejected),
                    static_cast<unsigned long long>(s.dropped), 1e3 * s.latency.quantile(0.99));
      values.push_back({in->channel() + " (" + (in->topic().empty() ? "no topic" : in->topic()) + ")", buf});
      problems += s.rejected + s.dropped;
    }
    const RosSession::Stats ss = session_.stats();
    values.push_back({"ros master losses", std::to_string(ss.master_losses)});
    values.push_back({"topic problems", std::to_string(ss.topic_problems)});
    outputs_.setBridgeStatus(std::move(values), problems > last_problems_);
    last_problems_ = problems;
  }
  if (opt_.stats_s > 0 && now >= next_report_) {
    next_report_ = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(opt_.stats_s));
    std::uint64_t problems = 0;
    const std::string lines = streams(problems);
    const RosSession::Stats ss = session_.stats();
    char head[200];
    std::snprintf(head, sizeof head, "stats: CPU %.1f %% of one core since the last report (%.1f %% since start); "
                  "ROS master %s, %llu losses",
                  cpu_.percentSinceLast(), cpu_.percentTotal(), ss.master_up ? "up" : "down",
                  static_cast<unsigned long long>(ss.master_losses));
    log_.line(std::string(head) + "\n" + lines.substr(0, lines.empty() ? 0 : lines.size() - 1));
  }
}

std::string Reporter::summary() {
  std::uint64_t problems = 0;
  const std::string lines = streams(problems);
  const RosSession::Stats ss = session_.stats();
  char head[240];
  std::snprintf(head, sizeof head,
                "livo-ros-bridge: CPU %.1f %% of one core; ROS master losses %llu, registrations %llu, topic "
                "problems %llu\n",
                cpu_.percentTotal(), static_cast<unsigned long long>(ss.master_losses),
                static_cast<unsigned long long>(ss.registrations), static_cast<unsigned long long>(ss.topic_problems));
  return head + lines;
}

}  // namespace livo_bridge
