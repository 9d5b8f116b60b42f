// livo-ros-bridge in a private network namespace (this test process joins it, so its own LCM and ROS
// sockets stay there too): roscore, three bridges and `rosbag play` of a bag written here with every
// message type and PointCloud2 layout (rosbridge_test_bag.hpp). Every LCM message the bridges publish must
// be, byte for byte, what `livo-convert rosbag` writes for the same bag and topics; the truncated cloud is
// rejected and counted, a topic of the wrong type is counted and never fatal. Then LCM -> ROS (odometry
// with its covariance, tf, registered scan, map, diagnostics), and a ROS master that goes away and comes
// back. Skips (visibly; a failure under CI=true) without root, the ROS client libraries or the ROS tools.
// livo-test-whole
// Not run by ctest (disabled): the demo's sensor rates through the bridge and the four processes,
//   build/bin/test_rosbridge --gtest_also_run_disabled_tests --gtest_filter=*DemoRates*
// livo-test-bins: livo-ros-bridge livo-convert livo-sim livo-preprocess livo-estimator livo-mapserver livo-exporter
// livo-test-deps: livo_datasets livo_io livo_eval livo_rosbag_storage livo_ros_client opencv_core opencv_imgcodecs
#include "process_test_children.hpp"
#include "process_test_files.hpp"
#include "rosbridge_test_bag.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#if !LIVO_TEST_ROSBAG || !defined(LIVO_HAVE_ROS_CLIENT)

TEST(RosBridge, NeedsTheRosClientLibraries) {
  LIVO_SKIP() << "built without the ROS 1 client libraries (libroscpp-dev, libnav-msgs-dev, libtf2-msgs-dev, "
                 "libdiagnostic-msgs-dev, librosbag-storage-dev): livo-ros-bridge and its test are skipped";
}

#else

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

using namespace livo;
using namespace livo::test;

namespace {

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

}  // namespace

// 1. ROS -> LCM: every message of the bag arrives as livo-convert writes it.
TEST(RosBridge, BagMessagesArriveAsLivoConvertWritesThem) {
  World& w = world();
  if (!w.ok) LIVO_SKIP() << w.why;
  const std::string bag = w.dir + "/all.bag";
  const BridgeBag n = writeBridgeBag(bag);

  // The reference: livo-convert on the same bag and topics.
  struct Run {
    std::string name, prefix;
    std::vector<std::string> topics, convert_extra;
  };
  const std::vector<Run> runs = {
      {"bridge_a", "LIVO_", {"--lidar-topic", "/points", "--imu-topic", "/imu", "--image-topic", "/cam/image_raw"}, {"--skip-bad"}},
      {"bridge_b", "B_", {"--lidar-topic", "/livox/lidar", "--imu-topic", "none", "--image-topic", "/cam/compressed"}, {}},
      {"bridge_c", "C_", {"--lidar-topic", "/livox2/lidar", "--imu-topic", "none", "--image-topic", "none"}, {}}};
  std::map<std::string, std::vector<std::vector<std::uint8_t>>> want;
  for (const Run& r : runs) {
    std::string cmd = kBin + "/livo-convert rosbag " + bag + " --out " + w.dir + "/" + r.name + ".lcm --quiet";
    for (const auto& a : r.topics) cmd += " " + a;
    for (const auto& a : r.convert_extra) cmd += " " + a;
    for (const char* role : {"LIDAR", "CAMERA", "IMU"})
      cmd += std::string(" --") + (std::string(role) == "LIDAR" ? "lidar" : std::string(role) == "IMU" ? "imu" : "camera") +
             "-channel " + r.prefix + role;
    ASSERT_EQ(std::system((cmd + " > " + w.dir + "/" + r.name + "_convert.txt 2>&1").c_str()), 0)
        << readFile(w.dir + "/" + r.name + "_convert.txt");
    for (auto& [ch, msgs] : logByChannel(w.dir + "/" + r.name + ".lcm")) want[ch] = msgs;
  }
  ASSERT_EQ(want["LIVO_IMU"].size(), static_cast<std::size_t>(n.imu));
  ASSERT_EQ(want["LIVO_LIDAR"].size(), static_cast<std::size_t>(n.points));
  ASSERT_EQ(want["LIVO_CAMERA"].size(), static_cast<std::size_t>(n.images));
  ASSERT_EQ(want["B_LIDAR"].size(), static_cast<std::size_t>(n.livox));
  ASSERT_EQ(want["B_CAMERA"].size(), static_cast<std::size_t>(n.compressed));
  ASSERT_EQ(want["C_LIDAR"].size(), static_cast<std::size_t>(n.livox2));

  // A topic of a type no role reads, named as bridge C's IMU: counted and warned about, never fatal.
  Child chatter({"rostopic", "pub", "-r", "5", "/chatter", "std_msgs/String", "data: hi"}, w.dir + "/chatter.txt");
  ASSERT_TRUE(waitUntil(
      [] {
        ros::master::V_TopicInfo t;
        ros::master::getTopics(t);
        return std::any_of(t.begin(), t.end(), [](const auto& i) { return i.name == "/chatter"; });
      },
      30))
      << readFile(w.dir + "/chatter.txt");

  std::vector<std::unique_ptr<Bridge>> bridges;
  for (const Run& r : runs) {
    std::vector<std::string> args = r.topics;
    if (r.name == "bridge_c") args[3] = "/chatter";
    if (r.name != "bridge_a") args.insert(args.end(), {"--topic-prefix", "/" + r.name});
    bridges.push_back(std::make_unique<Bridge>(w.dir, r.name, r.prefix, args));
  }
  for (auto& b : bridges) ASSERT_TRUE(b->says("registered with the ROS master")) << readFile(b->log);
  EXPECT_TRUE(bridges[2]->says("topic /chatter has type std_msgs/String, which is not an IMU type")) << readFile(bridges[2]->log);

  // Plays once every topic has a subscriber (the bridges subscribe when the topics appear).
  Child play({"rosbag", "play", "--wait-for-subscribers", "-q", "-r", "4", bag}, w.dir + "/play1.txt");
  EXPECT_EQ(play.wait(60), 0) << readFile(w.dir + "/play1.txt");
  EXPECT_TRUE(waitUntil(
      [&] {
        for (const auto& [ch, msgs] : want)
          if (w.lcm->count(ch) < msgs.size()) return false;
        return true;
      },
      30));
  for (const auto& [ch, msgs] : want) {
    SCOPED_TRACE(ch);
    const auto got = w.lcm->messages(ch);
    ASSERT_EQ(got.size(), msgs.size());
    for (std::size_t i = 0; i < msgs.size(); ++i)
      EXPECT_TRUE(got[i] == msgs[i]) << "message " << i << ": utime " << utimeOf(got[i]) << " vs " << utimeOf(msgs[i])
                                     << ", " << got[i].size() << " vs " << msgs[i].size() << " bytes";
    std::cout << ch << ": " << got.size() << " messages, identical to livo-convert rosbag\n";
  }
  // The truncated cloud was rejected, the empty one skipped; bridge C counted the wrong-type topic.
  EXPECT_TRUE(bridges[0]->says("LiDAR /points: message rejected: sensor_msgs/PointCloud2.data: declares"))
      << readFile(bridges[0]->log);
  for (auto& b : bridges) EXPECT_EQ(b->stop(), 0);
  EXPECT_NE(readFile(bridges[0]->log).find("LiDAR /points -> LIVO_LIDAR: 10 in, 8 out, 1 rejected, 1 skipped, 0 dropped"),
            std::string::npos);
  EXPECT_NE(readFile(bridges[0]->log).find("IMU /imu -> LIVO_IMU: 400 in, 400 out, 0 rejected, 0 skipped, 0 dropped (200 held for the IMU unit decision"),
            std::string::npos);
  EXPECT_NE(readFile(bridges[2]->log).find("topic problems 1"), std::string::npos);
  chatter.signal(SIGINT);
  chatter.wait(10);
}

// 2. LCM -> ROS: odometry (pose, covariance in ROS's convention), tf, registered scan, map, diagnostics.
TEST(RosBridge, EstimatorOutputsArriveOnRos) {
  World& w = world();
  if (!w.ok) LIVO_SKIP() << w.why;
  Bridge bridge(w.dir, "bridge_out", "LIVO_", {"--lidar-topic", "none", "--imu-topic", "none", "--image-topic", "none"});
  ASSERT_TRUE(bridge.says("registered with the ROS master")) << readFile(bridge.log);
  RosListener ros_in;
  ASSERT_TRUE(waitUntil([&] { return ros_in.connected(); }, 30)) << readFile(bridge.log);

  const Utime t0 = 1'650'000'000'000'000;
  livo::odometry_t odo = testOdometry(t0);
  livo::registered_scan_t scan{};
  scan.utime = t0;
  scan.num_points = 5;
  for (int i = 0; i < 5; ++i) {
    scan.x.push_back(1.0f + i), scan.y.push_back(-0.5f * i), scan.z.push_back(0.25f);
    scan.intensity.push_back(10.0f * i);
    scan.rgb.push_back(i == 2 ? -1 : 0x102030 * (i + 1));
  }
  scan.num_colors = 5;
  livo::estimator_stats_t st{};
  st.utime = t0;
  st.frame_index = 42;
  st.total_ms = 12.5f;
  st.sigma_min = 0.3f;
  livo::map_stats_t ms{};
  ms.utime = t0;
  ms.local_voxels = 77;
  // Sent until everything arrived (a multicast datagram can be lost); each round one second of message
  // time later, so that every round also publishes a map.
  auto has_stats = [&] {
    for (const auto& a : ros_in.diagnostics)
      for (const auto& s : a.status)
        if (s.name == "livo: estimator")
          for (const auto& kv : s.values)
            if (kv.key == "frame_index" && kv.value == "42") return true;
    return false;
  };
  Utime t = t0;
  ASSERT_TRUE(waitUntil(
      [&] {
        odo.utime = scan.utime = st.utime = ms.utime = t;
        t += 1'000'000;
        w.lcm->publish("LIVO_ODOMETRY", odo);
        w.lcm->publish("LIVO_REGISTERED_SCAN", scan);
        w.lcm->publish("LIVO_ESTIMATOR_STATS", st);
        w.lcm->publish("LIVO_MAP_STATS", ms);
        sleepS(0.1);
        std::lock_guard<std::mutex> lock(ros_in.mu);
        return !ros_in.odometry.empty() && !ros_in.tf.empty() && !ros_in.scans.empty() && !ros_in.maps.empty() &&
               has_stats();
      },
      30))
      << readFile(bridge.log);
  nav_msgs::Odometry r;
  tf2_msgs::TFMessage tf_msg;
  sensor_msgs::PointCloud2 scan_msg, map_msg;
  std::size_t counts[5];
  {
    std::lock_guard<std::mutex> lock(ros_in.mu);  // copied out: the callbacks must not wait on it later
    r = ros_in.odometry.front();
    tf_msg = ros_in.tf.front();
    scan_msg = ros_in.scans.front();
    map_msg = ros_in.maps.front();
    counts[0] = ros_in.odometry.size(), counts[1] = ros_in.tf.size(), counts[2] = ros_in.scans.size();
    counts[3] = ros_in.maps.size(), counts[4] = ros_in.diagnostics.size();
  }

  // Pose: as sent; the quaternion up to its sign, through livo's rotation matrix.
  EXPECT_EQ(r.header.frame_id, "world");
  EXPECT_EQ(r.child_frame_id, "body");
  const std::uint64_t stamp_us = r.header.stamp.toNSec() / 1000;
  EXPECT_EQ(r.header.stamp.toNSec() % 1000, 0u);
  EXPECT_TRUE(stamp_us >= static_cast<std::uint64_t>(t0) && (stamp_us - t0) % 1'000'000 == 0) << stamp_us;
  EXPECT_EQ(r.pose.pose.position.x, odo.position[0]);
  EXPECT_EQ(r.pose.pose.position.y, odo.position[1]);
  EXPECT_EQ(r.pose.pose.position.z, odo.position[2]);
  const Eigen::Quaterniond q_sent(odo.orientation[3], odo.orientation[0], odo.orientation[1], odo.orientation[2]);
  const Eigen::Quaterniond q_ros(r.pose.pose.orientation.w, r.pose.pose.orientation.x, r.pose.pose.orientation.y,
                                 r.pose.pose.orientation.z);
  EXPECT_NEAR(std::abs(q_sent.dot(q_ros)), 1.0, 1e-12);
  // Covariance: livo's [rotation (body, right perturbation), position] as ROS's [position, rotation about
  // the world axes]: C_ros = J C J^T, J = [[0, I], [R, 0]].
  Eigen::Matrix<double, 6, 6> c, J = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) c(i, j) = odo.covariance[i][j];
  J.block<3, 3>(0, 3).setIdentity();
  J.block<3, 3>(3, 0) = q_sent.normalized().toRotationMatrix();
  const Eigen::Matrix<double, 6, 6> c_ros = J * c * J.transpose();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) EXPECT_NEAR(r.pose.covariance[6 * i + j], c_ros(i, j), 1e-15) << i << "," << j;
  // The same pose as tf.
  const auto& tf = tf_msg.transforms.at(0);
  EXPECT_EQ(tf.header.frame_id, "world");
  EXPECT_EQ(tf.child_frame_id, "body");
  EXPECT_EQ(tf.transform.translation.x, odo.position[0]);
  EXPECT_NEAR(std::abs(q_sent.dot(Eigen::Quaterniond(tf.transform.rotation.w, tf.transform.rotation.x,
                                                      tf.transform.rotation.y, tf.transform.rotation.z))),
              1.0, 1e-12);
  // Registered scan and map: x, y, z, intensity, rgb (white where no camera saw the point).
  for (const sensor_msgs::PointCloud2* cloud : {&scan_msg, &map_msg}) {
    ASSERT_EQ(cloud->width, 5u);
    ASSERT_EQ(cloud->fields.size(), 5u);
    EXPECT_EQ(cloud->fields[4].name, "rgb");
    for (std::uint32_t i = 0; i < 5; ++i) {
      float v[4];
      std::uint32_t rgb = 0;
      std::memcpy(v, &cloud->data[i * cloud->point_step], 16);
      std::memcpy(&rgb, &cloud->data[i * cloud->point_step + 16], 4);
      EXPECT_EQ(v[0], scan.x[i]);
      EXPECT_EQ(v[1], scan.y[i]);
      EXPECT_EQ(v[2], scan.z[i]);
      EXPECT_EQ(v[3], scan.intensity[i]);
      EXPECT_EQ(rgb, i == 2 ? 0xFFFFFFu : static_cast<std::uint32_t>(scan.rgb[i]));
    }
  }
  std::cout << "ROS side: " << counts[0] << " odometry, " << counts[1] << " tf, " << counts[2] << " scans, " << counts[3]
            << " maps, " << counts[4] << " diagnostics\n";
  ros_in.subs.clear();
  EXPECT_EQ(bridge.stop(), 0);
}

// 3. The ROS master goes away and comes back: the bridge keeps running, registers again, and messages
// flow both ways after it.
TEST(RosBridge, SurvivesARestartedMaster) {
  World& w = world();
  if (!w.ok) LIVO_SKIP() << w.why;
  const std::string bag = w.dir + "/imu.bag";
  writeImuBag(bag, 50, rosbag::compression::Uncompressed);
  // mps2: nothing held for the unit decision (50 samples only).
  Bridge bridge(w.dir, "bridge_restart", "R_", {"--imu-topic", "/imu", "--lidar-topic", "none", "--image-topic", "none",
                                                "--imu-accel-unit", "mps2"});
  ASSERT_TRUE(bridge.says("registered with the ROS master")) << readFile(bridge.log);
  w.stopRoscore();
  EXPECT_TRUE(bridge.says("went away")) << readFile(bridge.log);
  ASSERT_TRUE(w.startRoscore()) << readFile(w.dir + "/roscore2.txt");
  EXPECT_TRUE(bridge.says("is back: registering every topic again")) << readFile(bridge.log);

  // ROS -> LCM after the restart: the IMU topic (named, so waited for) is subscribed as it appears.
  Child play({"rosbag", "play", "--wait-for-subscribers", "-q", bag}, w.dir + "/play2.txt");
  EXPECT_EQ(play.wait(60), 0) << readFile(w.dir + "/play2.txt");
  EXPECT_TRUE(waitUntil([&] { return w.lcm->count("R_IMU") >= 50; }, 30)) << readFile(bridge.log);
  EXPECT_EQ(w.lcm->count("R_IMU"), 50u);

  // LCM -> ROS after the restart (the test's own node registers again too).
  RosListener ros_in;
  ASSERT_TRUE(waitUntil([&] { return ros_in.connected(); }, 30)) << readFile(bridge.log);
  ASSERT_TRUE(waitUntil(
      [&] {
        w.lcm->publish("R_ODOMETRY", testOdometry(1'650'000'000'000'000));
        sleepS(0.1);
        return ros_in.size(ros_in.odometry) > 0;
      },
      30));
  ros_in.subs.clear();
  EXPECT_EQ(bridge.stop(), 0);
  EXPECT_NE(readFile(bridge.log).find("ROS master losses 1, registrations 2"), std::string::npos);
}

// 4. Benchmark (disabled): the demo scenario as a ROS bag (Avia-like PointCloud2 at 10 Hz, IMU at 200 Hz,
// 640 x 512 mono8 images at 10 Hz) played at its rate into the bridge, the four processes behind it and
// the odometry back on ROS. Prints the bridge's added latency and CPU (its --stats lines), the poses on
// ROS and the exported trajectory's ATE.
namespace {

/// The simulator's LCM log as the bag a ROS driver set would record (stamps = sensor time; a scan is
/// recorded at its end, like a driver publishes it).
void lcmLogToBag(const std::string& log, const std::string& bag_path) {
  using F = sensor_msgs::PointField;
  const CloudSpec spec{"avia", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"intensity", F::FLOAT32, 12},
                                {"ring", F::UINT16, 16}, {"time", F::FLOAT32, 18}}, 22};
  rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
  LogReader reader(log);
  LogEvent ev;
  while (reader.next(ev)) {
    if (ev.channel == "LIVO_IMU") {
      livo::imu_t m;
      ImuSample s;
      ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m) && fromMsg(m, s));
      bag.write("/imu", rosTime(s.utime * 1000), imuMsg(s.utime * 1000, s.gyro, s.accel));
    } else if (ev.channel == "LIVO_LIDAR") {
      livo::lidar_scan_t m;
      LidarScan scan;
      ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m) && fromMsg(m, scan));
      std::vector<PointValues> pts;
      pts.reserve(scan.points.size());
      for (const LidarPoint& p : scan.points)
        pts.push_back({{"x", p.p_lidar.x()}, {"y", p.p_lidar.y()}, {"z", p.p_lidar.z()}, {"intensity", p.intensity},
                       {"ring", std::max<int>(p.ring, 0)}, {"time", p.time_offset_s}});
      bag.write("/livox/points", rosTime(scan.endUtime() * 1000), cloudMsg(spec, scan.utime * 1000, pts));
    } else if (ev.channel == "LIVO_CAMERA") {
      livo::image_t m;
      Image img;
      ASSERT_TRUE(decode(ev.data.data(), ev.data.size(), m) && fromMsg(m, img));
      sensor_msgs::Image r;
      r.header.stamp = rosTime(img.utime * 1000);
      r.height = img.height, r.width = img.width, r.encoding = "mono8", r.step = img.row_stride;
      r.data = img.data;
      bag.write("/camera/image", rosTime(img.utime * 1000), r);
    }
  }
}

}  // namespace

TEST(RosBridge, DISABLED_DemoRatesThroughTheSuite) {
  World& w = world();
  if (!w.ok) LIVO_SKIP() << w.why;
  const std::string d = w.dir + "/demo";
  std::filesystem::create_directories(d);
  ASSERT_EQ(std::system((kBin + "/livo-sim --quiet --scenario " + std::string(LIVO_SOURCE_DIR) + "/config/sim/demo.yaml --out " +
                         d + "/demo.lcm --gt " + d + "/gt.tum --rig " + d + "/rig.yaml > " + d + "/sim.txt 2>&1")
                            .c_str()),
            0)
      << readFile(d + "/sim.txt");
  lcmLogToBag(d + "/demo.lcm", d + "/demo.bag");
  const std::string rig = d + "/rig.yaml";
  auto proc = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> argv{kBin + "/livo-" + name, "--config", rig, "--lcm-url", kUrl};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return std::make_unique<Child>(argv, d + "/" + name + ".txt");
  };
  auto mapserver = proc("mapserver", {});
  auto estimator = proc("estimator", {"--idle-exit", "6"});
  auto exporter = proc("exporter", {"--out", d + "/export", "--idle-exit", "10"});
  auto preprocess = proc("preprocess", {"--idle-exit", "30"});
  Child bridge({kBin + "/livo-ros-bridge", "--config", rig, "--lcm-url", kUrl, "--stats", "5"}, d + "/bridge.txt");
  RosListener ros_in;
  ASSERT_TRUE(waitUntil([&] { return ros_in.connected(); }, 30)) << readFile(d + "/bridge.txt");
  Child play({"rosbag", "play", "--wait-for-subscribers", "-q", d + "/demo.bag"}, d + "/play.txt");
  EXPECT_EQ(play.wait(120), 0) << readFile(d + "/play.txt");
  EXPECT_EQ(preprocess->wait(120), 0);  // idle exits once the bag is over
  EXPECT_EQ(estimator->wait(60), 0);
  EXPECT_EQ(exporter->wait(60), 0);
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait(30), 0);
  mapserver->signal(SIGINT);
  EXPECT_EQ(mapserver->wait(30), 0);
  std::cout << readFile(d + "/bridge.txt");
  const Trajectory gt = readTum(d + "/gt.tum"), est = readTum(d + "/export/trajectory.tum");
  std::cout << "demo through the bridge: " << ros_in.size(ros_in.odometry) << " odometry messages on ROS, "
            << est.size() << " poses exported, ATE " << 100 * evaluate(gt, est, EvalConfig{}).ate.translation_m.rmse
            << " cm\n";
  ros_in.subs.clear();
}

#endif

