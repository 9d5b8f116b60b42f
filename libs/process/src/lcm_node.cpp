#include "livo/process/lcm_node.hpp"

#include "livo/common/timing.hpp"
#include "livo/process/stop_signal.hpp"

#include <cerrno>
#include <sstream>
#include <stdexcept>

namespace livo {

namespace {

/// LCM treats subscription channels as POSIX regular expressions: escape everything special.
std::string regexEscape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (std::string(".[]{}()\\*+?|^$").find(c) != std::string::npos) o += '\\';
    o += c;
  }
  return o;
}

}  // namespace

bool shouldWarn(std::uint64_t n) {
  if (n == 0) return false;
  if (n <= 5) return true;
  while (n % 10 == 0) n /= 10;
  return n == 1;
}

struct LcmNode::Route {
  LcmNode* node = nullptr;
  std::string channel;
  RawHandler handler;
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    node->deliver(*this, rbuf->data, rbuf->data_size);
  }
};

LcmNode::LcmNode(const std::string& url, std::string name, std::ostream* log)
    : url_(url), name_(std::move(name)), log_(log), lcm_(std::make_unique<lcm::LCM>(url)) {
  if (!lcm_->good())
    throw std::runtime_error("cannot open LCM URL '" + url +
                             "' (malformed URL, or no multicast route: see README, 'Running the processes')");
}

LcmNode::~LcmNode() = default;

void LcmNode::subscribeRaw(const std::string& channel, RawHandler handler) {
  if (channel.empty()) throw std::invalid_argument("LcmNode::subscribeRaw: empty channel name");
  auto r = std::make_unique<Route>();
  r->node = this;
  r->channel = channel;
  r->handler = std::move(handler);
  if (!lcm_->subscribe(regexEscape(channel), &Route::onMessage, r.get()))
    throw std::runtime_error("LCM subscription to " + channel + " failed");
  counters_[channel];
  routes_.push_back(std::move(r));
}

void LcmNode::deliver(Route& r, const void* data, std::size_t size) {
  ChannelCounters& c = counters_[r.channel];
  ++c.received;
  c.bytes += size;
  Validation v;
  try {
    v = r.handler(data, size);
  } catch (const std::exception& e) {
    v = Validation::fail(std::string("handler failed: ") + e.what());
  }
  if (v) return;
  ++c.rejected;
  c.last_error = v.error;
  if (log_ && shouldWarn(c.rejected))
    *log_ << name_ << ": " << r.channel << ": rejected message (" << c.rejected << " so far): " << v.error << "\n";
}

void LcmNode::publishRaw(const std::string& channel, const void* data, std::size_t size) {
  if (size > static_cast<std::size_t>(limits_.max_message_bytes))
    throw std::runtime_error(channel + ": message of " + std::to_string(size) + " bytes exceeds max_message_bytes");
  if (lcm_->publish(channel, data, static_cast<unsigned int>(size)) != 0)
    throw std::runtime_error(channel + ": LCM publish failed (" + std::to_string(size) + " bytes)");
}

bool LcmNode::dispatch(const std::string& channel, const void* data, std::size_t size) {
  bool any = false;
  for (auto& r : routes_)
    if (r->channel == channel) {
      deliver(*r, data, size);
      any = true;
    }
  return any;
}

int LcmNode::drain() {
  int n = 0;
  while (handleOnce(0)) ++n;
  return n;
}

int LcmNode::drainOnStop(double max_s) {
  Stopwatch watch;
  int n = 0;
  while (watch.elapsedMs() < 1000.0 * max_s && handleOnce(0)) ++n;
  return n;
}

bool LcmNode::handleOnce(int timeout_ms) {
  errno = 0;
  const int r = lcm_->handleTimeout(timeout_ms);
  if (r > 0) return true;
  if (r == 0) return false;
  if (errno == EINTR || stopRequested()) return false;
  throw std::runtime_error("LCM receive failed on " + url_);
}

LcmNode::SpinEnd LcmNode::spin(double idle_exit_s, const std::function<void()>& poll) {
  Stopwatch idle;
  while (!stopRequested()) {
    const std::uint64_t before = totalReceived();
    handleOnce(100);
    if (poll) poll();
    // Messages handled inside poll() count too (the estimator handles frames and answers while it
    // waits for the map server): a process busy for longer than idle_exit_s is not idle.
    if (totalReceived() != before) idle.restart();
    if (idle_exit_s > 0 && idle.elapsedMs() > 1000.0 * idle_exit_s) return SpinEnd::kIdle;
  }
  return SpinEnd::kStopSignal;
}

std::uint64_t LcmNode::totalRejected() const {
  std::uint64_t n = 0;
  for (const auto& [k, c] : counters_) n += c.rejected;
  return n;
}

std::uint64_t LcmNode::totalReceived() const {
  std::uint64_t n = 0;
  for (const auto& [k, c] : counters_) n += c.received;
  return n;
}

std::string LcmNode::countersSummary() const {
  std::ostringstream os;
  for (const auto& [ch, c] : counters_) {
    os << "  " << ch << ": " << c.received << " received, " << c.rejected << " rejected";
    if (!c.last_error.empty()) os << " (last: " << c.last_error << ")";
    os << "\n";
  }
  return os.str();
}

}  // namespace livo
