// livo-ros-bridge in a private network namespace (this test process joins it, so its own LCM and ROS
// sockets stay there too): roscore, three bridges and `rosbag play` of a bag written here with every
// message type and PointCloud2 layout (rosbridge_test_bag.hpp). Every LCM message the bridges publish must
// be, byte for byte, what `livo-convert rosbag` writes for the same bag and topics; the truncated cloud is
// rejected and counted, a topic of the wrong type is counted and never fatal. Then LCM -> ROS (odometry
// with its covariance, tf, registered scan, map, diagnostics), and a ROS master that goes away and comes
// back. Skips (visibly; a failure under CI=true) without root, the ROS client libraries or the ROS tools.
// The demo's sensor rates through the bridge: test_rosbridge_rates.cpp.
// livo-test-whole
// livo-test-bins: livo-ros-bridge livo-convert
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

#include "rosbridge_test_world.hpp"

using namespace livo_rosbridge_test;

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

// 4. Drain on stop: IMU samples held for the acceleration-unit decision (fewer than the 200 it needs) are
// published when the bridge is stopped, and counted as out: 50 in, 50 on LCM, 50 out in the summary.
TEST(RosBridge, HeldImuSamplesArePublishedAndCountedOnStop) {
  World& w = world();
  if (!w.ok) LIVO_SKIP() << w.why;
  const std::string bag = w.dir + "/imu_held.bag";
  writeImuBag(bag, 50, rosbag::compression::Uncompressed);
  Bridge bridge(w.dir, "bridge_held", "H_", {"--imu-topic", "/imu", "--lidar-topic", "none", "--image-topic", "none"});
  ASSERT_TRUE(bridge.says("registered with the ROS master")) << readFile(bridge.log);
  Child play({"rosbag", "play", "--wait-for-subscribers", "-q", bag}, w.dir + "/play_held.txt");
  EXPECT_EQ(play.wait(60), 0) << readFile(w.dir + "/play_held.txt");
  // The periodic statistics (--stats 2) show all 50 received and none published yet (the unit is undecided).
  ASSERT_TRUE(bridge.says("IMU /imu -> H_IMU: 50 in, 0 out")) << readFile(bridge.log);
  EXPECT_EQ(w.lcm->count("H_IMU"), 0u);
  EXPECT_EQ(bridge.stop(), 0);
  EXPECT_TRUE(waitUntil([&] { return w.lcm->count("H_IMU") >= 50; }, 30));
  EXPECT_EQ(w.lcm->count("H_IMU"), 50u);
  EXPECT_NE(readFile(bridge.log).find("IMU /imu -> H_IMU: 50 in, 50 out, 0 rejected, 0 skipped, 0 dropped (50 held"),
            std::string::npos)
      << readFile(bridge.log);
}

#endif
