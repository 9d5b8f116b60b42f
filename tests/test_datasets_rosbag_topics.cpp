// ROS 1 bag import of several topics: events of all topics come out in time order; a missing topic, a
// wrong or unknown type give errors naming the topics.
// livo-test-deps: livo_io livo_rosbag_storage
#include "datasets_rosbag_test_util.hpp"

#include <gtest/gtest.h>

using namespace livo;

#if LIVO_TEST_ROSBAG

using namespace livo::test;

TEST(Rosbag, EventsOfAllTopicsComeOutInTimeOrder) {
  TempDir t;
  {
    rosbag::Bag bag(t / "a.bag", rosbag::bagmode::Write);
    using F = sensor_msgs::PointField;
    const CloudSpec ouster{"o", {{"x", F::FLOAT32, 0}, {"y", F::FLOAT32, 4}, {"z", F::FLOAT32, 8}, {"t", F::UINT32, 12}}, 16};
    // Written in record-time order: IMU 1 ms late, scans 100 ms late (recorded at their end), images 20 ms.
    std::vector<std::pair<std::int64_t, std::function<void(ros::Time)>>> writes;
    for (int i = 0; i < 200; ++i) {
      const std::int64_t st = kT0 + i * 5'000'000LL;
      writes.push_back({st + 1'000'000, [&bag, st](ros::Time rt) { bag.write("/imu", rt, imuMsg(st, {0, 0, 0}, {0, 0, 9.8})); }});
    }
    for (int k = 0; k < 10; ++k) {
      const std::int64_t st = kT0 + k * 100'000'000LL + 3'000'000;
      writes.push_back({st + 100'000'000, [&bag, st, ouster](ros::Time rt) {
                          std::vector<PointValues> pts;
                          for (int i = 0; i < 10; ++i) pts.push_back({{"x", 1}, {"y", i}, {"z", 0}, {"t", i * 9'000'000}});
                          bag.write("/os_cloud_node/points", rt, cloudMsg(ouster, st, pts));
                        }});
      const std::int64_t ct = kT0 + k * 100'000'000LL + 50'000'000;
      writes.push_back({ct + 20'000'000, [&bag, ct](ros::Time rt) {
                          sensor_msgs::Image m;
                          m.header.stamp = rosTime(ct);
                          m.height = 2, m.width = 2, m.encoding = "mono8", m.step = 2, m.data = {1, 2, 3, 4};
                          bag.write("/cam0/image_raw", rt, m);
                        }});
    }
    // One IMU sample stamped 0.8 s in the past: beyond the reorder window, dropped.
    writes.push_back({kT0 + 1'000'000'000, [&bag](ros::Time rt) { bag.write("/imu", rt, imuMsg(kT0 + 200'000'000, {0, 0, 0}, {0, 0, 9.8})); }});
    // One IMU sample with a glitched stamp 1000 s ahead: kept, written last, nothing else lost.
    writes.push_back({kT0 + 500'000'000, [&bag](ros::Time rt) { bag.write("/imu", rt, imuMsg(kT0 + 1000'000'000'000LL, {0, 0, 0}, {0, 0, 9.8})); }});
    std::stable_sort(writes.begin(), writes.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [rt, w] : writes) w(rosTime(rt));
  }
  RosbagOptions opt;
  opt.reorder_window_s = 0.5;
  const RosbagSummary s = convertRosbag(t / "a.bag", t / "a.lcm", opt);
  ASSERT_TRUE(s.error.empty()) << s.error;
  EXPECT_EQ(s.topics.lidar, "/os_cloud_node/points");
  EXPECT_EQ(s.topics.image, "/cam0/image_raw");
  const ReadBack r = readLog(t / "a.lcm");
  ASSERT_EQ(r.imu.size(), 201u);
  EXPECT_EQ(r.imu.back().utime, (kT0 + 1000'000'000'000LL) / 1000);
  EXPECT_EQ(r.scans.size(), 10u);
  EXPECT_EQ(r.images.size(), 10u);
  EXPECT_TRUE(std::is_sorted(r.times.begin(), r.times.end()));
  EXPECT_TRUE(contains(s.describe(), "1 LIVO_IMU events arrived later than the reorder window")) << s.describe();
  for (int k = 0; k < 10; ++k) EXPECT_EQ(r.scans[k].utime, (kT0 + k * 100'000'000LL + 3'000'000) / 1000);
}

TEST(Rosbag, TopicSelectionErrorsNameTheTopics) {
  TempDir t;
  {
    rosbag::Bag bag(t / "s.bag", rosbag::bagmode::Write);
    bag.write("/imu_a", rosTime(kT0), imuMsg(kT0, {0, 0, 0}, {0, 0, 9.8}));
    bag.write("/imu_b", rosTime(kT0), imuMsg(kT0, {0, 0, 0}, {0, 0, 9.8}));
    bag.write("/chatter", rosTime(kT0), RawMsg{"std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1", "string data\n", Bytes().str("hi").b});
    bag.write("/bad_md5", rosTime(kT0), RawMsg{"sensor_msgs/Imu", "0123456789abcdef0123456789abcdef", "# old\n", {}});
  }
  const std::string bag = t / "s.bag", out = t / "s.lcm";
  std::string e = errorOf([&] { convertRosbag(bag, out); });
  EXPECT_TRUE(contains(e, "several IMU topics; choose one with --imu-topic")) << e;
  EXPECT_TRUE(contains(e, "/imu_a (sensor_msgs/Imu, 1 messages)")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("", "/nope", "")); });
  EXPECT_TRUE(contains(e, "no topic /nope (--imu-topic)")) << e;
  EXPECT_TRUE(contains(e, "/chatter (std_msgs/String")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("/chatter", "/imu_a", "")); });
  EXPECT_TRUE(contains(e, "topic /chatter has type std_msgs/String, which is not a LiDAR type")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("", "/bad_md5", "")); });
  EXPECT_TRUE(contains(e, "definition MD5 0123456789abcdef0123456789abcdef is not the layout")) << e;
  e = errorOf([&] { convertRosbag(bag, out, only("none", "none", "none")); });
  EXPECT_TRUE(contains(e, "no LiDAR, IMU or camera topic to convert")) << e;
  EXPECT_FALSE(fs::exists(out));  // nothing written for errors found before the first message
  const RosbagSummary s = convertRosbag(bag, out, only("", "/imu_b", ""));
  EXPECT_EQ(s.conversion.events, 1u);
}

#endif  // LIVO_TEST_ROSBAG
