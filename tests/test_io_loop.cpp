// The loop closure's message (map_correction_t; libs/io loop_messages.hpp) and its consumers' copy of the
// map frame (libs/loop map_frame.hpp): struct -> message -> bytes -> decode -> struct round trips with
// random values (fixed seed), validation errors that name the field, the byte-level precheck refusing
// counts the bytes cannot hold, and MapFrameTrajectory carrying frames by the keyframe before them.
#include "livo/io/loop_messages.hpp"
#include "livo/loop/map_frame.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace livo;

namespace {

std::mt19937 rng(20261207);
double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
Vec3 randVec3(double s) { return Vec3(uni(-s, s), uni(-s, s), uni(-s, s)); }
Pose randPose(double s) {
  Pose T = Pose::Identity();
  T.linear() = expSO3(randVec3(3.0));
  T.translation() = randVec3(s);
  return T;
}

MapCorrection randCorrection(int first, int n, int total, int loops) {
  MapCorrection c;
  c.utime = 1'700'000'000'000'000 + std::int64_t(uni(0, 1e9));
  c.T_map_odom = randPose(50.0);
  c.keyframes_total = total;
  c.first = first;
  Utime t = c.utime - 1'000'000'000;
  for (int i = 0; i < n; ++i) {
    t += 100'000 + std::int64_t(uni(0, 1e6));
    c.keyframes.push_back(KeyframePose{t, randPose(500.0), randPose(500.0)});
  }
  for (int i = 0; i < loops; ++i) {
    const int a = int(uni(0, total - 2));
    c.loops.emplace_back(a, a + 1 + int(uni(0, total - a - 1.01)));
  }
  c.solves = 7;
  c.final = true;
  return c;
}

void expectError(const Validation& v, const std::string& prefix, const std::string& detail = "") {
  ASSERT_FALSE(v) << "expected an error at " << prefix;
  EXPECT_EQ(v.error.rfind(prefix, 0), 0u) << v.error;
  EXPECT_NE(v.error.find(detail), std::string::npos) << v.error;
}

void expectNear(const Pose& a, const Pose& b) {
  EXPECT_LT((a.translation() - b.translation()).norm(), 1e-9);
  EXPECT_LT((a.linear() - b.linear()).norm(), 1e-12);
}

}  // namespace

TEST(MapCorrectionMessage, RoundTripKeepsKeyframesPosesAndLoops) {
  const MapCorrection c = randCorrection(5, 40, 60, 6);
  const auto bytes = encode(toMsg(c));
  livo::map_correction_t m{};
  ASSERT_TRUE(decode(bytes.data(), bytes.size(), m));
  MapCorrection d;
  ASSERT_TRUE(fromMsg(m, d));
  EXPECT_EQ(d.utime, c.utime);
  EXPECT_EQ(d.keyframes_total, 60);
  EXPECT_EQ(d.first, 5);
  EXPECT_EQ(d.solves, 7);
  EXPECT_TRUE(d.final);
  expectNear(d.T_map_odom, c.T_map_odom);
  ASSERT_EQ(d.keyframes.size(), c.keyframes.size());
  for (std::size_t i = 0; i < c.keyframes.size(); ++i) {
    EXPECT_EQ(d.keyframes[i].utime, c.keyframes[i].utime);
    expectNear(d.keyframes[i].T_odom, c.keyframes[i].T_odom);
    expectNear(d.keyframes[i].T_map, c.keyframes[i].T_map);
  }
  EXPECT_EQ(d.loops, c.loops);
  // An empty correction (no keyframe yet) is valid too.
  MapCorrection e;
  livo::map_correction_t me = toMsg(e);
  const auto eb = encode(me);
  ASSERT_TRUE(decode(eb.data(), eb.size(), me));
  EXPECT_TRUE(fromMsg(me, e));
}

TEST(MapCorrectionMessage, ValidationNamesTheField) {
  const livo::map_correction_t good = toMsg(randCorrection(2, 5, 10, 3));
  MapCorrection out;
  ASSERT_TRUE(fromMsg(good, out));
  out.utime = 4242;
  livo::map_correction_t m = good;
  m.keyframe_utime[3] = m.keyframe_utime[2];
  expectError(fromMsg(m, out), "map_correction_t.keyframe_utime[3]", "not after");
  EXPECT_EQ(out.utime, 4242) << "untouched on failure";
  m = good; m.map_pose[1][4] = std::nan("");
  expectError(fromMsg(m, out), "map_correction_t.map_pose[1].pose[4]", "non-finite");
  m = good; for (int i = 3; i < 7; ++i) m.odom_pose[0][std::size_t(i)] = 0.0;
  expectError(fromMsg(m, out), "map_correction_t.odom_pose[0].pose", "zero");
  m = good; m.position[1] = INFINITY;
  expectError(fromMsg(m, out), "map_correction_t.position/orientation[1]");
  m = good; m.first_keyframe = 6;  // 6 + 5 > 10
  expectError(fromMsg(m, out), "map_correction_t.first_keyframe + num_keyframes", "exceeds keyframes_total");
  m = good; m.loop_to[1] = m.loop_from[1];
  expectError(fromMsg(m, out), "map_correction_t.loop_from/loop_to[1]", "from < to");
  m = good; m.loop_to[0] = 10;
  expectError(fromMsg(m, out), "map_correction_t.loop_from/loop_to[0]", "keyframes_total");
  m = good; m.solves = -1;
  expectError(fromMsg(m, out), "map_correction_t.solves");
  m = good; m.num_keyframes = 4;
  expectError(fromMsg(m, out), "map_correction_t.keyframe_utime", "num_keyframes declares 4");
  MessageLimits lim;
  lim.max_keyframes = 4;
  expectError(fromMsg(good, out, lim), "map_correction_t.keyframes_total", "max_keyframes");
}

TEST(MapCorrectionMessage, PrecheckRefusesACountTheBytesCannotHold) {
  const livo::map_correction_t m = toMsg(randCorrection(0, 3, 3, 1));
  auto buf = encode(m);
  // num_keyframes sits after the hash and the 77-byte header.
  const std::size_t at = 8 + 8 + 24 + 32 + 4 + 4 + 1 + 4;
  ASSERT_EQ(buf[at + 3], 3);
  buf[at] = 0x00; buf[at + 1] = 0x10; buf[at + 2] = 0x00; buf[at + 3] = 0x00;  // 1 M keyframes declared
  livo::map_correction_t d{};
  expectError(decode(buf.data(), buf.size(), d), "map_correction_t.num_keyframes", "exceeds the limit");
  MessageLimits big;
  big.max_keyframes = 1 << 22;
  expectError(decode(buf.data(), buf.size(), d, big), "map_correction_t.num_keyframes", "bytes remain");
  auto short_buf = encode(m);
  short_buf.resize(short_buf.size() - 1);
  expectError(decode(short_buf.data(), short_buf.size(), d), "map_correction_t.num_loops", "only 7 bytes remain");
}

TEST(MapFrameTrajectory, CarriesFramesByTheKeyframeAtOrBeforeThemAndTakesLaterSolves) {
  // Keyframes at 1, 2, 3 s; the solve moves keyframe 1 by 1 m in x and turns keyframe 2 by 90 deg.
  MapCorrection c;
  c.keyframes_total = 3;
  for (int i = 0; i < 3; ++i) {
    KeyframePose k;
    k.utime = (i + 1) * 1'000'000;
    k.T_odom.translation() = Vec3(10.0 * i, 0, 0);
    k.T_map = k.T_odom;
    c.keyframes.push_back(k);
  }
  MapFrameTrajectory map;
  EXPECT_EQ(map.apply(c), "");
  Pose T = Pose::Identity();
  T.translation() = Vec3(12, 1, 0);
  EXPECT_FALSE(map.toMap(999'999, T)) << "before the first keyframe";
  expectNear(*map.toMap(2'500'000, T), T);  // no correction yet

  MapCorrection solved = c;
  solved.keyframes[1].T_map.translation() += Vec3(1, 0, 0);
  solved.keyframes[2].T_map.linear() = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_EQ(map.apply(solved), "");
  // Carried by keyframe 1 (at 2 s) up to just before 3 s: shifted by 1 m.
  EXPECT_LT((map.toMap(2'000'000, T)->translation() - Vec3(13, 1, 0)).norm(), 1e-12);
  EXPECT_LT((map.toMap(2'999'999, T)->translation() - Vec3(13, 1, 0)).norm(), 1e-12);
  // From 3 s by keyframe 2: T_map T_odom^-1 turns about keyframe 2's map position (20, 0): (12, 1) is
  // (-8, 1) from it, turned to (-1, -8).
  EXPECT_LT((map.toMap(3'000'000, T)->translation() - Vec3(19, -8, 0)).norm(), 1e-12);

  // A correction with keyframe 1 at another time (another run) is refused and changes nothing.
  MapCorrection other = c;
  other.first = 1;
  other.keyframes.erase(other.keyframes.begin());
  other.keyframes[0].utime += 5;
  EXPECT_NE(map.apply(other).find("keyframe 1 was at utime 2000000"), std::string::npos);
  EXPECT_LT((map.toMap(2'000'000, T)->translation() - Vec3(13, 1, 0)).norm(), 1e-12);

  // A gap (keyframes 3 to 5 never arrived, 6 did): frames before 7 s stay with keyframe 2, from 7 s on 6.
  MapCorrection later;
  later.keyframes_total = 7;
  later.first = 6;
  later.keyframes = {{7'000'000, Pose::Identity(), Pose::Identity()}};
  later.keyframes[0].T_map.translation() = Vec3(0, 0, 2);
  EXPECT_EQ(map.apply(later), "");
  EXPECT_EQ(map.known(), 4u);
  EXPECT_EQ(map.total(), 7);
  EXPECT_LT((map.toMap(6'000'000, T)->translation() - Vec3(19, -8, 0)).norm(), 1e-12);
  EXPECT_LT((map.toMap(7'000'000, T)->translation() - Vec3(12, 1, 2)).norm(), 1e-12);
}
