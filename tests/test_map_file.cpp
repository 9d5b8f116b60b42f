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

// Map files of version 1 stored patch samples as floats; they load into today's byte samples rounded.
// The oracle: a version-2 file of the same map with the header's version and the one patch rewritten.
TEST(MapFile, VersionOneLoadsWithItsPatchesRounded) {
  HybridMap map(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  auto vp = visualPoint(42, Vec3(1, 2, 3));
  for (int i = 0; i < PatchPyramid::kValues; ++i) vp->obs[0].patch.values[std::size_t(i)] = std::uint8_t((i * 7 + 3) % 251);
  const PatchPyramid stored = vp->obs[0].patch;
  ASSERT_TRUE(map.visual().local().insert(std::move(vp)));
  std::ostringstream v2;
  saveMap(v2, map);
  std::string bytes = v2.str();
  const std::string patch(reinterpret_cast<const char*>(stored.values.data()), stored.values.size());
  const std::size_t at = bytes.find(patch);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(bytes.find(patch, at + 1), std::string::npos) << "the patch must be found once";
  std::string floats(std::size_t(PatchPyramid::kValues) * sizeof(float), '\0');
  for (int i = 0; i < PatchPyramid::kValues; ++i) {
    // Off by up to 0.4 from the gray level, both ways: rounding must give it back.
    const float v = float(stored.values[std::size_t(i)]) + (i % 2 ? 0.4f : -0.4f) * float(stored.values[std::size_t(i)] > 0);
    std::memcpy(&floats[std::size_t(i) * sizeof(float)], &v, sizeof(float));
  }
  // Version 1 has no view count: the int32 after the observation count, before the utime (int64).
  const std::size_t views_at = at - 8 - 4;
  std::string v1 = bytes.substr(0, views_at) + bytes.substr(views_at + 4, at - views_at - 4) + floats +
                   bytes.substr(at + patch.size());
  const std::uint32_t one = 1;
  std::memcpy(&v1[8], &one, sizeof(one));  // after the 8-byte magic
  HybridMap loaded(HybridMapConfig{}, VoxelMapConfig{}, VisualMapConfig{});
  std::istringstream in(v1);
  loadMap(in, "v1", loaded);
  const VisualPoint* p = loaded.visual().local().find(42);
  ASSERT_NE(p, nullptr);
  EXPECT_TRUE(p->obs[0].patch.values == stored.values);
  EXPECT_EQ(p->views, 1);  // version 1: the observations it holds
  // A version-1 patch sample that is no gray value is refused with the reason.
  std::string bad = v1;
  const float junk = 900.f;
  std::memcpy(&bad[at - 4 + 5 * sizeof(float)], &junk, sizeof(float));
  std::istringstream bad_in(bad);
  try {
    loadMap(bad_in, "bad", loaded);
    ADD_FAILURE() << "a sample of 900 must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a gray value"), std::string::npos) << e.what();
  }
  // Versions this build does not know are refused, naming both it reads.
  std::string v3 = bytes;
  const std::uint32_t three = 3;
  std::memcpy(&v3[8], &three, sizeof(three));
  std::istringstream v3_in(v3);
  try {
    loadMap(v3_in, "v3", loaded);
    ADD_FAILURE() << "version 3 must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("reads 1 and 2"), std::string::npos) << e.what();
  }
}
