// The ROS side's life: master, registration, topic discovery (ros_session.hpp).
#include "ros_session.hpp"

#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <ros/xmlrpc_manager.h>
#include <xmlrpcpp/XmlRpcClient.h>
#include <xmlrpcpp/XmlRpcException.h>

#include <algorithm>
#include <chrono>

namespace livo_bridge {

namespace {

/// The master's PID, or -1 when it cannot be reached (never waits for it).
int masterPid() {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  if (!ros::master::execute("getPid", args, result, payload, false)) return -1;
  return payload.getType() == XmlRpc::XmlRpcValue::TypeInt ? static_cast<int>(payload) : 0;
}

}  // namespace

RosSession::RosSession(const BridgeOptions& opt, std::vector<SensorInput*> inputs, EstimatorOutputs& outputs,
                       BridgeLog& log)
    : opt_(opt), inputs_(std::move(inputs)), outputs_(outputs), log_(log) {}

RosSession::~RosSession() { stop(); }

void RosSession::start() {
  running_ = true;
  thread_ = std::thread([this] { run(); });
}

void RosSession::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

RosSession::Stats RosSession::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

void RosSession::run() {
  using Clock = std::chrono::steady_clock;
  while (running_) {
    const auto next = Clock::now() + std::chrono::duration<double>(opt_.master_poll_s);
    try {
      poll();
    } catch (const std::exception& e) {  // roscpp throws for bad names and registration failures
      log_.every(++waits_, std::string("ROS side: ") + e.what());
    }
    while (running_ && Clock::now() < next) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void RosSession::poll() {
  const int pid = masterPid();
  bool was_up = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    was_up = stats_.master_up;
    if (pid < 0 && was_up) {
      stats_.master_up = false;
      ++stats_.master_losses;
    }
  }
  if (pid < 0) {
    if (was_up)
      log_.line("the ROS master at " + ros::master::getURI() +
                " went away: connections already made keep running; waiting for it to come back");
    else if (!ever_up_)
      log_.every(++waits_, "waiting for the ROS master at " + ros::master::getURI());
    return;
  }
  if (!was_up || pid != master_pid_) {
    if (ever_up_)
      log_.line("ROS master at " + ros::master::getURI() + " (pid " + std::to_string(pid) +
                ") is back: registering every topic again");
    if (!nh_) {
      ros::start();
      nh_ = std::make_unique<ros::NodeHandle>();
    }
    registerAll();
    master_pid_ = pid;
    ever_up_ = true;
    std::lock_guard<std::mutex> lock(mu_);
    stats_.master_up = true;
    ++stats_.registrations;
  }
  discover();
}

void RosSession::registerAll() {
  for (SensorInput* in : inputs_) in->unsubscribe();
  outputs_.advertise(*nh_);
  log_.line("registered with the ROS master " + ros::master::getURI() + " as " + ros::this_node::getName() +
            ": publishing " + opt_.topic_prefix + "/odometry, /tf, " + opt_.topic_prefix + "/registered_scan, " +
            opt_.topic_prefix + "/map, /diagnostics");
}

void RosSession::discover() {
  std::vector<ros::master::TopicInfo> infos;
  if (!ros::master::getTopics(infos)) return;
  const std::vector<std::string> own = outputs_.topics();
  std::vector<livo::BagTopicInfo> topics;
  for (const auto& i : infos)
    if (std::find(own.begin(), own.end(), i.name) == own.end()) topics.push_back({i.name, i.datatype, "*", 0});
  std::sort(topics.begin(), topics.end(), [](const auto& a, const auto& b) { return a.topic < b.topic; });

  using Kind = livo::RosTopicChoice::Kind;
  for (SensorInput* in : inputs_) {
    if (in->wanted() == "none" || !in->topic().empty()) continue;
    const livo::RosTopicChoice c = livo::chooseRosTopic(topics, in->role(), in->wanted(), "ROS master");
    if (c.kind == Kind::kChosen) {
      const auto it = std::find_if(topics.begin(), topics.end(), [&](const auto& t) { return t.topic == c.topic; });
      if (!in->subscribe(*nh_, c.topic, it->datatype))
        log_.every(++problems_["subscribe " + c.topic], "could not subscribe " + c.topic + " (ROS master gone?)");
      continue;
    }
    // Warned at a limited rate per role and kind of problem (the text may change as topics come and go).
    const std::string role = livo::roleName(in->role());
    std::string problem = c.problem;
    if (c.kind == Kind::kNoCandidate)
      problem = "no " + role + " topic in the ROS graph yet (" + livo::roleFlag(in->role()) +
                " names one, none skips the role)";
    if (c.kind == Kind::kMissing)
      problem = "waiting for the " + role + " topic " + in->wanted() + " (" + livo::roleFlag(in->role()) +
                ") to appear in the ROS graph";
    const std::uint64_t n = ++problems_[role + "/" + std::to_string(static_cast<int>(c.kind))];
    if (n == 1 && (c.kind == Kind::kWrongType || c.kind == Kind::kAmbiguous)) {
      std::lock_guard<std::mutex> lock(mu_);
      ++stats_.topic_problems;
    }
    log_.every(n, problem);
  }
}

void RosSession::collectQueueDrops() {
  if (stats().registrations == 0) return;
  // roscpp counts the drops of each subscription's incoming queue, but only tells through the node's
  // XML-RPC API (getBusStats, as rosnode does): ask our own node.
  std::string host;
  std::uint32_t port = 0;
  if (!ros::network::splitURI(ros::XMLRPCManager::instance()->getServerURI(), host, port)) return;
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue args, result;
  args[0] = ros::this_node::getName();
  if (!client.execute("getBusStats", args, result)) return;
  std::map<std::string, std::uint64_t> by_topic;
  try {
    XmlRpc::XmlRpcValue& subs = result[2][1];  // [code, status, [publish, subscribe, service]]
    for (int i = 0; i < subs.size(); ++i) {
      const std::string topic = subs[i][0];
      XmlRpc::XmlRpcValue& conns = subs[i][1];
      for (int j = 0; j < conns.size(); ++j)
        drops_by_connection_[topic + "#" + std::to_string(static_cast<int>(conns[j][0]))] =
            static_cast<std::uint64_t>(static_cast<int>(conns[j][3]));
    }
  } catch (const XmlRpc::XmlRpcException&) {  // an unexpected layout: keep what was read before
  }
  for (const auto& [key, drops] : drops_by_connection_) by_topic[key.substr(0, key.rfind('#'))] += drops;
  for (SensorInput* in : inputs_) {
    const std::string t = in->topic();
    if (!t.empty()) in->setQueueDrops(by_topic[t]);
  }
}

}  // namespace livo_bridge
