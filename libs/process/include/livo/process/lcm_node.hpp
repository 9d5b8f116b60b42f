// A small typed layer over lcm::LCM for the processes: subscriptions that validate before they convert
// (decode() checks every declared count against the bytes and MessageLimits, then fromMsg() checks the
// values), per-channel counters of received and rejected messages, rate-limited warnings, and an event
// loop that ends on SIGINT/SIGTERM or after an idle time. Handlers see message time only (the receive
// time of LCM is never passed on).
//
// Tests use "memq://": publish() queues, drain() delivers. dispatch() feeds raw bytes to the handlers
// of a channel without any transport (log replay, benchmarks).
#pragma once

#include "livo/io/convert.hpp"

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace livo {

struct ChannelCounters {
  std::uint64_t received = 0;  ///< messages handed to this node (network or dispatch())
  std::uint64_t rejected = 0;  ///< failed decode / validation / handler
  std::uint64_t bytes = 0;
  std::string last_error;
};

/// Rate limit for repeated warnings: the 1st..5th, then the 10th, 100th, 1000th ... occurrence.
bool shouldWarn(std::uint64_t occurrence);

namespace detail {
template <class Msg, class T, class = void>
struct FromMsgTakesLimits : std::false_type {};
template <class Msg, class T>
struct FromMsgTakesLimits<Msg, T,
                          std::void_t<decltype(fromMsg(std::declval<const Msg&>(), std::declval<T&>(),
                                                       std::declval<const MessageLimits&>()))>> : std::true_type {};
}  // namespace detail

/// fromMsg() with the limits where the conversion takes them.
template <class Msg, class T>
Validation convertMessage(const Msg& m, T& out, const MessageLimits& lim) {
  if constexpr (detail::FromMsgTakesLimits<Msg, T>::value) return fromMsg(m, out, lim);
  else return fromMsg(m, out);
}

class LcmNode {
 public:
  /// Opens `url` (use resolveLcmUrl() for the flag). `name` prefixes warnings on `*log` (may be null).
  /// Throws std::runtime_error naming the URL when LCM cannot open it.
  LcmNode(const std::string& url, std::string name, std::ostream* log);
  ~LcmNode();
  LcmNode(const LcmNode&) = delete;
  LcmNode& operator=(const LcmNode&) = delete;

  /// Raw handler: returns a failed Validation to count the message as rejected.
  using RawHandler = std::function<Validation(const void* data, std::size_t size)>;
  void subscribeRaw(const std::string& channel, RawHandler handler);

  /// decode() (precheck + generated decode) then `handler(msg)`; a failure of either is a reject.
  template <class Msg>
  void subscribe(const std::string& channel, std::function<Validation(const Msg&)> handler) {
    subscribeRaw(channel, [this, h = std::move(handler)](const void* data, std::size_t size) {
      Msg m;
      Validation v = decode(data, size, m, limits_);
      return v ? h(m) : v;
    });
  }
  /// decode() + fromMsg() into T, then `cb(value)` for valid messages.
  template <class Msg, class T>
  void subscribeStruct(const std::string& channel, std::function<void(T&)> cb) {
    subscribe<Msg>(channel, [this, cb = std::move(cb)](const Msg& m) {
      T value;
      Validation v = convertMessage(m, value, limits_);
      if (v) cb(value);
      return v;
    });
  }

  /// Encodes and publishes. Throws std::runtime_error naming the channel when LCM refuses it.
  template <class Msg>
  void publish(const std::string& channel, const Msg& m) {
    const std::vector<std::uint8_t> buf = encode(m);
    publishRaw(channel, buf.data(), buf.size());
  }
  void publishRaw(const std::string& channel, const void* data, std::size_t size);

  /// Hands `data` to the handlers of `channel` as if received (no transport). False when none.
  bool dispatch(const std::string& channel, const void* data, std::size_t size);
  /// Handles every message already queued, without waiting; returns how many.
  int drain();
  /// Drain on stop: handles the messages already received, without waiting for more, for at most
  /// `max_s` seconds (a sender that keeps publishing cannot hold the exit); returns how many.
  int drainOnStop(double max_s = 2.0);
  /// Waits up to `timeout_ms` for one message and handles it; false on timeout or interruption.
  /// Throws std::runtime_error when LCM reports an error (other than an interrupting signal).
  bool handleOnce(int timeout_ms);

  enum class SpinEnd { kStopSignal, kIdle };
  /// Handles messages until stopRequested() (SIGINT/SIGTERM) or, when idle_exit_s > 0, until no
  /// message arrived for idle_exit_s seconds (wall clock: how long to wait for traffic, never used as
  /// a message time). `poll` (optional) runs after each handled message and on every 100 ms timeout.
  SpinEnd spin(double idle_exit_s, const std::function<void()>& poll = {});

  const std::map<std::string, ChannelCounters>& counters() const { return counters_; }
  std::uint64_t totalRejected() const;
  std::uint64_t totalReceived() const;
  /// "LIVO_IMU 2000 received, 0 rejected" lines, one per subscribed channel.
  std::string countersSummary() const;

  const MessageLimits& limits() const { return limits_; }
  void setLimits(const MessageLimits& lim) { limits_ = lim; }
  std::ostream* log() const { return log_; }
  const std::string& name() const { return name_; }
  const std::string& url() const { return url_; }
  lcm::LCM& lcm() { return *lcm_; }

 private:
  struct Route;
  void deliver(Route& r, const void* data, std::size_t size);

  std::string url_, name_;
  std::ostream* log_;
  MessageLimits limits_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::vector<std::unique_ptr<Route>> routes_;
  std::map<std::string, ChannelCounters> counters_;
};

}  // namespace livo
