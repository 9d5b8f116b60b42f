// The world of the livo-ros-bridge tests: a private network namespace this process joins, roscore, the
// test's own ROS node and LCM recorder, bridge processes and a ROS listener. Included by test_rosbridge.cpp
// and test_rosbridge_rates.cpp inside their `#if` on the ROS client libraries.
#pragma once

#include "process_test_children.hpp"
#include "process_test_files.hpp"
#include "rosbridge_test_bag.hpp"
#include "test_skip.hpp"

#include <gtest/gtest.h>

#include "livo/eval/evaluate.hpp"
#include "livo/eval/tum.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/io/map_messages.hpp"

#include <diagnostic_msgs/DiagnosticArray.h>
#include <lcm/lcm-cpp.hpp>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <Eigen/Geometry>

#include <fcntl.h>
#include <sched.h>

#include <atomic>
#include <csignal>
#include <mutex>
#include <thread>

namespace livo_rosbridge_test {

using namespace livo;
using namespace livo::test;

const char* kMaster = "http://127.0.0.1:11311";

/// Every LCM message on the bus, per channel, in arrival order (a thread handles LCM).
class LcmRecorder {
 public:
  LcmRecorder() : lcm_(kUrl) {
    lcm_.subscribe(".*", &LcmRecorder::onMessage, this)->setQueueCapacity(100000);  // not LCM's 30: nothing lost here
    thread_ = std::thread([this] {
      while (running_) lcm_.handleTimeout(50);
    });
  }
  ~LcmRecorder() {
    running_ = false;
    thread_.join();
  }
  std::size_t count(const std::string& channel) const {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = got_.find(channel);
    return it == got_.end() ? 0 : it->second.size();
  }
  std::vector<std::vector<std::uint8_t>> messages(const std::string& channel) const {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = got_.find(channel);
    return it == got_.end() ? std::vector<std::vector<std::uint8_t>>{} : it->second;
  }
  template <class Msg>
  void publish(const std::string& channel, const Msg& m) {
    lcm_.publish(channel, &m);
  }

 private:
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const auto* p = static_cast<const std::uint8_t*>(rbuf->data);
    std::lock_guard<std::mutex> lock(mu_);
    got_[channel].emplace_back(p, p + rbuf->data_size);
  }
  lcm::LCM lcm_;
  mutable std::mutex mu_;
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> got_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

/// The events of an LCM log per channel.
std::map<std::string, std::vector<std::vector<std::uint8_t>>> logByChannel(const std::string& path) {
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> out;
  LogReader reader(path);
  LogEvent ev;
  while (reader.next(ev)) out[ev.channel].push_back(ev.data);
  return out;
}

Utime utimeOf(const std::vector<std::uint8_t>& m) {  // every livo message starts with utime (big-endian)
  if (m.size() < 16) return -1;
  std::int64_t t = 0;
  for (int i = 8; i < 16; ++i) t = t << 8 | m[i];
  return t;
}

/// The namespace, roscore, the test's own ROS node and LCM recorder: shared by the tests in order.
struct World {
  std::unique_ptr<Netns> ns;
  std::string dir, why;
  std::unique_ptr<Child> roscore;
  std::unique_ptr<LcmRecorder> lcm;
  int roscores = 0;
  bool ok = false;

  World() = default;
  World(World&&) = default;

  bool startRoscore() {
    roscore = std::make_unique<Child>(std::vector<std::string>{"roscore", "-p", "11311"},
                                      dir + "/roscore" + std::to_string(++roscores) + ".txt");
    return waitUntil([] { return ros::master::check(); }, 30);
  }
  void stopRoscore() {
    roscore->signal(SIGINT);
    EXPECT_EQ(roscore->wait(30), 0) << readFile(dir + "/roscore" + std::to_string(roscores) + ".txt");
  }
  // At exit: roscore stops its rosmaster and rosout on SIGINT (a kill would orphan them; Child's
  // destructor kills its whole process group as the last resort).
  ~World() {
    if (roscore && roscore->pid > 0) {
      roscore->signal(SIGINT);
      roscore->wait(30);
    }
  }
};

World& world() {
  static World w = [] {
    World w;
    w.ns = std::make_unique<Netns>();
    if (!w.ns->ok) {
      w.why = w.ns->why;
      return w;
    }
    for (const char* tool : {"roscore", "rosbag", "rostopic"})
      if (!haveTool(tool)) {
        w.why = std::string(tool) + " missing (Debian packages python3-roslaunch, python3-rosbag, python3-rostopic)";
        return w;
      }
    // Join the namespace: this process's sockets (LCM, roscpp) and its children live there.
    const int fd = ::open(("/var/run/netns/" + w.ns->name).c_str(), O_RDONLY);
    if (fd < 0 || ::setns(fd, CLONE_NEWNET) != 0) {
      w.why = "cannot join the network namespace " + w.ns->name;
      return w;
    }
    ::close(fd);
    w.dir = tempDir("rosbridge");
    ::setenv("ROS_MASTER_URI", kMaster, 1);
    ::setenv("ROS_IP", "127.0.0.1", 1);  // the namespace has only its loopback device
    ::setenv("ROS_HOME", w.dir.c_str(), 1);
    ros::M_string remap;
    ros::init(remap, "livo_test_listener", ros::init_options::NoSigintHandler | ros::init_options::NoRosout);
    if (!w.startRoscore()) {
      w.why = "roscore did not start: " + readFile(w.dir + "/roscore1.txt");
      return w;
    }
    ros::start();
    w.lcm = std::make_unique<LcmRecorder>();
    w.ok = true;
    return w;
  }();
  return w;
}

std::string writeConfig(const std::string& path, const std::string& prefix) {
  std::ofstream(path) << "channels:\n  imu: " << prefix << "IMU\n  lidar: " << prefix << "LIDAR\n  camera: " << prefix
                      << "CAMERA\n  odometry: " << prefix << "ODOMETRY\n  registered_scan: " << prefix
                      << "REGISTERED_SCAN\n  estimator_stats: " << prefix << "ESTIMATOR_STATS\n  map_stats: " << prefix
                      << "MAP_STATS\n";
  return path;
}

/// One bridge process and its log.
struct Bridge {
  std::string log;
  std::unique_ptr<Child> child;
  Bridge(const std::string& dir, const std::string& name, const std::string& channel_prefix,
         std::vector<std::string> args) {
    log = dir + "/" + name + ".txt";
    std::vector<std::string> argv{kBin + "/livo-ros-bridge", "--config",
                                  writeConfig(dir + "/" + name + ".yaml", channel_prefix), "--lcm-url", kUrl,
                                  "--node-name", name, "--stats", "2"};
    argv.insert(argv.end(), args.begin(), args.end());
    child = std::make_unique<Child>(argv, log);
  }
  bool says(const std::string& text, double deadline_s = 30) const {
    return waitUntil([&] { return readFile(log).find(text) != std::string::npos; }, deadline_s);
  }
  std::size_t times(const std::string& text) const {
    const std::string s = readFile(log);
    std::size_t n = 0;
    for (auto p = s.find(text); p != std::string::npos; p = s.find(text, p + 1)) ++n;
    return n;
  }
  /// SIGINT, then the exit code; the log (with the summary) goes to the test output.
  int stop() {
    child->signal(SIGINT);
    const int rc = child->wait(30);
    std::cout << "---- " << log << "\n" << readFile(log);
    return rc;
  }
};

/// What the test's ROS node received (callbacks on the global queue, spun by an AsyncSpinner).
struct RosListener {
  std::mutex mu;
  std::vector<nav_msgs::Odometry> odometry;
  std::vector<tf2_msgs::TFMessage> tf;
  std::vector<sensor_msgs::PointCloud2> scans, maps;
  std::vector<diagnostic_msgs::DiagnosticArray> diagnostics;
  ros::NodeHandle nh;
  std::vector<ros::Subscriber> subs;
  ros::AsyncSpinner spinner{1};

  template <class M>
  void listen(const std::string& topic, std::vector<M>& into) {
    subs.push_back(nh.subscribe<M>(topic, 100, [this, &into](const boost::shared_ptr<const M>& m) {
      std::lock_guard<std::mutex> lock(mu);
      into.push_back(*m);
    }));
  }
  void subscribeAll() {
    for (auto& s : subs) s.shutdown();
    subs.clear();
    listen("/livo/odometry", odometry);
    listen("/tf", tf);
    listen("/livo/registered_scan", scans);
    listen("/livo/map", maps);
    listen("/diagnostics", diagnostics);
  }
  RosListener() {
    subscribeAll();
    spinner.start();
  }
  bool connected() {
    for (auto& s : subs)
      if (s.getNumPublishers() == 0) return false;
    return true;
  }
  template <class M>
  std::size_t size(const std::vector<M>& v) {
    std::lock_guard<std::mutex> lock(mu);
    return v.size();
  }
};

livo::odometry_t testOdometry(Utime t) {
  livo::odometry_t o{};
  o.utime = t;
  const double p[3] = {1.5, -2.25, 0.375}, v[3] = {0.5, 0.25, -0.125};
  const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  const double qa[4] = {q.x(), q.y(), q.z(), q.w()};
  for (int i = 0; i < 3; ++i) o.position[i] = p[i], o.velocity[i] = v[i], o.gravity[i] = i == 2 ? -9.81 : 0;
  for (int i = 0; i < 4; ++i) o.orientation[i] = qa[i];
  o.inv_exposure = 1.0;
  Eigen::Matrix<double, 6, 6> a;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) a(i, j) = 0.01 * std::sin(1.0 + i * 7 + j * 3);
  const Eigen::Matrix<double, 6, 6> c = a * a.transpose() + 1e-4 * Eigen::Matrix<double, 6, 6>::Identity();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) o.covariance[i][j] = c(i, j);
  o.status = 4;  // visual update
  return o;
}

}  // namespace livo_rosbridge_test
