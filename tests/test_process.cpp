// libs/process: typed LCM subscriptions (validation, reject counters, literal channel names), the
// processes' command line, and the core of livo-preprocess driven over memq:// (one process, no
// network): frames at the image times with their sweeps and IMU, bad messages counted, LiDAR-only mode.
// The exporter's core: test_process_exporter.cpp; the binaries and run-local: test_process_system.cpp.
#include "livo/common/timing.hpp"
#include "livo/estimation/pipeline.hpp"
#include "livo/io/channels.hpp"
#include "livo/process/cli.hpp"
#include "livo/process/lcm_node.hpp"
#include "livo/process/preprocess_node.hpp"

#include "process_test_files.hpp"
#include "process_test_streams.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <thread>

using namespace livo;
using test::lines;

namespace {

PreprocessConfig cameraConfig() {
  PreprocessConfig cfg;
  cfg.camera_enabled = true;
  cfg.imu_rate_hz = 200.0;
  cfg.blind_m = 0.5;
  return cfg;
}

/// Collects every frame published on LIVO_FRAME of `lcm`.
struct FrameSink {
  std::vector<Frame> frames;
  explicit FrameSink(LcmNode& lcm) {
    lcm.subscribeStruct<livo::frame_t, Frame>("LIVO_FRAME", [this](Frame& f) { frames.push_back(f); });
  }
};

}  // namespace

// ---------------------------------------------------------------- LcmNode, CLI

TEST(LcmNode, ValidMessagesReachTheHandlerBadOnesAreCounted) {
  std::ostringstream log;
  LcmNode lcm("memq://", "test", &log);
  std::vector<ImuSample> got;
  lcm.subscribeStruct<livo::imu_t, ImuSample>("LIVO_IMU", [&](ImuSample& s) { got.push_back(s); });

  ImuSample s;
  s.utime = 123;
  s.gyro = Eigen::Vector3d(0.1, 0.2, 0.3);
  lcm.publish("LIVO_IMU", toMsg(s));
  const std::vector<std::uint8_t> garbage{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  lcm.publishRaw("LIVO_IMU", garbage.data(), garbage.size());
  std::vector<std::uint8_t> truncated = encode(toMsg(s));
  truncated.resize(truncated.size() - 3);
  lcm.publishRaw("LIVO_IMU", truncated.data(), truncated.size());
  livo::imu_t nan_msg = toMsg(s);
  nan_msg.angular_velocity[1] = std::nan("");
  lcm.publish("LIVO_IMU", nan_msg);
  lcm.drain();

  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].utime, 123);
  EXPECT_DOUBLE_EQ(got[0].gyro.y(), 0.2);
  const ChannelCounters& c = lcm.counters().at("LIVO_IMU");
  EXPECT_EQ(c.received, 4u);
  EXPECT_EQ(c.rejected, 3u);
  EXPECT_NE(c.last_error.find("imu_t"), std::string::npos) << c.last_error;
  EXPECT_NE(log.str().find("LIVO_IMU: rejected message (3 so far)"), std::string::npos) << log.str();
}

TEST(LcmNode, ChannelNamesAreLiteralNotRegularExpressions) {
  LcmNode lcm("memq://", "test", nullptr);
  int hits = 0;
  lcm.subscribeRaw("A.B*", [&](const void*, std::size_t) {
    ++hits;
    return Validation::ok();
  });
  const char byte = 0;
  lcm.publishRaw("AxBBB", &byte, 1);
  lcm.publishRaw("A.B*", &byte, 1);
  lcm.drain();
  EXPECT_EQ(hits, 1);
  EXPECT_TRUE(lcm.dispatch("A.B*", &byte, 1));
  EXPECT_FALSE(lcm.dispatch("other", &byte, 1));
  EXPECT_EQ(hits, 2);
}

TEST(LcmNode, HandlerExceptionsAreRejectsNotCrashes) {
  LcmNode lcm("memq://", "test", nullptr);
  lcm.subscribeRaw("X", [](const void*, std::size_t) -> Validation { throw std::runtime_error("disk full"); });
  const char byte = 0;
  lcm.publishRaw("X", &byte, 1);
  EXPECT_NO_THROW(lcm.drain());
  EXPECT_EQ(lcm.totalRejected(), 1u);
  EXPECT_NE(lcm.counters().at("X").last_error.find("disk full"), std::string::npos);
}

TEST(LcmNode, MessagesHandledInsidePollKeepTheSpinFromIdling) {
  // A busy process (the estimator waiting for submaps handles frames inside its poll) is not idle:
  // 25 polls of 30 ms, each handling one message (with the spin's own 100 ms waits between them: 3 s),
  // outlast the 0.5 s idle exit several times.
  LcmNode lcm("memq://", "test", nullptr);
  int handled = 0, polls = 0;
  lcm.subscribeRaw("X", [&](const void*, std::size_t) {
    ++handled;
    return Validation::ok();
  });
  const LcmNode::SpinEnd end = lcm.spin(0.5, [&] {
    if (polls >= 25) return;
    ++polls;
    std::this_thread::sleep_for(std::chrono::milliseconds(30));  // the work of a frame
    const char byte = 0;
    lcm.publishRaw("X", &byte, 1);
    lcm.drain();  // handled inside poll, not by the spin's own handleOnce
  });
  EXPECT_EQ(end, LcmNode::SpinEnd::kIdle);
  EXPECT_EQ(polls, 25) << "the spin went idle while poll was still handling messages";
  EXPECT_EQ(handled, 25);
}

TEST(LcmNode, WarningsAreRateLimited) {
  std::vector<std::uint64_t> warned;
  for (std::uint64_t n = 0; n <= 20000; ++n)
    if (shouldWarn(n)) warned.push_back(n);
  EXPECT_EQ(warned, (std::vector<std::uint64_t>{1, 2, 3, 4, 5, 10, 100, 1000, 10000}));
}

TEST(LcmNode, UnusableUrlIsAnErrorNamingIt) {
  try {
    LcmNode lcm("nosuchprovider://x", "test", nullptr);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://x"), std::string::npos) << e.what();
  }
}

TEST(CommandLine, ParsesCommonOptionsAndNamesTheBadFlag) {
  auto parse = [](std::vector<const char*> argv, ProcessArgs& a, std::string* out = nullptr) {
    CommandLine cl("livo-x", "test");
    addProcessOptions(cl, a);
    if (out) cl.text("--out", out, "DIR", "output");
    argv.insert(argv.begin(), "livo-x");
    std::ostringstream os;
    return cl.parse(int(argv.size()), argv.data(), os) == CommandLine::Outcome::kRun;
  };
  ProcessArgs a;
  std::string out;
  EXPECT_TRUE(parse({"--config", "c.yaml", "--lcm-url=memq://", "--idle-exit", "2.5", "--out", "d", "--print-config"},
                    a, &out));
  EXPECT_EQ(a.config, "c.yaml");
  EXPECT_EQ(a.lcm_url, "memq://");
  EXPECT_DOUBLE_EQ(a.idle_exit_s, 2.5);
  EXPECT_TRUE(a.print_config);
  EXPECT_EQ(out, "d");

  auto error = [&](std::vector<const char*> argv) -> std::string {
    ProcessArgs b;
    try {
      parse(argv, b);
    } catch (const UsageError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error({"--lcm-url", "x"}), "--config is required");
  EXPECT_EQ(error({"--config", "c", "--bogus"}), "unknown option '--bogus'");
  EXPECT_EQ(error({"--config"}), "--config: missing value (CFG.yaml)");
  EXPECT_EQ(error({"--config", "c", "--idle-exit", "soon"}), "--idle-exit: expected a number >= 0, got 'soon'");
  EXPECT_EQ(error({"--config", "c", "--idle-exit", "-1"}), "--idle-exit: expected a number >= 0, got '-1'");
  EXPECT_EQ(error({"--config", "c", "stray"}), "unexpected argument 'stray'");

  ProcessArgs h;
  CommandLine cl("livo-x", "test");
  addProcessOptions(cl, h);
  const std::string help = cl.help();
  EXPECT_NE(help.find("--lcm-url URL"), std::string::npos) << help;
  EXPECT_NE(help.find(kDefaultLcmUrl), std::string::npos) << help;
  EXPECT_NE(help.find("--print-config"), std::string::npos) << help;
  EXPECT_NE(help.find("[default: 0 s]"), std::string::npos) << help;
}

TEST(CommandLine, PrintConfigIsTheEffectiveConfigurationAndAFixedPoint) {
  // Present keys keep their text, absent ones get the module's default (the selector's tau_translation_m
  // from `environment`), command-line overrides replace the value; the output loads back to the same text.
  const std::string yaml =
      "environment: outdoor\n"
      "lidar: {blind_m: 0.50, T_imu_lidar: [0, 0, 0, 0, 0, 0, 1], model: avia}\n"
      "preprocess: {wait_timeout_s: 0.4}\n"
      "channels: {frame: MY_FRAME}\n"
      "exporter: {map_voxel_m: 0.2}\n";
  auto print = [](const std::string& text) {
    ConfigFile file = ConfigFile::parse(text, "rig.yaml");
    PipelineConfig pipe;
    pipe.load(file.root());
    ChannelConfig ch;
    ch.load(file.root().section("channels"));
    file.overrideEffective("map.memory_cap_mb", 64.0);
    std::ostringstream os;
    printConfig(os, "livo-x", file, "--visual-mode all");
    return std::make_pair(os.str(), pipe);
  };
  const auto [printed, pipe] = print(yaml);
  for (const char* s : {"# Effective configuration of livo-x", "# Command-line settings, not config keys: --visual-mode all",
                        "environment: outdoor", "  blind_m: 0.50\n", "  wait_timeout_s: 0.4\n", "  frame: MY_FRAME\n",
                        "  tau_translation_m: 2\n", "  memory_cap_mb: 64\n", "  imu: LIVO_IMU\n"})
    EXPECT_NE(printed.find(s), std::string::npos) << s << "\n" << printed;
  EXPECT_EQ(printed.find("exporter"), std::string::npos) << "a section nobody read is not printed";
  EXPECT_EQ(print(printed).first, printed);
  EXPECT_EQ(print(printed).second.selector.tau_translation_m, pipe.selector.tau_translation_m);
  EXPECT_EQ(print(printed).second.preprocess.wait_timeout_s, pipe.preprocess.wait_timeout_s);
}

TEST(CommandLine, UnknownKeysInTheProcesssOwnSectionsAreErrors) {
  ConfigFile file = ConfigFile::parse(
      "lidar: {blind_m: 0.5, T_imu_lidar: [0, 0, 0, 0, 0, 0, 1]}\n"
      "preprocess: {wait_timeout_s: 0.4, wait_timout_s: 0.3}\n"
      "channels: {frame: MY_FRAME}\n",
      "rig.yaml");
  PreprocessConfig cfg;
  cfg.load(file.root());
  ChannelConfig ch;
  ch.load(file.root().section("channels"));
  EXPECT_EQ(ch.frame, "MY_FRAME");
  try {
    checkSectionsUsed(file, {"channels", "preprocess"});
    FAIL() << "expected an error for the typo";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rig.yaml: preprocess.wait_timout_s"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(checkSectionsUsed(file, {"channels"}));  // lidar.T_imu_lidar belongs to the estimator
}

// ---------------------------------------------------------------- PreprocessNode

TEST(PreprocessNode, PublishesOneFrameAtEachImageTimeOverMemq) {
  const test::SensorStream stream = test::makeSensorStream(2.0);
  std::ostringstream log;
  LcmNode lcm("memq://", "livo-preprocess", &log);
  FrameSink sink(lcm);
  PreprocessNode node(lcm, cameraConfig(), ChannelConfig{}, &log, 0.5);
  for (const auto& ev : stream.events) {
    lcm.publishRaw(ev.channel, ev.bytes.data(), ev.bytes.size());
    lcm.drain();
  }
  node.finish();
  lcm.drain();

  // One frame per image, then (at the end of input) one without image for the LiDAR points after the
  // last image (the recombiner's image_wait_timeout_s).
  ASSERT_EQ(sink.frames.size(), stream.image_times.size() + 1);
  EXPECT_FALSE(sink.frames.back().has_image);
  EXPECT_NEAR(double(sink.frames.back().utime), double(test::kStreamT0 + 1999500), 1.0);
  EXPECT_EQ(node.counters().frames_published, sink.frames.size());
  EXPECT_EQ(node.counters().frames_with_image, stream.image_times.size());
  EXPECT_EQ(lcm.totalRejected(), 0u) << lcm.countersSummary();
  Utime prev_end = 0;
  for (std::size_t i = 0; i < stream.image_times.size(); ++i) {
    const Frame& f = sink.frames[i];
    SCOPED_TRACE("frame " + std::to_string(i));
    EXPECT_EQ(f.utime, stream.image_times[i]);
    ASSERT_TRUE(f.has_image);
    EXPECT_EQ(f.image.utime, f.utime);
    EXPECT_EQ(f.image.format, PixelFormat::Gray8);
    ASSERT_EQ(f.image.width, 40);
    ASSERT_EQ(f.image.height, 30);
    // Gray of (4u, 100, 100): brightness rises with u, the same in every row.
    EXPECT_LT(f.image.data[0], f.image.data[39]);
    EXPECT_EQ(f.image.data[5], f.image.data[29 * 40 + 5]);
    if (i > 0) {
      EXPECT_EQ(f.sweep_start_utime, prev_end);
    }
    prev_end = f.utime;
    // Sweep: points in (sweep start, frame time] (the first sweep includes its first point).
    ASSERT_FALSE(f.sweep.points.empty());
    for (const auto& p : f.sweep.points) {
      const Utime t = f.sweep.utime + Utime(std::llround(1e6 * double(p.time_offset_s)));
      EXPECT_LE(t, f.utime + 1);
      if (i > 0) {
        EXPECT_GE(t, f.sweep_start_utime);
      }
    }
    // IMU brackets the sweep.
    ASSERT_GE(f.imu.size(), 2u);
    EXPECT_LE(f.imu.front().utime, f.sweep_start_utime);
    EXPECT_GE(f.imu.back().utime, f.utime);
  }
  // Periodic counters on message time: every 0.5 s of frame time over 1.9 s of frames.
  std::size_t reports = 0;
  for (const auto& l : lines(log.str())) reports += l.rfind("livo-preprocess: t ", 0) == 0;
  EXPECT_EQ(reports, 3u) << log.str();
  EXPECT_NE(node.summary().find("frames published 21 (20 with image"), std::string::npos) << node.summary();
}

TEST(PreprocessNode, BadMessagesAreCountedAndFramesStillFlow) {
  const test::SensorStream stream = test::makeSensorStream(2.0);
  std::ostringstream log;
  LcmNode lcm("memq://", "livo-preprocess", &log);
  FrameSink sink(lcm);
  PreprocessNode node(lcm, cameraConfig(), ChannelConfig{}, &log);
  const std::vector<std::uint8_t> garbage(64, 0xAB);
  Image jpeg;  // says JPEG, holds garbage: decodes as a message, fails in toGray8
  jpeg.utime = test::kStreamT0 + 1;
  jpeg.format = PixelFormat::Jpeg;
  jpeg.width = 40;
  jpeg.height = 30;
  jpeg.data.assign(100, 0x11);
  Image short_raw;  // raw RGB8 with too few bytes: fails validation
  short_raw.utime = test::kStreamT0 + 2;
  short_raw.format = PixelFormat::Rgb8;
  short_raw.width = 40;
  short_raw.height = 30;
  short_raw.row_stride = 120;
  short_raw.data.assign(50, 0);
  const livo::image_t short_msg = toMsg(short_raw);
  int injected = 0;
  for (const auto& ev : stream.events) {
    lcm.publishRaw(ev.channel, ev.bytes.data(), ev.bytes.size());
    if (ev.channel == "LIVO_LIDAR" && injected < 3) {
      ++injected;
      lcm.publishRaw("LIVO_LIDAR", garbage.data(), garbage.size());
      lcm.publishRaw("LIVO_IMU", garbage.data(), garbage.size());
      lcm.publish("LIVO_CAMERA", toMsg(jpeg));
      lcm.publish("LIVO_CAMERA", short_msg);
    }
    lcm.drain();
  }
  node.finish();
  lcm.drain();
  EXPECT_EQ(node.counters().frames_with_image, stream.image_times.size());
  EXPECT_EQ(sink.frames.size(), stream.image_times.size() + 1);
  EXPECT_EQ(lcm.counters().at("LIVO_LIDAR").rejected, 3u);
  EXPECT_EQ(lcm.counters().at("LIVO_IMU").rejected, 3u);
  EXPECT_EQ(lcm.counters().at("LIVO_CAMERA").rejected, 6u);
  EXPECT_EQ(node.counters().images_unconvertible, 3u);
  EXPECT_NE(log.str().find("LIVO_CAMERA: rejected message"), std::string::npos) << log.str();
}

TEST(PreprocessNode, LidarOnlyConfigFramesPerScanAndIgnoresImages) {
  const test::SensorStream stream = test::makeSensorStream(1.0);
  LcmNode lcm("memq://", "livo-preprocess", nullptr);
  FrameSink sink(lcm);
  PreprocessConfig cfg = cameraConfig();
  cfg.camera_enabled = false;
  ChannelConfig channels;
  channels.frame = "LIVO_FRAME";
  PreprocessNode node(lcm, cfg, channels, nullptr);
  const std::vector<std::uint8_t> garbage(16, 0);
  for (const auto& ev : stream.events) lcm.dispatch(ev.channel, ev.bytes.data(), ev.bytes.size());
  lcm.dispatch("LIVO_CAMERA", garbage.data(), garbage.size());  // not even decoded
  node.finish();
  lcm.drain();
  EXPECT_EQ(lcm.totalRejected(), 0u);
  EXPECT_EQ(node.recombiner().stats().images_ignored, stream.image_times.size() + 1);
  ASSERT_EQ(sink.frames.size(), 10u);  // one per scan
  for (std::size_t i = 0; i < sink.frames.size(); ++i) {
    EXPECT_FALSE(sink.frames[i].has_image);
    EXPECT_NEAR(double(sink.frames[i].utime), double(test::kStreamT0 + 100000 * Utime(i) + 99500), 1.0);  // scan i's last point
  }
}

// ---------------------------------------------------------------- speed (opt-in)
// ./test_process --gtest_also_run_disabled_tests --gtest_filter='*Speed*' (also test_process_exporter)

TEST(ProcessSpeed, DISABLED_PreprocessFramesPerSecond) {
  // Avia-like input: 24,000 points per 0.1 s scan, 640 x 512 RGB8 images at 10 Hz, IMU at 200 Hz.
  const test::SensorStream stream = test::makeSensorStream(5.0, 24000, 640, 512);
  std::size_t bytes = 0;
  for (const auto& ev : stream.events) bytes += ev.bytes.size();
  LcmNode lcm("memq://", "livo-preprocess", nullptr);
  std::size_t frames = 0;
  lcm.subscribeRaw("LIVO_FRAME", [&](const void*, std::size_t) {
    ++frames;
    return Validation::ok();
  });
  PreprocessNode node(lcm, cameraConfig(), ChannelConfig{}, nullptr);
  Stopwatch watch;
  for (const auto& ev : stream.events) {
    lcm.dispatch(ev.channel, ev.bytes.data(), ev.bytes.size());  // decode, convert, recombine, encode
    lcm.drain();                                                 // the published frames
  }
  node.finish();
  lcm.drain();
  const double s = watch.elapsedMs() / 1000.0;
  std::printf("preprocess: %zu frames in %.3f s = %.1f frames/s (%.1f MB/s of input, %.1f x real time)\n", frames, s,
              double(frames) / s, double(bytes) / 1e6 / s, 5.0 / s);
  EXPECT_EQ(frames, stream.image_times.size() + 1);
}
