// libs/sim: events are time-ordered and complete, camera frames independent of the scans, and the same
// seed gives the same bytes whatever the thread count.
#include "sim_test_util.hpp"

#include "livo/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

using namespace livo;
using namespace livo::sim;
using namespace livo::sim::test;

// ---------------------------------------------------------------- events and determinism

TEST(SimEvents, TimeOrderedCompleteAndCameraIndependentOfScans) {
  SimScenario sc = makeScenario("room", "mid360", true);
  sc.duration_s = 1.0;
  Simulator sim(sc);
  SimEvent ev;
  Utime last = 0;
  int imu = 0, scans = 0, images = 0;
  while (sim.next(ev)) {
    ASSERT_GE(ev.utime, last);
    last = ev.utime;
    ASSERT_LT(ev.utime, sim.startUtime() + 1'000'000);
    if (ev.kind == SimEvent::Kind::Imu) {
      ++imu;
      ASSERT_EQ(ev.utime, ev.imu.utime);
    }
    if (ev.kind == SimEvent::Kind::Lidar) {
      ++scans;
      ASSERT_EQ(ev.utime, ev.scan.utime);
    }
    if (ev.kind == SimEvent::Kind::Image) {
      ++images;
      ASSERT_EQ(ev.utime, ev.image.utime);
      ASSERT_NE((ev.utime - sim.startUtime()) % 100'000, 0);  // not on a scan boundary
      ASSERT_EQ(ev.image.format, PixelFormat::Gray8);
      ASSERT_EQ(ev.image.data.size(), static_cast<std::size_t>(ev.image.width * ev.image.height));
    }
  }
  EXPECT_EQ(imu, 200);
  EXPECT_EQ(scans, 10);
  EXPECT_EQ(images, 10);
}

namespace {

// Every byte of every event of a run, in order.
std::vector<std::uint8_t> runBytes(SimScenario sc, int threads) {
  std::vector<std::uint8_t> out;
  auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  Simulator sim(sc, SimOptions{threads});
  SimEvent ev;
  while (sim.next(ev)) {
    put(&ev.utime, sizeof ev.utime);
    if (ev.kind == SimEvent::Kind::Imu) put(ev.imu.gyro.data(), 24), put(ev.imu.accel.data(), 24);
    if (ev.kind == SimEvent::Kind::Lidar)
      for (const auto& p : ev.scan.points) put(p.p_lidar.data(), 12), put(&p.time_offset_s, 4), put(&p.intensity, 4), put(&p.ring, 2);
    if (ev.kind == SimEvent::Kind::Image) put(ev.image.data.data(), ev.image.data.size());
  }
  return out;
}

}  // namespace

TEST(SimDeterminism, SameSeedSameBytesWhateverTheThreadCount) {
  SimScenario sc = makeScenario("room", "avia", true);
  sc.duration_s = 1.2;
  const auto a = runBytes(sc, 1), b = runBytes(sc, 3);
  EXPECT_GT(a.size(), 1'000'000u);
  EXPECT_TRUE(a == b);
  sc.seed = 8;
  EXPECT_FALSE(a == runBytes(sc, 2));
}
