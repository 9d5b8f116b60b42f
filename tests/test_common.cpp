// libs/common: SO(3)/SE(3) against numeric differences and identities, config loading errors,
// timing summaries.
#include "livo/common/config.hpp"
#include "livo/common/modes.hpp"
#include "livo/common/ms_histogram.hpp"
#include "livo/common/so3.hpp"
#include "livo/common/timing.hpp"
#include "livo/common/types.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace livo;

namespace {

Vec3 randomAxisAngle(std::mt19937& rng, double angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 a(n(rng), n(rng), n(rng));
  return a.normalized() * angle;
}

// Numeric right Jacobian: columns of Log(Exp(phi)^-1 Exp(phi + eps e_i)) / eps.
Mat3 numericRightJacobian(const Vec3& phi) {
  const double eps = 1e-6;
  Mat3 J;
  for (int i = 0; i < 3; ++i) {
    Vec3 d = Vec3::Zero();
    d[i] = eps;
    const Vec3 plus = logSO3(expSO3(phi).transpose() * expSO3(phi + d));
    const Vec3 minus = logSO3(expSO3(phi).transpose() * expSO3(phi - d));
    J.col(i) = (plus - minus) / (2 * eps);
  }
  return J;
}

}  // namespace

TEST(So3, HatVeeAndCrossProduct) {
  const Vec3 a(1, -2, 3), b(0.5, 4, -1);
  EXPECT_TRUE((hat(a) * b).isApprox(a.cross(b)));
  EXPECT_TRUE(vee(hat(a)).isApprox(a));
}

TEST(So3, ExpLogRoundTripAcrossAngles) {
  std::mt19937 rng(7);
  // From tiny angles through the series/closed-form switch up to (almost) pi.
  for (double angle : {0.0, 1e-12, 1e-7, 1e-5, 1e-3, 0.1, 1.0, 2.5, 3.0, M_PI - 1e-4, M_PI - 1e-8}) {
    for (int k = 0; k < 20; ++k) {
      const Vec3 phi = randomAxisAngle(rng, angle);
      const Mat3 R = expSO3(phi);
      EXPECT_NEAR((R.transpose() * R - Mat3::Identity()).norm(), 0.0, 1e-12);
      EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
      const Vec3 back = logSO3(R);
      EXPECT_TRUE(expSO3(back).isApprox(R, 1e-9)) << "angle " << angle;
      if (angle < M_PI - 1e-3) {
        EXPECT_NEAR((back - phi).norm(), 0.0, 1e-9) << "angle " << angle;
      }
    }
  }
}

TEST(So3, LogAtExactlyPi) {
  const Vec3 axis = Vec3(1, 2, -1).normalized();
  const Mat3 R = Eigen::AngleAxisd(M_PI, axis).toRotationMatrix();
  const Vec3 phi = logSO3(R);
  EXPECT_NEAR(phi.norm(), M_PI, 1e-9);
  EXPECT_NEAR(std::abs(phi.normalized().dot(axis)), 1.0, 1e-9);
}

TEST(So3, ExpMatchesEigenAngleAxis) {
  std::mt19937 rng(3);
  for (int k = 0; k < 50; ++k) {
    const Vec3 phi = randomAxisAngle(rng, 3.0 * (k + 1) / 50.0);
    EXPECT_TRUE(expSO3(phi).isApprox(Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix(), 1e-12));
  }
}

TEST(So3, RightJacobianMatchesNumeric) {
  std::mt19937 rng(11);
  for (double angle : {1e-9, 1e-4, 0.3, 1.5, 2.8}) {
    const Vec3 phi = randomAxisAngle(rng, angle);
    EXPECT_TRUE(rightJacobianSO3(phi).isApprox(numericRightJacobian(phi), 1e-6)) << "angle " << angle;
    EXPECT_TRUE((rightJacobianSO3(phi) * rightJacobianInvSO3(phi)).isApprox(Mat3::Identity(), 1e-9));
  }
}

TEST(So3, RightJacobianInverseFiniteNearPi) {
  const Vec3 phi = Vec3(0, 0, 1) * (M_PI - 1e-9);
  EXPECT_TRUE(rightJacobianInvSO3(phi).allFinite());
}

TEST(Se3, ExpLogRoundTrip) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 2.0);
  for (int k = 0; k < 50; ++k) {
    Vec6 xi;
    for (int i = 0; i < 3; ++i) xi[i] = n(rng);
    xi.tail<3>() = randomAxisAngle(rng, 0.06 * k);
    const Pose T = expSE3(xi);
    EXPECT_NEAR((logSE3(T) - xi).norm(), 0.0, 1e-9);
  }
}

TEST(Se3, ExpIsMatrixExponential) {
  // Oracle: exp of the 4x4 twist matrix by a long Taylor series.
  Vec6 xi;
  xi << 0.3, -1.2, 0.7, 0.4, -0.2, 0.9;
  Eigen::Matrix4d X = Eigen::Matrix4d::Zero();
  X.topLeftCorner<3, 3>() = hat(xi.tail<3>());
  X.topRightCorner<3, 1>() = xi.head<3>();
  Eigen::Matrix4d sum = Eigen::Matrix4d::Identity(), term = Eigen::Matrix4d::Identity();
  for (int k = 1; k < 40; ++k) {
    term = term * X / k;
    sum += term;
  }
  EXPECT_TRUE(expSE3(xi).matrix().isApprox(sum, 1e-12));
}

TEST(Se3, PoseArrayRoundTrip) {
  const double a[7] = {1, 2, 3, -0.5, 0.5, -0.5, 0.5};
  const Pose T = poseFromArray(a);
  const auto b = poseToArray(T);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(a[i], b[i], 1e-12);
  // Camera looking forward (the simulated rigs' nominal mounting): optical axis z_cam = x_imu.
  EXPECT_TRUE((T.linear() * Vec3::UnitZ()).isApprox(Vec3::UnitX()));
  const double zero[7] = {0, 0, 0, 0, 0, 0, 0};
  EXPECT_THROW(poseFromArray(zero), std::invalid_argument);
}

// ---- config ----

struct ToyLioConfig {
  double voxel_size_m = 0.5;
  int max_layer = 2;
  Eigen::Isometry3d T_imu_lidar = Eigen::Isometry3d::Identity();
  void load(const ConfigNode& n) {
    n.require("voxel_size_m", voxel_size_m).get("max_layer", max_layer).get("T_imu_lidar", T_imu_lidar);
    n.check(voxel_size_m > 0, "voxel_size_m", "must be > 0");
  }
};

TEST(Config, ReadsKeysAndKeepsDefaults) {
  auto f = ConfigFile::parse("lio:\n  voxel_size_m: 0.4\n  T_imu_lidar: [1, 2, 3, 0, 0, 0, 1]\n", "rig.yaml");
  ToyLioConfig c;
  c.load(f.root().section("lio"));
  EXPECT_DOUBLE_EQ(c.voxel_size_m, 0.4);
  EXPECT_EQ(c.max_layer, 2);
  EXPECT_TRUE(c.T_imu_lidar.translation().isApprox(Vec3(1, 2, 3)));
  EXPECT_NO_THROW(f.checkAllKeysUsed());
}

TEST(Config, EffectiveLinesNameEveryKeyAndDifferencesNameTheKeysThatDiffer) {
  auto a = ConfigFile::parse("lio:\n  voxel_size_m: 0.4\n  T_imu_lidar: [1, 2, 3, 0, 0, 0, 1]\n", "a.yaml");
  auto b = ConfigFile::parse("lio:\n  voxel_size_m: 0.5\n  max_layer: 3\n  T_imu_lidar: [1, 2, 3.5, 0, 0, 0, 1]\n",
                             "b.yaml");
  ToyLioConfig ca, cb;
  ca.load(a.root().section("lio"));
  cb.load(b.root().section("lio"));
  const std::string la = a.effectiveLines(), lb = b.effectiveLines();
  EXPECT_NE(la.find("lio.voxel_size_m=0.4\n"), std::string::npos) << la;
  EXPECT_NE(la.find("lio.max_layer=2\n"), std::string::npos) << "defaults too:\n" << la;
  EXPECT_TRUE(configDifferences(la, la).empty());
  const std::vector<std::string> d = configDifferences(la, lb);
  ASSERT_EQ(d.size(), 3u) << la << lb;
  EXPECT_EQ(d[0].rfind("lio.T_imu_lidar: [1, 2, 3, 0, 0, 0, 1] here, [1, 2, 3.5, 0, 0, 0, 1] there", 0), 0u) << d[0];
  EXPECT_EQ(d[1], "lio.max_layer: 2 here, 3 there");
  EXPECT_EQ(d[2], "lio.voxel_size_m: 0.4 here, 0.5 there");
  EXPECT_EQ(configDifferences(la, lb, {"lio.max_layer"}).size(), 2u) << "ignored keys";
  EXPECT_EQ(configDifferences(la, lb, {}, 1).size(), 1u) << "at most max";
  EXPECT_TRUE(configDifferences(la, "other.key=1\n").empty()) << "only keys both read";
}

TEST(Config, MissingRequiredKeyNamesKeyAndFile) {
  auto f = ConfigFile::parse("lio:\n  max_layer: 3\n", "rig.yaml");
  ToyLioConfig c;
  try {
    c.load(f.root().section("lio"));
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rig.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("lio.voxel_size_m"), std::string::npos) << e.what();
  }
}

TEST(Config, UnknownKeyNamesKey) {
  auto f = ConfigFile::parse("lio:\n  voxel_size_m: 0.5\n  voxle_size: 1\nimu:\n  rate: 3\n", "rig.yaml");
  ToyLioConfig c;
  c.load(f.root().section("lio"));
  try {
    f.checkAllKeysUsed();
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("lio.voxle_size"), std::string::npos) << msg;
    EXPECT_NE(msg.find("1 more"), std::string::npos) << msg;
  }
  const auto unused = f.unusedKeys();
  ASSERT_EQ(unused.size(), 2u);
  EXPECT_EQ(unused[1], "imu");
}

TEST(Config, WrongTypesAndBadValuesNameKey) {
  {
    auto f = ConfigFile::parse("lio:\n  voxel_size_m: abc\n", "a.yaml");
    ToyLioConfig c;
    EXPECT_THROW(c.load(f.root().section("lio")), ConfigError);
  }
  {
    auto f = ConfigFile::parse("lio:\n  voxel_size_m: -1\n", "a.yaml");
    ToyLioConfig c;
    try {
      c.load(f.root().section("lio"));
      FAIL();
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("lio.voxel_size_m: must be > 0"), std::string::npos) << e.what();
    }
  }
  {
    auto f = ConfigFile::parse("lio:\n  voxel_size_m: 1\n  T_imu_lidar: [1, 2, 3]\n", "a.yaml");
    ToyLioConfig c;
    EXPECT_THROW(c.load(f.root().section("lio")), ConfigError);
  }
  {
    auto f = ConfigFile::parse("lio: 5\n", "a.yaml");
    EXPECT_THROW(f.root().section("lio"), ConfigError);
  }
  EXPECT_THROW(ConfigFile::parse("a: [1, 2\n", "bad.yaml"), ConfigError);
  EXPECT_THROW(ConfigFile::load("/nonexistent/livo.yaml"), ConfigError);
}

// ---- timing ----

TEST(Timing, SummaryStatistics) {
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(i);
  const auto s = summarize(v);
  EXPECT_EQ(s.count, 100u);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  EXPECT_DOUBLE_EQ(s.median, 50.5);
  EXPECT_DOUBLE_EQ(s.p95, 95.0);
  EXPECT_DOUBLE_EQ(s.max, 100.0);
  EXPECT_EQ(summarize({}).count, 0u);
}

TEST(Timing, PeakRssIsReadAndGrowsWithTouchedMemory) {
  const auto before = peakRssBytes();
  ASSERT_GT(before, 0u);
  std::vector<char> big(64 << 20, 1);  // 64 MiB, touched
  EXPECT_GE(peakRssBytes(), before + (32u << 20)) << static_cast<int>(big[12345]);
}

// fromSeconds is an inline copy of std::llround's rounding (halves away from zero): the oracle is llround
// itself, on halves, negatives, float offsets as stored in LidarPoint, huge values and NaN.
TEST(Types, FromSecondsRoundsAsLlround) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> wide(-1e7, 1e7);
  std::uniform_real_distribution<float> offset(-0.2f, 0.2f);
  std::vector<double> xs = {0.0, -0.0, 0.5e-6, -0.5e-6, 1.5e-6, -1.5e-6, 2.5e-6, 0.49999999999999994e-6,
                            1.2345675, -1.2345675, 4.5e12, -4.5e12, 1e13, 9.1e12, -9.3e12, 1e300, -1e300};
  for (int i = 0; i < 200000; ++i) {
    xs.push_back(wide(rng));
    xs.push_back(static_cast<double>(offset(rng)));
    xs.push_back(std::floor(wide(rng)) * 1e-6 + 0.5e-6);  // exact halves of a microsecond (up to s * 1e6 rounding)
  }
  for (double x : xs) ASSERT_EQ(fromSeconds(x), static_cast<Utime>(std::llround(x * 1e6))) << x;
  EXPECT_EQ(fromSeconds(std::nan("")), static_cast<Utime>(std::llround(std::nan(""))));
}

// Quantiles of the histogram against the sorted samples (the oracle): within half a bin, with values
// beyond the last bin, negatives and NaN counted at the ends.
TEST(MsHistogram, QuantilesMatchTheSortedSamplesWithinHalfABin) {
  MsHistogram empty;
  EXPECT_EQ(empty.quantile(0.5), -1.0);
  std::mt19937 rng(3);
  std::exponential_distribution<double> lag(1.0 / 20.0);  // mean 20 ms, a long tail
  MsHistogram h(0.5, 200.0);
  std::vector<double> xs;
  for (int i = 0; i < 20000; ++i) {
    const double x = lag(rng);
    xs.push_back(x);
    h.add(x);
  }
  std::sort(xs.begin(), xs.end());
  ASSERT_EQ(h.count(), xs.size());
  for (double q : {0.1, 0.5, 0.9, 0.95, 0.99}) {
    const double truth = xs[std::size_t(std::ceil(q * double(xs.size()))) - 1];
    if (truth < 199.5) EXPECT_NEAR(h.quantile(q), truth, 0.25 + 1e-9) << "q " << q;
  }
  MsHistogram ends(1.0, 10.0);
  ends.add(-3.0);
  ends.add(std::nan(""));
  ends.add(1e9);
  EXPECT_EQ(ends.quantile(0.5), 0.5);    // two of three in the first bin
  EXPECT_EQ(ends.quantile(1.0), 10.5);   // the last bin holds everything beyond 10 ms
}

TEST(Types, TimeConversionsAndScanEnd) {
  EXPECT_EQ(fromSeconds(1.2345675), 1234568);
  LidarScan s;
  s.utime = 1000000;
  EXPECT_EQ(s.endUtime(), 1000000);
  s.points.resize(2);
  s.points[1].time_offset_s = 0.1f;
  EXPECT_EQ(s.endUtime(), 1100000);
}

// Every mode's name parses back to it; an unknown name is refused with the valid names, by the
// parser (std::invalid_argument) and where a config reads it (ConfigError naming the key).
template <class Mode>
void expectRoundTrips(std::initializer_list<Mode> all, const std::string& names) {
  for (Mode m : all) EXPECT_EQ(parseMode<Mode>(toString(m)), m) << toString(m);
  EXPECT_EQ(modeNames<Mode>(), names);
  Mode kept = *all.begin();
  EXPECT_FALSE(parseMode(std::string("nonsense"), kept));
  EXPECT_EQ(kept, *all.begin());
  EXPECT_THROW(parseMode<Mode>("Nonsense"), std::invalid_argument);
}

TEST(Modes, NamesRoundTripAndUnknownNamesAreRefused) {
  expectRoundTrips({LidarModel::Avia, LidarModel::Mid360, LidarModel::Spinning32, LidarModel::Generic},
                   "avia, mid360, spinning32 or generic");
  expectRoundTrips({CameraKind::Pinhole, CameraKind::Equidistant}, "pinhole or equidistant");
  expectRoundTrips({Environment::Indoor, Environment::Outdoor}, "indoor or outdoor");
  expectRoundTrips({VisualMode::Adaptive, VisualMode::All, VisualMode::Off}, "adaptive, all or off");
  expectRoundTrips({MapMode::Hybrid, MapMode::Global}, "hybrid or global");
  try {
    parseMode<VisualMode>("every");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "visual mode must be adaptive, all or off, got 'every'");
  }

  auto file = ConfigFile::parse("environment: outdoor\nlidar:\n  model: velodyne\n", "rig.yaml");
  Environment env = Environment::Indoor;
  readMode(file.root(), "environment", env);
  EXPECT_EQ(env, Environment::Outdoor);
  LidarModel lidar = LidarModel::Generic;
  try {
    requireMode(file.root().section("lidar"), "model", lidar);
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "rig.yaml: lidar.model: must be avia, mid360, spinning32 or generic, got 'velodyne'");
  }
  EXPECT_THROW(requireMode(ConfigFile::parse("{}", "rig.yaml").root(), "model", lidar), ConfigError);
  CameraKind absent = CameraKind::Equidistant;  // a missing optional key keeps the default
  readMode(ConfigFile::parse("{}", "rig.yaml").root(), "model", absent);
  EXPECT_EQ(absent, CameraKind::Equidistant);
}
