// The estimator with its map in another process (FramePipeline + RemoteMap + MapService, the cores of
// livo-estimator and livo-mapserver) against the single-process Pipeline on the same frames, with
// the simulator's ground truth: same trajectory within a small tolerance, lost answers survived,
// map files that reload to the same answers.
// livo-test-whole (the simulated log is shared by its tests)
// livo-test-deps: livo_sim livo_estimation livo_eval livo_map
#include "livo/estimation/frame_pipeline.hpp"
#include "livo/estimation/remote_map.hpp"
#include "livo/map/map_file.hpp"
#include "livo/map/map_service.hpp"
#include "remote_test_util.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

using namespace livo;
using livo_test::SimFrames;

namespace {

/// MapClient calling a MapService directly; drops the answers whose request id `drop` selects.
class DirectClient : public MapClient {
 public:
  explicit DirectClient(MapService& s) : service_(s) {}
  std::function<bool(std::int64_t)> drop;
  bool request(const MapQuery& q, Submap& out) override {
    ++queries;
    if (drop && drop(q.request_id)) return false;
    out = service_.answer(q);
    plane_count += out.planes.size();
    visual_count += out.visual_points.size();
    return true;
  }
  void send(const MapUpdate& u) override {
    service_.apply(u);
    ++updates;
  }
  std::size_t queries = 0, updates = 0, plane_count = 0, visual_count = 0;

 private:
  MapService& service_;
};

struct RemoteRun {
  Trajectory est;
  std::size_t visual_frames = 0, timeouts = 0, timeout_frames = 0;
  std::size_t predicted = 0;  ///< frames that queried the map
};

RemoteRun runRemote(const SimFrames& sf, DirectClient& client) {
  FramePipeline est(sf.cfg);
  RemoteMap map(sf.cfg, client);
  RemoteRun out;
  for (const Frame& f : sf.frames) {
    const FrameResult r = est.process(f, map);
    out.predicted += r.link.queries > 0;
    if (!r.lio.initialized) continue;
    out.est.push_back({toSeconds(f.utime), r.lio.state.pose()});
    out.visual_frames += r.visual_used;
    out.timeouts += std::size_t(r.link.timeouts);
    out.timeout_frames += r.link.map_timeout;
  }
  return out;
}

MapService makeService(const PipelineConfig& cfg) {
  HybridMapConfig m = cfg.map;
  m.mode = cfg.map_mode;
  return MapService(m, cfg.lio.map, cfg.visual_map);
}

}  // namespace

/// Largest position difference between two trajectories at the common time stamps.
double maxDiff(const Trajectory& a, const Trajectory& b) {
  double worst = 0;
  std::size_t j = 0;
  std::size_t common = 0;
  for (const auto& pa : a) {
    while (j < b.size() && b[j].t < pa.t - 1e-9) ++j;
    if (j == b.size()) break;
    if (std::abs(b[j].t - pa.t) > 1e-9) continue;
    worst = std::max(worst, (pa.T_world_body.translation() - b[j].T_world_body.translation()).norm());
    ++common;
  }
  EXPECT_GT(common, a.size() * 9 / 10) << "the trajectories must share their time stamps";
  return worst;
}

class RemoteRoom : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { data_ = new SimFrames(livo_test::simulateFrames("room", 20.0, "adaptive")); }
  static void TearDownTestSuite() {
    delete data_;
    data_ = nullptr;
  }
  static SimFrames* data_;
};
SimFrames* RemoteRoom::data_ = nullptr;

TEST_F(RemoteRoom, SameTrajectoryAsTheSingleProcess) {
  const SimFrames& sf = *data_;
  MapService service = makeService(sf.cfg);
  DirectClient client(service);
  const RemoteRun r = runRemote(sf, client);
  ASSERT_GT(r.est.size(), 150u);
  const double ate_single = livo_test::ateRmse(sf.gt, sf.single);
  const double ate_remote = livo_test::ateRmse(sf.gt, r.est);
  const double diff = maxDiff(r.est, sf.single);
  std::cout << "room 20 s: single ATE " << ate_single * 100 << " cm (" << sf.single_visual_frames
            << " visual frames), remote ATE " << ate_remote * 100 << " cm (" << r.visual_frames
            << " visual frames), max position difference " << diff * 100 << " cm; queries " << client.queries
            << ", mean planes per submap " << double(client.plane_count) / double(client.queries) << "\n";
  EXPECT_EQ(r.timeouts, 0u);
  EXPECT_GT(r.visual_frames, 10u) << "the visual update runs through the map server too";
  // Measured (2026-12-02, patches as bytes): max position difference 0.458 mm (the planes the split
  // estimator sees lag the single process's by nothing in lock step; floating-point order and the
  // visual grid merge differ, and with patch samples rounded to gray levels such a difference can flip
  // a sample by one level: 0.0195 mm with float patches), ATE 0.3322 cm single, 0.3308 cm remote.
  // Bounds about twice that.
  EXPECT_LE(diff, 9e-4) << "split and single-process runs agree";
  EXPECT_LE(std::abs(ate_remote - ate_single), 4e-5);
  EXPECT_LE(ate_remote, 0.007);
  // The map server holds what the single process would: visual points were created remotely.
  EXPECT_GT(service.map().visual().local().size() + service.map().visual().longterm().size(), 100u);
  EXPECT_GT(service.counters().visual_upserts, 100u);
}

TEST_F(RemoteRoom, SurvivesLostSubmaps) {
  const SimFrames& sf = *data_;
  MapService service = makeService(sf.cfg);
  DirectClient client(service);
  // Every 7th answer lost, and a burst of 10 in a row (a map server restart).
  client.drop = [](std::int64_t id) { return id % 7 == 0 || (id >= 100 && id < 110); };
  const RemoteRun r = runRemote(sf, client);
  ASSERT_GT(r.est.size(), 150u);
  EXPECT_GT(r.timeouts, 20u);
  EXPECT_EQ(client.updates, r.predicted) << "one update per estimated frame, answered or not";
  const double ate = livo_test::ateRmse(sf.gt, r.est);
  std::cout << "room 20 s with lost answers: " << r.timeouts << " timeouts on " << r.timeout_frames << " frames, ATE "
            << ate * 100 << " cm\n";
  // Measured 0.225 cm with 43 timeouts (2026-12-02); about twice that.
  EXPECT_LE(ate, 0.0045) << "the estimator continues with the planes it has";
}

TEST_F(RemoteRoom, MapFileReloadsToTheSameAnswers) {
  const SimFrames& sf = *data_;
  MapService service = makeService(sf.cfg);
  DirectClient client(service);
  runRemote(sf, client);
  const std::string path = (std::filesystem::temp_directory_path() / "livo_test_map.bin").string();
  const MapFileInfo saved = saveMap(path, service.map());
  EXPECT_GT(saved.planes, 100u);
  MapService reloaded = makeService(sf.cfg);
  const MapFileInfo loaded = loadMap(path, reloaded.map());
  EXPECT_EQ(loaded.root_voxels, saved.root_voxels);
  EXPECT_EQ(loaded.planes, saved.planes);
  EXPECT_EQ(loaded.visual_points_local, saved.visual_points_local);
  EXPECT_EQ(loaded.visual_points_longterm, saved.visual_points_longterm);
  // Same content; vectors come back without their growth slack.
  EXPECT_LE(reloaded.map().stats().bytes_lidar, service.map().stats().bytes_lidar);
  EXPECT_GE(reloaded.map().stats().bytes_lidar, service.map().stats().bytes_lidar * 8 / 10);
  // A query over every root voxel answers the same planes and visual points.
  MapQuery q;
  service.map().lidar().voxels().forEachRoot([&q](const VoxelKey& k) { q.keys.push_back(k); });
  service.map().visual().local().forEach([&](const VisualPoint& p) { q.visual_keys.push_back(service.map().visual().local().keyOf(p.p_world)); });
  q.want_visual = true;
  const Submap a = service.answer(q), b = reloaded.answer(q);
  ASSERT_EQ(a.planes.size(), b.planes.size());
  ASSERT_EQ(a.visual_points.size(), b.visual_points.size());
  double worst = 0;
  for (std::size_t i = 0; i < a.planes.size(); ++i)
    worst = std::max(worst, (a.planes[i].plane.center - b.planes[i].plane.center).norm() +
                                (a.planes[i].plane.cov_nq - b.planes[i].plane.cov_nq).norm());
  EXPECT_EQ(worst, 0.0);
  EXPECT_EQ(a.next_visual_point_id, b.next_visual_point_id);

  // Damaged files: a clear error naming the file, and an empty map.
  {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), std::streamsize(bytes.size() / 2));
  }
  MapService broken = makeService(sf.cfg);
  try {
    loadMap(path, broken.map());
    ADD_FAILURE() << "a truncated map file must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_EQ(broken.map().lidar().voxels().numRootVoxels(), 0u);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << "not a map";
  EXPECT_THROW(loadMap(path, broken.map()), std::runtime_error);
  std::filesystem::remove(path);
}

TEST(PlaneIndex, AnswersLikeTheVoxelMap) {
  // The planes of a voxel map copied into a PlaneIndex give the same association for every query.
  VoxelMapConfig vc;
  VoxelMap map(vc);
  std::vector<PointWithCov> pts;
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 0.01);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int i = 0; i < 20000; ++i) {
    PointWithCov p;
    const double a = u(rng), b = u(rng);
    switch (i % 3) {
      case 0: p.p_world = Vec3(a, b, n(rng)); break;
      case 1: p.p_world = Vec3(a, 3.0 + n(rng), b + 3.0); break;
      default: p.p_world = Vec3(-3.0 + n(rng), a, b + 3.0); break;
    }
    p.cov_world = Mat3::Identity() * 1e-4;
    pts.push_back(p);
  }
  map.insert(pts);
  PlaneIndex index(vc.voxel_size_m, vc.sigma_num);
  map.forEachPlane([&](const VoxelKey& k, const Plane& pl) { index.add(k, pl); });
  ASSERT_EQ(index.numPlanes(), map.numPlanes());
  std::size_t matched = 0;
  for (int i = 0; i < 3000; ++i) {
    PointWithCov q = pts[std::size_t(i) * 5];
    q.p_world += Vec3(n(rng), n(rng), n(rng)) * 3.0;
    PlaneMatch a, b;
    const bool fa = map.findBestPlane(q, a), fb = index.findBestPlane(q, b);
    ASSERT_EQ(fa, fb) << i;
    if (!fa) continue;
    ++matched;
    EXPECT_EQ(a.distance, b.distance);
    EXPECT_EQ(a.probability, b.probability);
    EXPECT_EQ(a.plane->center, b.plane->center);
  }
  EXPECT_GT(matched, 2000u);
}
