// The restart protocol's messages (filter_state_t, resume_request_t, resume_t; libs/io
// resume_messages.hpp): struct -> message -> bytes -> decode -> struct round trips with random values
// (fixed seed), validation errors that name the field, and the byte-level precheck refusing a count
// the bytes cannot hold before anything is allocated.
#include "livo/io/resume_messages.hpp"

#include <livo/resume_request_t.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace livo;

namespace {

std::mt19937 rng(20261206);
double uni(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); }
Vec3 randVec3(double s) { return Vec3(uni(-s, s), uni(-s, s), uni(-s, s)); }

FilterSnapshot randSnapshot() {
  FilterSnapshot s;
  NavState& x = s.filter.state;
  x.utime = 1'700'000'000'000'000 + std::int64_t(uni(0, 1e9));
  x.R_world_imu = expSO3(randVec3(3.0));
  x.p_world_imu = randVec3(300.0);
  x.v_world = randVec3(10.0);
  x.bg = randVec3(0.01);
  x.ba = randVec3(0.1);
  x.g_world = Vec3(0, 0, -9.81) + randVec3(0.1);
  x.inv_exposure = uni(0.5, 2.0);
  x.time_offset_s = uni(-0.01, 0.01);
  const StateCov A = StateCov::NullaryExpr([] { return uni(-0.1, 0.1); });
  s.filter.P = A * A.transpose();
  s.filter.accel_scale = 9.81;
  s.frames = 1234;
  return s;
}

void expectError(const Validation& v, const std::string& prefix, const std::string& detail = "") {
  ASSERT_FALSE(v) << "expected an error at " << prefix;
  EXPECT_EQ(v.error.rfind(prefix, 0), 0u) << v.error;
  EXPECT_NE(v.error.find(detail), std::string::npos) << v.error;
}

ResumeAnswer randAnswer(int n_imu) {
  ResumeAnswer a;
  a.request_id = 77;
  a.have_state = true;
  a.snapshot = randSnapshot();
  for (int i = 0; i < n_imu; ++i) {
    ImuSample s;
    s.utime = a.snapshot.filter.state.utime + 5000 * (i + 1);
    s.gyro = randVec3(2.0);
    s.accel = randVec3(20.0);
    a.imu.push_back(s);
  }
  a.imu_dropped = 3;
  return a;
}

}  // namespace

TEST(ResumeMessages, RoundTripKeepsTheWholeFilterStateAndTheSamples) {
  const ResumeAnswer a = randAnswer(50);
  const auto buf = encode(toMsg(a));
  livo::resume_t m{};
  ASSERT_TRUE(decode(buf.data(), buf.size(), m));
  ResumeAnswer b;
  ASSERT_TRUE(fromMsg(m, b)) << fromMsg(m, b).error;
  EXPECT_EQ(b.request_id, 77);
  ASSERT_TRUE(b.have_state);
  const NavState &x = a.snapshot.filter.state, &y = b.snapshot.filter.state;
  EXPECT_EQ(y.utime, x.utime);
  EXPECT_LT((y.p_world_imu - x.p_world_imu).norm(), 1e-9);
  EXPECT_LT((y.R_world_imu - x.R_world_imu).norm(), 1e-12);
  EXPECT_EQ(y.v_world, x.v_world);
  EXPECT_EQ(y.bg, x.bg);
  EXPECT_EQ(y.ba, x.ba);
  EXPECT_EQ(y.g_world, x.g_world);
  EXPECT_EQ(y.inv_exposure, x.inv_exposure);
  EXPECT_EQ(y.time_offset_s, x.time_offset_s);
  EXPECT_LT((b.snapshot.filter.P - a.snapshot.filter.P).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(b.snapshot.filter.accel_scale, 9.81);
  EXPECT_EQ(b.snapshot.frames, 1234);
  ASSERT_EQ(b.imu.size(), 50u);
  EXPECT_EQ(b.imu[17].utime, a.imu[17].utime);
  EXPECT_EQ(b.imu[17].accel, a.imu[17].accel);
  EXPECT_EQ(b.imu_dropped, 3);

  // No state: only the request id matters.
  ResumeAnswer none;
  none.request_id = 5;
  ResumeAnswer c;
  ASSERT_TRUE(fromMsg(toMsg(none), c));
  EXPECT_FALSE(c.have_state);
  EXPECT_TRUE(c.imu.empty());

  livo::resume_request_t q{};
  q.request_id = -9;
  const auto qb = encode(q);
  livo::resume_request_t qd{};
  ASSERT_TRUE(decode(qb.data(), qb.size(), qd));
  EXPECT_EQ(qd.request_id, -9);
}

TEST(ResumeMessages, ValidationNamesTheField) {
  const livo::filter_state_t good = toMsg(randSnapshot());
  FilterSnapshot out;
  ASSERT_TRUE(fromMsg(good, out));
  livo::filter_state_t m = good;
  m.velocity[2] = std::nan("");
  expectError(fromMsg(m, out), "filter_state_t.velocity[2]");
  m = good; m.accel_scale = 0;
  expectError(fromMsg(m, out), "filter_state_t.accel_scale", "(0, 20]");
  m = good; m.covariance[4][4] = -1;
  expectError(fromMsg(m, out), "filter_state_t.covariance", "negative variance");
  m = good; m.covariance[2][9] += 1.0;
  expectError(fromMsg(m, out), "filter_state_t.covariance", "not symmetric");
  m = good; for (double& q : m.orientation) q = 0;
  expectError(fromMsg(m, out), "filter_state_t.orientation");
  m = good; m.inv_exposure = 0;
  expectError(fromMsg(m, out), "filter_state_t.inv_exposure");
  m = good; m.frames = -1;
  expectError(fromMsg(m, out), "filter_state_t.frames");

  const livo::resume_t rg = toMsg(randAnswer(4));
  ResumeAnswer a;
  a.request_id = 4242;
  livo::resume_t r = rg;
  r.imu[2].utime = r.imu[1].utime;  // not after the previous sample
  expectError(fromMsg(r, a), "resume_t.imu[2].utime", "not after");
  EXPECT_EQ(a.request_id, 4242) << "untouched on failure";
  r = rg; r.imu[0].utime = r.state.utime;  // not after the state
  expectError(fromMsg(r, a), "resume_t.imu[0].utime", "not after");
  r = rg; r.imu[3].linear_acceleration[1] = INFINITY;
  expectError(fromMsg(r, a), "resume_t.imu[3]");
  r = rg; r.imu_dropped = -2;
  expectError(fromMsg(r, a), "resume_t.imu_dropped");
  r = rg; r.state.gravity[0] = std::nan("");
  expectError(fromMsg(r, a), "resume_t.state.filter_state_t.gravity[0]");
  r = rg; r.num_imu = 3;
  expectError(fromMsg(r, a), "resume_t.imu", "num_imu declares 3");
  MessageLimits lim;
  lim.max_imu_per_frame = 3;
  expectError(fromMsg(rg, a, lim), "resume_t.num_imu", "max_imu_per_frame");
}

TEST(ResumeMessages, PrecheckRefusesACountTheBytesCannotHold) {
  livo::resume_t m = toMsg(randAnswer(3));
  m.num_imu = 3;
  auto buf = encode(m);
  // num_imu sits after the 8-byte hash, request_id, have_state and the fixed-size state.
  const std::size_t at = 8 + 8 + 1 + std::size_t(livo::filter_state_t()._getEncodedSizeNoHash());
  ASSERT_EQ(buf[at + 3], 3);
  buf[at] = 0x00; buf[at + 1] = 0x10; buf[at + 2] = 0x00; buf[at + 3] = 0x00;  // 1 M samples declared
  livo::resume_t d{};
  expectError(decode(buf.data(), buf.size(), d), "resume_t.num_imu", "exceeds the limit");
  MessageLimits big;
  big.max_imu_per_frame = 1 << 22;
  expectError(decode(buf.data(), buf.size(), d, big), "resume_t.num_imu", "bytes remain");
  livo::resume_t e{};
  auto short_buf = encode(toMsg(randAnswer(3)));
  short_buf.resize(short_buf.size() - 1);  // the last byte of config_mismatch (its NUL)
  expectError(decode(short_buf.data(), short_buf.size(), e), "resume_t.config_mismatch", "only 0 bytes remain");
  short_buf.resize(short_buf.size() - 5);  // then the string's length and the last byte of imu_dropped
  expectError(decode(short_buf.data(), short_buf.size(), e), "resume_t.imu_dropped", "message ends early");
}
