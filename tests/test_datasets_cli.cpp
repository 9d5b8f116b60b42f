// Dataset converters through the livo-convert binary, end to end (EuRoC folder, errors, unknown format).
// livo-test-deps: livo_io livo_common opencv_core opencv_imgcodecs
#include "datasets_test_util.hpp"

#include "test_skip.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

using namespace livo;
using namespace livo::test;

// ---------------- the binary, end to end ----------------

TEST(LivoConvert, BinaryEndToEnd) {
  const std::string bin = std::string(LIVO_BINARY_DIR) + "/bin/livo-convert";
  if (!fs::exists(bin)) LIVO_SKIP() << "binary not built: " << bin;
  SyntheticEuroc s;
  const std::string out = s.dir / "e.lcm", rig = s.dir / "rig.yaml", txt = s.dir / "stdout.txt";
  int rc = std::system((bin + " euroc " + s.dir.path.string() + " --out " + out + " --rig " + rig + " --quiet > " +
                        txt + " 2>&1").c_str());
  EXPECT_EQ(rc, 0);
  std::ifstream f(txt);
  const std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(text, "LIVO_CAMERA")) << text;
  EXPECT_TRUE(contains(text, "LIVO_IMU")) << text;
  EXPECT_EQ(readLog(out).images.size(), 3u);
  EXPECT_TRUE(fs::exists(rig));

  // Bad input: non-zero exit and a message naming file and line.
  s.setImuLine(5, "1,2,3");
  const std::string err = s.dir / "stderr.txt";
  const std::string bad_out = s.dir / "bad.lcm";
  rc = std::system((bin + " euroc " + s.dir.path.string() + " --out " + bad_out + " 2> " + err + " > /dev/null").c_str());
  EXPECT_NE(rc, 0);
  std::ifstream e(err);
  const std::string etext((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(etext, "mav0/imu0/data.csv:5: expected 7 columns, got 3")) << etext;
  EXPECT_FALSE(fs::exists(bad_out));

  // Unknown format.
  rc = std::system((bin + " bagfile x.bag --out " + out + " 2> " + err).c_str());
  EXPECT_NE(rc, 0);
  std::ifstream u(err);
  const std::string utext((std::istreambuf_iterator<char>(u)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(utext, "unknown format 'bagfile'")) << utext;
}
