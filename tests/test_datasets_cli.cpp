// Dataset converters through the livo-convert binary, end to end (EuRoC folder, errors, unknown format),
// and its command line (sub-commands, --help, --version, usage errors).
// livo-test-deps: livo_io livo_common livo_cli opencv_core opencv_imgcodecs
// livo-test-bins: livo-convert
#include "datasets_test_util.hpp"

#include "livo/cli/command_line.hpp"
#include "test_skip.hpp"

#include <sys/wait.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

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
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 1) << "a run-time error, not a crash: status " << rc;
  std::ifstream e(err);
  const std::string etext((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(etext, "mav0/imu0/data.csv:5: expected 7 columns, got 3")) << etext;
  EXPECT_FALSE(fs::exists(bad_out));

  // Unknown format.
  rc = std::system((bin + " bagfile x.bag --out " + out + " 2> " + err).c_str());
  EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2) << "a usage error, not a crash: status " << rc;
  std::ifstream u(err);
  const std::string utext((std::istreambuf_iterator<char>(u)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(contains(utext, "unknown command 'bagfile'")) << utext;
}

TEST(LivoConvert, SubCommandsHelpVersionAndUsageErrors) {
  const std::string bin = std::string(LIVO_BINARY_DIR) + "/bin/livo-convert";
  if (!fs::exists(bin)) LIVO_SKIP() << "binary not built: " << bin;
  TempDir dir;
  struct Ran {
    int rc;
    std::string out, err;
  };
  auto run = [&](const std::string& args) {
    const std::string out = dir / "out.txt", err = dir / "err.txt";
    const int status = std::system((bin + " " + args + " > " + out + " 2> " + err).c_str());
    auto slurp = [](const std::string& p) {
      std::ifstream f(p);
      return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    };
    return Ran{WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
  };
  Ran r = run("--help");
  EXPECT_EQ(r.rc, 0);
  for (const char* s : {"usage: livo-convert euroc|kitti|rosbag ARGS [options]", "commands:\n  euroc",
                        "usage: livo-convert euroc DIR --out LOG.lcm [options]", "--rate-hz HZ", "[default: 10 Hz]",
                        "--imu-accel-unit auto|g|mps2", "--fields auto|xyz|xyzi",
                        "exit status: 0 ok, 1 run-time error, 2 usage or configuration error"})
    EXPECT_TRUE(contains(r.out, s)) << s << "\n" << r.out;
  r = run("kitti --help");
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.out.rfind("usage: livo-convert kitti DIR --out LOG.lcm [options]\n", 0), 0u) << r.out;
  EXPECT_FALSE(contains(r.out, "--imu-margin")) << r.out;
  r = run("--version");
  EXPECT_EQ(r.rc, 0);
  EXPECT_EQ(r.out, std::string("livo-convert ") + livo::projectVersion() + "\n");

  for (const auto& [args, message, hint] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"kitti d --out o.lcm --rate-hz 5x", "--rate-hz: expected a number > 0, got '5x'", "livo-convert kitti"},
           {"kitti d --out o.lcm --fields xyzrgb", "--fields: expected one of auto|xyz|xyzi, got 'xyzrgb'",
            "livo-convert kitti"},
           {"rosbag b.bag --out o.lcm --mono16-bits 17", "--mono16-bits: expected an integer in [9, 16], got '17'",
            "livo-convert rosbag"},
           {"euroc d --out o.lcm --rate-hz 5", "unknown option '--rate-hz' (an option of kitti, not of livo-convert euroc)",
            "livo-convert euroc"},
           {"euroc --out o.lcm", "missing argument DIR", "livo-convert euroc"},
           {"euroc d", "--out is required", "livo-convert euroc"},
           {"bagfile x --out o.lcm", "unknown command 'bagfile' (expected euroc|kitti|rosbag)", "livo-convert"},
           {"", "missing command (euroc|kitti|rosbag)", "livo-convert"}}) {
    r = run(args);
    EXPECT_EQ(r.rc, 2) << args;
    EXPECT_EQ(r.err, "livo-convert: " + message + "\ntry '" + hint + " --help'\n") << args;
  }
  r = run("kitti " + (dir / "missing") + " --out " + (dir / "o.lcm"));  // bad input: 1
  EXPECT_EQ(r.rc, 1) << r.err;
}
