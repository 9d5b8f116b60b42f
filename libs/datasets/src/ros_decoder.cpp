// Decoding by type with the scan rules, and the IMU acceleration unit (ros_input.hpp): shared by the bag
// converter and the live bridge.
#include "livo/datasets/ros_input.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace livo {

void checkRosInputOptions(const RosInputOptions& opt) {
  if (!(opt.max_scan_span_s > 0)) throw DatasetError("--max-scan-span must be positive");
  if (opt.mono16_bits != 0 && (opt.mono16_bits < 9 || opt.mono16_bits > 16))
    throw DatasetError("--mono16-bits must be 9..16 (or 0 to keep GRAY16)");
  if (opt.imu_unit_samples < 1) throw DatasetError("imu_unit_samples must be at least 1");
  if (!(opt.gravity_m_s2 > 0) || !std::isfinite(opt.gravity_m_s2)) throw DatasetError("--gravity must be positive");
}

RosDecoder::RosDecoder(const RosInputOptions& opt) : opt_(opt) {
  checkRosInputOptions(opt);
  for (RosDecodeOptions* d : {&generic_, &livox_}) {
    d->point_time_field = opt.point_time_field;
    d->mono16_bits = opt.mono16_bits;
  }
  generic_.sensor = opt.sensor.empty() ? "generic" : opt.sensor;
  livox_.sensor = opt.sensor.empty() ? "avia" : opt.sensor;
  max_span_ns_ = std::llround(opt.max_scan_span_s * 1e9);
}

std::optional<RosPayload> RosDecoder::decode(RosType type, const std::uint8_t* data, std::size_t size) {
  switch (type) {
    case RosType::Imu: return RosPayload(decodeRosImu(data, size));
    case RosType::PointCloud2: return scan(decodeRosPointCloud2(data, size, generic_));
    case RosType::LivoxCustomMsg: return scan(decodeLivoxCustomMsg(data, size, livox_));
    case RosType::Image: return RosPayload(decodeRosImage(data, size, generic_));
    case RosType::CompressedImage: return RosPayload(decodeRosCompressedImage(data, size, generic_));
    case RosType::Unknown: break;
  }
  throw DatasetError(std::string("not a supported message type (supported: ") + rosSupportedTypes() + ")");
}

std::optional<RosPayload> RosDecoder::scan(DecodedScan ds) {
  counts_.nonfinite_points += ds.dropped_nonfinite;
  if (ds.time_field.empty()) ++counts_.untimed_scans;
  if (ds.scan.points.empty()) {
    ++counts_.empty_scans;
    return std::nullopt;
  }
  if (ds.span_ns > max_span_ns_) {
    if (counts_.long_scans++ == 0)
      counts_.long_example = "points span " + std::to_string(ds.span_ns * 1e-9) + " s (time field '" + ds.time_field + "')";
    return std::nullopt;
  }
  return RosPayload(std::move(ds.scan));
}

double detectAccelScale(const std::vector<double>& accel_norms, const RosInputOptions& opt, std::string& note) {
  char buf[200];
  if (opt.imu_accel_unit == AccelUnit::G) {
    std::snprintf(buf, sizeof buf, "acceleration in g (--imu-accel-unit g): multiplied by %.5f", opt.gravity_m_s2);
    note = buf;
    return opt.gravity_m_s2;
  }
  if (opt.imu_accel_unit == AccelUnit::MetresPerSecond2) {
    note = "acceleration in m/s^2 (--imu-accel-unit mps2)";
    return 1.0;
  }
  if (accel_norms.empty()) {
    note = "no IMU samples: acceleration unit not checked";
    return 1.0;
  }
  std::vector<double> v = accel_norms;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  const double median = v[v.size() / 2];
  if (median >= 0.7 && median <= 1.3) {
    std::snprintf(buf, sizeof buf, "acceleration in g detected (median |a| %.3f over %zu samples): multiplied by %.5f",
                  median, v.size(), opt.gravity_m_s2);
    note = buf;
    return opt.gravity_m_s2;
  }
  if (median >= 7.0 && median <= 13.0)
    std::snprintf(buf, sizeof buf, "acceleration in m/s^2 (median |a| %.3f over %zu samples)", median, v.size());
  else
    std::snprintf(buf, sizeof buf,
                  "WARNING: median |a| %.3f over %zu samples is neither about 1 g nor about 9.8 m/s^2: kept as is",
                  median, v.size());
  note = buf;
  return 1.0;
}

ImuUnitGate::ImuUnitGate(const RosInputOptions& opt) : opt_(opt) {
  if (opt.imu_accel_unit != AccelUnit::Auto) {
    scale_ = detectAccelScale({}, opt_, note_);
    decided_ = true;
  }
}

void ImuUnitGate::push(const ImuSample& s, std::vector<ImuSample>& ready) {
  if (decided_) {
    ready.push_back(s);
    ready.back().accel *= scale_;
    return;
  }
  held_.push_back(s);
  if (static_cast<int>(held_.size()) >= opt_.imu_unit_samples) decide(ready);
}

void ImuUnitGate::finish(std::vector<ImuSample>& ready) {
  if (!decided_) decide(ready);
}

void ImuUnitGate::decide(std::vector<ImuSample>& ready) {
  std::vector<double> norms;
  norms.reserve(held_.size());
  for (const auto& s : held_) norms.push_back(s.accel.norm());
  scale_ = detectAccelScale(norms, opt_, note_);
  decided_ = true;
  for (auto& s : held_) {
    s.accel *= scale_;
    ready.push_back(s);
  }
  held_.clear();
  held_.shrink_to_fit();
}

}  // namespace livo
