// libs/eval: TUM trajectory files: full-precision round trip, comments and blank lines, and errors naming
// the file, the line and the column.
#include "eval_test_util.hpp"

#include "livo/eval/evaluate.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

using namespace livo;
using namespace livo::test;

// ---------------------------------------------------------------- TUM files

TEST(TumIo, WriterFlushesEveryLineAndRoundTripsFullPrecision) {
  const Trajectory traj = perturb(syntheticTrajectory(), {knownTransform(1.0), 0.1, 0.1, 3});
  const std::string path = (tempDir() / "roundtrip.tum").string();
  TumWriter writer(path);
  for (int k = 0; k < 3; ++k) writer.write(traj[k]);
  // Still open: every written line must already be on disk.
  const Trajectory partial = readTum(path);
  ASSERT_EQ(partial.size(), 3u);
  for (std::size_t k = 3; k < traj.size(); ++k) writer.write(traj[k]);
  EXPECT_EQ(writer.count(), traj.size());

  const Trajectory back = readTum(path);
  ASSERT_EQ(back.size(), traj.size());
  for (std::size_t k = 0; k < traj.size(); ++k) {
    EXPECT_NEAR(back[k].t, traj[k].t, 1e-9 + 1e-15 * traj[k].t);
    EXPECT_LT((back[k].T_world_body.translation() - traj[k].T_world_body.translation()).norm(), 2e-9);
    EXPECT_LT(rotationAngle(back[k].T_world_body.linear().transpose() * traj[k].T_world_body.linear()), 1e-8);
  }
}

TEST(TumIo, SkipsCommentsBlankLinesAndCarriageReturns) {
  const std::string path = writeText("comments.tum",
                                     "# t x y z qx qy qz qw\n\n  \n"
                                     "1.0 1 2 3 0 0 0 1\r\n"
                                     "   # indented comment\n"
                                     "1.5\t4 5 6 0 0 0.7071068 0.7071068\n");
  const Trajectory traj = readTum(path);
  ASSERT_EQ(traj.size(), 2u);
  EXPECT_DOUBLE_EQ(traj[1].t, 1.5);
  EXPECT_TRUE(traj[1].T_world_body.translation().isApprox(Vec3(4, 5, 6)));
  EXPECT_NEAR(rotationAngle(traj[1].T_world_body.linear()), M_PI / 2, 1e-6);
}

TEST(TumIo, EmptyOrMissingFileIsAnErrorNamingTheFile) {
  for (const std::string text : {"", "# only a header\n\n"}) {
    const std::string path = writeText("empty.tum", text);
    const std::string msg = errorOf([&] { readTum(path); });
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("no poses"), std::string::npos) << msg;
  }
  const std::string missing = (tempDir() / "does_not_exist.tum").string();
  const std::string msg = errorOf([&] { readTum(missing); });
  EXPECT_NE(msg.find(missing + ": cannot open"), std::string::npos) << msg;
}

TEST(TumIo, TimesMustStrictlyIncreaseAndTheErrorNamesTheLine) {
  const std::string header = "# header\n1.0 0 0 0 0 0 0 1\n";
  for (const std::string bad : {"0.5 0 0 0 0 0 0 1\n", "1.0 0 0 0 0 0 0 1\n"}) {
    const std::string path = writeText("unsorted.tum", header + bad);
    const std::string msg = errorOf([&] { readTum(path); });
    EXPECT_NE(msg.find(path + ":3:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("strictly increasing"), std::string::npos) << msg;
  }
}

TEST(TumIo, MalformedRowsNameTheLineAndTheColumn) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"2.0 0 0 0 0 0 1\n", "got 7"},
      {"2.0 0 0 0 0 0 0 1 9\n", "got more"},
      {"2.0 0 0 0 abc 0 0 1\n", "column 'qx': not a number: 'abc'"},
      {"2.0 0 1.5x 0 0 0 0 1\n", "column 'y': not a number"},
      {"2.0 0 0 nan 0 0 0 1\n", "column 'z': value is not finite"},
      {"2.0 0 0 0 0 0 0 2\n", "quaternion norm"},
      {"2.0 0 0 0 0 0 0 0\n", "quaternion norm"},
  };
  for (const auto& [row, expected] : cases) {
    const std::string path = writeText("malformed.tum", "1.0 0 0 0 0 0 0 1\n" + row);
    const std::string msg = errorOf([&] { readTum(path); });
    EXPECT_NE(msg.find(path + ":2:"), std::string::npos) << row << " -> " << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << row << " -> " << msg;
  }
}
