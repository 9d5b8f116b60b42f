// Map files (libs/map map_file.hpp): the formats this build reads. (Round trips of whole runs are in
// test_pipeline_remote.cpp, mutated files in test_io_fuzz.cpp.)
#include "livo/map/hybrid_map.hpp"
#include "livo/map/map_file.hpp"
#include "map_hybrid_test_util.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <sstream>
#include <string>

using namespace livo;
using namespace livo::test;

// Map files of version 1 stored patch samples as floats and no view count, version 2 bytes and the view
// count, version 3 adds the long-term flag; all load. The oracle: a version-3 file of the same map with
// the header's version and the fields a version lacks rewritten.
TEST(MapFile, OlderVersionsLoad) {
  HybridMap map(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  auto vp = visualPoint(42, Vec3(1, 2, 3));
  for (int i = 0; i < PatchPyramid::kValues; ++i) vp->obs[0].patch.values[std::size_t(i)] = std::uint8_t((i * 7 + 3) % 251);
  vp->from_longterm = true;  // returned from the long-term map
  vp->views = 5;
  const PatchPyramid stored = vp->obs[0].patch;
  ASSERT_TRUE(map.visual().local().insert(std::move(vp)));
  auto lt = visualPoint(43, Vec3(4, 5, 6));
  for (int i = 0; i < PatchPyramid::kValues; ++i) lt->obs[0].patch.values[std::size_t(i)] = std::uint8_t((i * 11 + 5) % 253);
  const PatchPyramid stored43 = lt->obs[0].patch;
  lt->from_longterm = false;  // the long-term map marks what it takes, here and on loading
  ASSERT_TRUE(map.visual().longterm().insert(std::move(lt)));
  std::ostringstream v3;
  saveMap(v3, map);
  const std::string bytes = v3.str();
  {
    HybridMap loaded(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
    std::istringstream in(bytes);
    loadMap(in, "v3", loaded);
    ASSERT_NE(loaded.visual().local().find(42), nullptr);
    EXPECT_TRUE(loaded.visual().local().find(42)->from_longterm);
    EXPECT_EQ(loaded.visual().local().find(42)->views, 5);
    ASSERT_NE(loaded.visual().longterm().find(43), nullptr);
    EXPECT_TRUE(loaded.visual().longterm().find(43)->from_longterm);
  }
  const std::string patch(reinterpret_cast<const char*>(stored.values.data()), stored.values.size());
  const std::size_t at = bytes.find(patch);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(bytes.find(patch, at + 1), std::string::npos) << "the patch must be found once";
  // Before the first observation's utime (int64): the view count (int32), then the flag (uint8).
  const std::size_t flag_at = at - 8 - 1, views_at = flag_at - 4;
  std::int32_t views_in_file = 0;
  std::memcpy(&views_in_file, &bytes[views_at], sizeof(views_in_file));
  EXPECT_EQ(views_in_file, 5);
  EXPECT_EQ(bytes[flag_at], '\1');
  const auto withVersion = [](std::string b, std::uint32_t v) {
    std::memcpy(&b[8], &v, sizeof(v));  // after the 8-byte magic
    return b;
  };
  // Version 2: without the flag bytes of 42 (local section, first) and 43 (long-term section, last).
  {
    std::string v2 = bytes.substr(0, flag_at) + bytes.substr(flag_at + 1);
    const std::string patch43(reinterpret_cast<const char*>(stored43.values.data()), stored43.values.size());
    const std::size_t z = v2.find(patch43);
    ASSERT_NE(z, std::string::npos);
    v2.erase(z - 8 - 1, 1);
    HybridMap loaded(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
    std::istringstream in(withVersion(v2, 2));
    loadMap(in, "v2", loaded);
    ASSERT_NE(loaded.visual().local().find(42), nullptr);
    EXPECT_FALSE(loaded.visual().local().find(42)->from_longterm);  // not stored: the local section's
    EXPECT_EQ(loaded.visual().local().find(42)->views, 5);
    ASSERT_NE(loaded.visual().longterm().find(43), nullptr);
    EXPECT_TRUE(loaded.visual().longterm().find(43)->from_longterm);
  }
  // Version 1: float samples, no view count, no flag (only point 42: the test cuts one point's fields).
  HybridMap one(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  ASSERT_TRUE(one.visual().local().insert(std::make_unique<VisualPoint>(*map.visual().local().find(42))));
  std::ostringstream one_os;
  saveMap(one_os, one);
  const std::string one_bytes = one_os.str();
  const std::size_t at1 = one_bytes.find(patch);
  ASSERT_NE(at1, std::string::npos);
  std::string floats(std::size_t(PatchPyramid::kValues) * sizeof(float), '\0');
  for (int i = 0; i < PatchPyramid::kValues; ++i) {
    // Off by up to 0.4 from the gray level, both ways: rounding must give it back.
    const float v = float(stored.values[std::size_t(i)]) + (i % 2 ? 0.4f : -0.4f) * float(stored.values[std::size_t(i)] > 0);
    std::memcpy(&floats[std::size_t(i) * sizeof(float)], &v, sizeof(float));
  }
  const std::size_t views1 = at1 - 8 - 1 - 4;
  const std::string v1 = withVersion(one_bytes.substr(0, views1) + one_bytes.substr(views1 + 5, at1 - views1 - 5) +
                                         floats + one_bytes.substr(at1 + patch.size()),
                                     1);
  HybridMap loaded(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  std::istringstream in(v1);
  loadMap(in, "v1", loaded);
  const VisualPoint* p = loaded.visual().local().find(42);
  ASSERT_NE(p, nullptr);
  EXPECT_TRUE(p->obs[0].patch.values == stored.values);
  EXPECT_EQ(p->views, 1);  // version 1: the observations it holds
  EXPECT_FALSE(p->from_longterm);
  // A version-1 patch sample that is no gray value is refused with the reason.
  std::string bad = v1;
  const float junk = 900.f;
  std::memcpy(&bad[at1 - 5 + 5 * sizeof(float)], &junk, sizeof(float));
  std::istringstream bad_in(bad);
  try {
    loadMap(bad_in, "bad", loaded);
    ADD_FAILURE() << "a sample of 900 must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a gray value"), std::string::npos) << e.what();
  }
  // Versions this build does not know are refused, naming those it reads.
  for (std::uint32_t v : {0u, 4u}) {
    std::istringstream vin(withVersion(bytes, v));
    try {
      loadMap(vin, "v", loaded);
      ADD_FAILURE() << "version " << v << " must be refused";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("reads 1 to 3"), std::string::npos) << e.what();
    }
  }
}
