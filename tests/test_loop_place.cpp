// Place recognition (libs/loop): the descriptor under a turn about z, the keyframe selector, the search's
// recall and precision on the simulator's revisits (ground truth from the simulator), config errors.
// livo-test-deps: livo_sim
// livo-test-whole
#include "livo/loop/loop_verifier.hpp"
#include "livo/loop/place_database.hpp"
#include "livo/loop/place_descriptor.hpp"
#include "livo/sim/simulator.hpp"
#include "loop_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace livo {
namespace {

using test::revisitScenario;
using test::worldScan;
using test::wrapAngle;

std::vector<Vec3> turned(const std::vector<Vec3>& pts, double yaw) {
  const Eigen::AngleAxisd R(yaw, Vec3::UnitZ());
  std::vector<Vec3> out;
  out.reserve(pts.size());
  for (const Vec3& p : pts) out.push_back(R * p);
  return out;
}

TEST(PlaceDescriptor, ATurnAboutZIsFoundAsTheYawAndLeavesTheRingKey) {
  const sim::Simulator s(revisitScenario());
  const std::int64_t j = 100;  // 10 s in: on the road between the buildings
  const Pose T = s.T_world_imu(s.lidarUtime(j));
  const PlaceDescriptorConfig cfg;
  // The scan in the keyframe's frame, then the same scan seen by a sensor turned by -yaw (its points
  // turned by +yaw): the descriptor must report +yaw (p_query = Rz(yaw) p_candidate).
  const std::vector<Vec3> world = worldScan(s, j);
  const PlaceDescriptor ref = PlaceDescriptor::computeAt(world, T, cfg);
  const std::vector<Vec3> local = test::inKeyframe(world, T);
  ASSERT_GT(ref.occupiedSectors(), cfg.sectors * 3 / 4);
  const double sector = 2.0 * M_PI / cfg.sectors;
  for (const double yaw_deg : {0.0, 30.0, -90.0, 137.0, 181.0, -44.5, 3.0}) {
    const double yaw = yaw_deg * M_PI / 180.0;
    const PlaceDescriptor q = PlaceDescriptor::compute(turned(local, yaw), cfg);
    const PlaceMatch m = q.match(ref);
    SCOPED_TRACE("yaw " + std::to_string(yaw_deg) + " deg");
    // Within half a sector (3 deg): the parabola's refinement of the best shift.
    EXPECT_LT(std::abs(wrapAngle(m.yaw_rad - yaw)), 0.5 * sector) << "found " << m.yaw_rad * 180 / M_PI;
    // Whole sectors move the cells exactly; in between, points change cells near the borders.
    const bool whole = std::abs(std::remainder(yaw, sector)) < 1e-9;
    if (whole) {
      EXPECT_LT(m.distance, 1e-6);
      EXPECT_LT(q.ringKeyDistance(ref), 1e-6);
    } else {
      // 2026-12-06: up to 0.204 (137 deg) and 0.0134; true revisits of the revisit scenario reach 0.31,
      // other places start at 0.38 (the test below).
      EXPECT_LT(m.distance, 0.25);
      EXPECT_LT(q.ringKeyDistance(ref), 0.02);
    }
  }
}

// A narrow field of view (a 70 deg Avia fills about 12 of the 60 sectors): two views of one place turned
// by less than the field of view compare on the sectors both see and give the yaw; views that share no
// sector compare to nothing.
TEST(PlaceDescriptor, ANarrowFieldOfViewStillGivesTheYaw) {
  const sim::Simulator s(revisitScenario());
  const std::int64_t j = 100;
  const Pose T = s.T_world_imu(s.lidarUtime(j));
  const std::vector<Vec3> local = test::inKeyframe(worldScan(s, j), T);
  const PlaceDescriptorConfig cfg;
  auto window = [&](double centre_deg) {  // the points within +-35 deg of an azimuth
    std::vector<Vec3> out;
    for (const Vec3& p : local)
      if (std::abs(wrapAngle(std::atan2(p.y(), p.x()) - centre_deg * M_PI / 180.0)) < 35.0 * M_PI / 180.0) out.push_back(p);
    return out;
  };
  const PlaceDescriptor ref = PlaceDescriptor::compute(window(0.0), cfg);
  ASSERT_LT(ref.occupiedSectors(), cfg.sectors / 4) << "fewer sectors than the 360 deg minimum of a quarter";
  for (const double yaw_deg : {12.0, -24.0, 30.0}) {
    SCOPED_TRACE("yaw " + std::to_string(yaw_deg) + " deg");
    // The same view from a sensor turned by -yaw: its points turned by +yaw.
    const PlaceMatch turn = PlaceDescriptor::compute(turned(window(0.0), yaw_deg * M_PI / 180.0), cfg).match(ref);
    EXPECT_LT(turn.distance, 0.25);
    EXPECT_LT(std::abs(wrapAngle(turn.yaw_rad - yaw_deg * M_PI / 180.0)), 0.5 * 2.0 * M_PI / cfg.sectors)
        << "found " << turn.yaw_rad * 180 / M_PI;
    // Looking yaw further round from the same spot: partly other points, the shared sectors agree.
    const PlaceMatch look = PlaceDescriptor::compute(window(yaw_deg), cfg).match(ref);
    EXPECT_LT(look.distance, 0.3);
    EXPECT_LT(std::abs(wrapAngle(look.yaw_rad)), 0.5 * 2.0 * M_PI / cfg.sectors);
  }
  EXPECT_GT(PlaceDescriptor::compute(window(180.0), cfg).match(ref).distance, 0.3) << "the view behind is another place";
}

TEST(PlaceDescriptor, ScansFromOtherPlacesAreFarAndEmptyScansCompareToNothing) {
  const sim::Simulator s(revisitScenario());
  const PlaceDescriptorConfig cfg;
  auto at = [&](std::int64_t j) { return PlaceDescriptor::computeAt(worldScan(s, j), s.T_world_imu(s.lidarUtime(j)), cfg); };
  const PlaceDescriptor a = at(100), b = at(102), far = at(200);  // 1.6 m and 80 m of road apart
  EXPECT_LT(b.match(a).distance, a.match(far).distance);
  const PlaceDescriptor none = PlaceDescriptor::compute({}, cfg);
  EXPECT_EQ(none.occupiedSectors(), 0);
  EXPECT_EQ(a.match(none).distance, 1.0);
  EXPECT_EQ(none.match(none).distance, 1.0);
  PlaceDescriptorConfig other = cfg;
  other.sectors = 30;
  EXPECT_EQ(PlaceDescriptor::compute(turned({Vec3(5, 0, 1)}, 0), other).match(a).distance, 1.0) << "sizes differ";
  // NaN points are left out, not binned.
  const PlaceDescriptor nan = PlaceDescriptor::compute({Vec3(NAN, 1, 1), Vec3(3, 0, 1)}, cfg);
  EXPECT_EQ(nan.occupiedSectors(), 1);
}

TEST(KeyframeSelector, EveryDistanceOrTurn) {
  KeyframeConfig cfg;
  cfg.distance_m = 2.0;
  cfg.angle_deg = 20.0;
  KeyframeSelector sel(cfg);
  int keys = 0;
  for (int i = 0; i <= 40; ++i) {  // 10 m straight in 0.25 m steps: keyframes at 0, 2, 4, 6, 8, 10 m
    Pose T = Pose::Identity();
    T.translation() = Vec3(0.25 * i, 0, 0);
    keys += sel.offer(T);
  }
  EXPECT_EQ(keys, 6);
  EXPECT_NEAR(sel.pathLength(), 10.0, 1e-9);
  keys = 0;
  for (int i = 1; i <= 18; ++i) {  // a turn in place of 90 deg in 5 deg steps: keyframes at 20, 40, 60, 80
    Pose T = Pose::Identity();
    T.translation() = Vec3(10, 0, 0);
    T.linear() = Eigen::AngleAxisd(5.0 * i * M_PI / 180.0, Vec3::UnitZ()).toRotationMatrix();
    keys += sel.offer(T);
  }
  EXPECT_EQ(keys, 4);
  EXPECT_NEAR(sel.pathLength(), 10.0, 1e-9) << "turning in place travels nothing";
}

// The revisit scenario drives a 340 m block three times. Keyframes every 2 m (true poses and scans);
// each is searched among those stored at least min_loop_path_m earlier before it is stored. A revisit
// is a keyframe with a stored one within 4 m; a found candidate is right when it lies within 4 m. The
// best candidate is then verified geometrically (loop_verifier.hpp) with the true relative pose as the
// odometry's guess; an accepted loop is false when its relative pose is off the truth.
TEST(PlaceDatabase, FindsTheRevisitsOfTheRevisitScenario) {
  const sim::Simulator s(revisitScenario());
  const PlaceDescriptorConfig dcfg;
  PlaceSearchConfig scfg;
  scfg.min_path_m = 2.0 * dcfg.max_range_m;
  PlaceDatabase db(scfg);
  KeyframeSelector sel(KeyframeConfig{});
  LoopVerifyConfig vcfg;
  vcfg.range_sigma_m = s.scenario().lidar.range_noise_m;
  vcfg.bearing_sigma_deg = s.scenario().lidar.beam_noise_deg;
  LoopVerifier verifier(vcfg);
  std::vector<std::vector<Vec3>> stored;  // per keyframe, its points in its frame (thinned to 0.2 m)
  constexpr double kNear = 4.0;
  int revisits = 0, found_right = 0, found_wrong = 0, found_elsewhere = 0, verified_right = 0, verified_wrong = 0;
  double max_yaw_err = 0.0, max_loop_err_m = 0.0;
  const std::int64_t scans = static_cast<std::int64_t>(s.scenario().duration_s * s.scenario().lidar.rate_hz) - 1;
  for (std::int64_t j = 0; j < scans; ++j) {
    const Utime t = s.lidarUtime(j);
    const Pose T = s.T_world_imu(t);
    if (!sel.offer(T)) continue;
    PlaceEntry e;
    e.utime = t;
    e.path_m = sel.pathLength();
    e.T_world_body = T;
    std::vector<Vec3> local = test::inKeyframe(worldScan(s, j), T);
    e.descriptor = PlaceDescriptor::compute(local, dcfg);
    bool revisit = false;
    for (std::size_t i = 0; i < db.size(); ++i)
      revisit |= e.path_m - db.entry(int(i)).path_m >= scfg.min_path_m &&
                 (db.entry(int(i)).T_world_body.translation() - T.translation()).norm() < kNear;
    revisits += revisit;
    const auto cands = db.search(e.descriptor, e.path_m);
    if (!cands.empty()) {
      const PlaceEntry& c = db.entry(cands[0].id);
      const bool right = (c.T_world_body.translation() - T.translation()).norm() < kNear;
      if (right && revisit) {
        ++found_right;
        max_yaw_err = std::max(max_yaw_err, std::abs(wrapAngle(cands[0].match.yaw_rad - (yawOf(c.T_world_body) - yawOf(T)))));
      } else if (revisit) {
        ++found_wrong;
      } else {
        ++found_elsewhere;
      }
      const Pose gt = keyframeFrame(c.T_world_body).inverse() * keyframeFrame(T);
      const LoopCheck check = verifier.verify(stored[std::size_t(cands[0].id)], local, cands[0].match.yaw_rad, gt,
                                              e.path_m - c.path_m);
      // A verified loop is false when its relative pose is: more than 0.3 m or 1 deg off the truth.
      const double err_m = (check.T_cand_query.translation() - gt.translation()).norm();
      const double err_deg = rotationAngle(gt.linear().transpose() * check.T_cand_query.linear()) * 180 / M_PI;
      if (check.accepted && err_m < 0.3 && err_deg < 1.0) {
        ++verified_right;
        max_loop_err_m = std::max(max_loop_err_m, err_m);
      } else if (check.accepted) {
        ++verified_wrong;
      }
    }
    stored.push_back(thinPoints(local, 0.2));
    db.add(std::move(e));
  }
  const double recall = revisits > 0 ? double(found_right) / revisits : 0.0;
  const int found = found_right + found_wrong + found_elsewhere;
  const double precision = found > 0 ? double(found_right) / found : 0.0;
  const LoopCheckCounts& n = verifier.counts();
  std::printf("revisit scenario: %zu keyframes, %d revisits; search: %d right, %d wrong place, %d where none was "
              "stored: recall %.3f, precision %.3f, max yaw error %.2f deg; verified: %d right, %d wrong (max "
              "error %.3f m); rejected: %d too few points, %d not converged, %d low overlap, %d high residual, "
              "%d inconsistent\n",
              db.size(), revisits, found_right, found_wrong, found_elsewhere, recall, precision,
              max_yaw_err * 180 / M_PI, verified_right, verified_wrong, max_loop_err_m, n.too_few_points,
              n.no_convergence, n.low_overlap, n.high_residual, n.inconsistent);
  // 2026-12-06: 383 keyframes, 247 revisits, recall 0.996, precision 1.000, max yaw error 2.58 deg; 246
  // verified, none false, the largest loop error 1.2 cm.
  EXPECT_GT(revisits, 200);
  EXPECT_GE(recall, 0.98);
  EXPECT_GE(precision, 0.98);
  EXPECT_LT(max_yaw_err * 180 / M_PI, 5.0);
  EXPECT_EQ(verified_wrong, 0);
  EXPECT_GE(verified_right, found_right * 95 / 100);
  EXPECT_LT(max_loop_err_m, 0.025);
}

TEST(LoopConfig, KeysAreCheckedAndBoundedByTheSensor) {
  auto error = [](const std::string& yaml, double lidar_range) {
    const ConfigFile f = ConfigFile::parse(yaml, "rig.yaml");
    try {
      PlaceDescriptorConfig d;
      d.load(f.root().section("loop"), lidar_range);
      PlaceSearchConfig s;
      s.load(f.root().section("loop"), d);
      KeyframeConfig k;
      k.load(f.root().section("loop"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("loop:\n  descriptor_rings: 10\n", 100.0), "");
  EXPECT_EQ(error("loop:\n  descriptor_range_m: 80\n", 60.0),
            "rig.yaml: loop.descriptor_range_m: must not exceed lidar.max_range_m (60.000000)");
  EXPECT_NE(error("loop:\n  descriptor_sectors: 4\n", 60.0).find("loop.descriptor_sectors: must be in [8, 720]"),
            std::string::npos);
  EXPECT_NE(error("loop:\n  keyframe_distance_m: 0\n", 60.0).find("loop.keyframe_distance_m"), std::string::npos);
  EXPECT_NE(error("loop:\n  match_distance: 2\n", 60.0).find("loop.match_distance"), std::string::npos);
  // A short-range sensor bounds the descriptor and with it the travel before a loop counts.
  const ConfigFile f = ConfigFile::parse("loop: {}\n", "rig.yaml");
  PlaceDescriptorConfig d;
  d.load(f.root().section("loop"), 12.0);
  PlaceSearchConfig s;
  s.load(f.root().section("loop"), d);
  EXPECT_EQ(d.max_range_m, 12.0);
  EXPECT_EQ(s.min_path_m, 24.0);
}

}  // namespace
}  // namespace livo
