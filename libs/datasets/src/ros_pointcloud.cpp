// sensor_msgs/PointCloud2 and livox_ros_driver CustomMsg -> LidarScan, with per-point times
// (conventions in ros_msgs.hpp).
#include "livo/datasets/ros_msgs.hpp"

#include "ros_buffer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace livo {

namespace {

// sensor_msgs/PointField datatypes.
enum : std::uint8_t { kInt8 = 1, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

int fieldBytes(std::uint8_t datatype) {
  switch (datatype) {
    case kInt8: case kUint8: return 1;
    case kInt16: case kUint16: return 2;
    case kInt32: case kUint32: case kFloat32: return 4;
    case kFloat64: return 8;
    default: return 0;
  }
}

bool isFloat(std::uint8_t datatype) { return datatype == kFloat32 || datatype == kFloat64; }

struct Field {
  std::string name;
  std::uint32_t offset = 0;
  std::uint8_t datatype = 0;
  std::uint32_t count = 0;
};

/// Reads one numeric field of a point record as a double (byte-swapped for big-endian clouds).
class FieldReader {
 public:
  FieldReader() = default;
  FieldReader(const Field& f, bool swap) : offset_(f.offset), type_(f.datatype), swap_(swap), valid_(true) {}
  bool valid() const { return valid_; }
  double operator()(const std::uint8_t* point) const {
    std::uint8_t raw[8];
    const int n = fieldBytes(type_);
    std::memcpy(raw, point + offset_, n);
    if (swap_) std::reverse(raw, raw + n);
    switch (type_) {
      case kInt8: return static_cast<std::int8_t>(raw[0]);
      case kUint8: return raw[0];
      case kInt16: return load<std::int16_t>(raw);
      case kUint16: return load<std::uint16_t>(raw);
      case kInt32: return load<std::int32_t>(raw);
      case kUint32: return load<std::uint32_t>(raw);
      case kFloat32: return load<float>(raw);
      default: return load<double>(raw);
    }
  }

 private:
  template <class T>
  static double load(const std::uint8_t* raw) {
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return static_cast<double>(v);
  }
  std::uint32_t offset_ = 0;
  std::uint8_t type_ = 0;
  bool swap_ = false;
  bool valid_ = false;
};

const Field* findField(const std::vector<Field>& fields, const char* name) {
  for (const auto& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

std::string fieldList(const std::vector<Field>& fields) {
  std::string s;
  for (const auto& f : fields) s += (s.empty() ? "" : ", ") + f.name;
  return s.empty() ? "none" : s;
}

std::int16_t toRing(double v) {
  return (v >= 0 && v <= std::numeric_limits<std::int16_t>::max()) ? static_cast<std::int16_t>(v) : -1;
}

/// Fills utime and time offsets from absolute point times in ns (scan start = earliest, floored to 1 us).
void applyPointTimes(DecodedScan& out, const std::vector<std::int64_t>& t_ns) {
  LidarScan& scan = out.scan;
  if (scan.points.empty()) {
    scan.utime = out.header_utime;
    return;
  }
  const auto [lo, hi] = std::minmax_element(t_ns.begin(), t_ns.end());
  scan.utime = nsToUtimeFloor(*lo);
  out.span_ns = *hi - *lo;
  const std::int64_t start_ns = scan.utime * 1000;
  for (std::size_t i = 0; i < scan.points.size(); ++i)
    scan.points[i].time_offset_s = static_cast<float>(static_cast<double>(t_ns[i] - start_ns) * 1e-9);
}

/// The fields of a PointCloud2 message, read and checked against the message length.
struct CloudMessage {
  std::int64_t header_ns = 0;
  std::uint32_t height = 0, width = 0;
  std::vector<Field> fields;
  bool big_endian = false;
  std::uint32_t point_step = 0, row_step = 0;
  std::uint32_t data_len = 0;
  const std::uint8_t* data = nullptr;

  std::uint64_t points() const { return static_cast<std::uint64_t>(width) * height; }
};

CloudMessage readCloudMessage(RosBuffer& b) {
  CloudMessage m;
  m.header_ns = b.header();
  m.height = b.get<std::uint32_t>("height");
  m.width = b.get<std::uint32_t>("width");
  // PointField: name (>= 4 bytes), offset uint32, datatype uint8, count uint32.
  const std::uint32_t nfields = b.count("fields", 4 + 4 + 1 + 4);
  m.fields.resize(nfields);
  for (auto& f : m.fields) {
    f.name = b.string("fields.name");
    f.offset = b.get<std::uint32_t>("fields.offset");
    f.datatype = b.get<std::uint8_t>("fields.datatype");
    f.count = b.get<std::uint32_t>("fields.count");
  }
  m.big_endian = b.get<std::uint8_t>("is_bigendian") != 0;
  m.point_step = b.get<std::uint32_t>("point_step");
  m.row_step = b.get<std::uint32_t>("row_step");
  m.data = b.bytes("data", m.data_len);
  b.get<std::uint8_t>("is_dense");
  b.finish();
  return m;
}

/// Every row inside the data, every point inside its row.
void checkRowLayout(const RosBuffer& b, const CloudMessage& m) {
  if (m.points() == 0) return;
  if (static_cast<std::uint64_t>(m.width) * m.point_step > m.row_step)
    b.fail("row_step", std::to_string(m.row_step) + " is smaller than width * point_step = " +
                           std::to_string(static_cast<std::uint64_t>(m.width) * m.point_step));
  if (static_cast<std::uint64_t>(m.row_step) * m.height > m.data_len)
    b.fail("data", "holds " + std::to_string(m.data_len) + " bytes but height * row_step = " +
                       std::to_string(static_cast<std::uint64_t>(m.row_step) * m.height));
}

/// Reader of the field `name`, checked to fit in the point record; invalid when absent and not `required`.
FieldReader fieldReader(const RosBuffer& b, const CloudMessage& m, const char* name, bool required) {
  const Field* f = findField(m.fields, name);
  if (!f) {
    if (required) b.fail("fields", std::string("no '") + name + "' field (fields: " + fieldList(m.fields) + ")");
    return {};
  }
  const int nb = fieldBytes(f->datatype);
  if (nb == 0)
    b.fail("fields", std::string("field '") + name + "' has unknown datatype " + std::to_string(f->datatype));
  if (static_cast<std::uint64_t>(f->offset) + nb > m.point_step)
    b.fail("fields", std::string("field '") + name + "' (offset " + std::to_string(f->offset) + ", " +
                         std::to_string(nb) + " bytes) does not fit in point_step " + std::to_string(m.point_step));
  return FieldReader(*f, m.big_endian);
}

/// Per-point time field (ros_msgs.hpp): named, none, or the first present of the usual names.
const Field* pointTimeField(const RosBuffer& b, const CloudMessage& m, const std::string& wanted) {
  const Field* tf = nullptr;
  if (wanted.empty()) {
    for (const char* name : {"time", "t", "timestamp", "offset_time"})
      if ((tf = findField(m.fields, name))) break;
  } else if (wanted != "none") {
    tf = findField(m.fields, wanted.c_str());
    if (!tf) b.fail("fields", "no point time field '" + wanted + "' (fields: " + fieldList(m.fields) + ")");
  }
  return tf;
}

/// Readers of the fields a LidarPoint takes; `time_field` is null when the points carry no time.
struct PointReaders {
  FieldReader x, y, z, intensity, ring, time;
  const Field* time_field = nullptr;
};

PointReaders pointReaders(const RosBuffer& b, const CloudMessage& m, const std::string& point_time_field) {
  PointReaders r;
  r.x = fieldReader(b, m, "x", true);
  r.y = fieldReader(b, m, "y", true);
  r.z = fieldReader(b, m, "z", true);
  for (const char* axis : {"x", "y", "z"})
    if (!isFloat(findField(m.fields, axis)->datatype))
      b.fail("fields", std::string("coordinate '") + axis + "' is not float32/float64");
  r.intensity = findField(m.fields, "intensity") ? fieldReader(b, m, "intensity", false)
                                                 : fieldReader(b, m, "reflectivity", false);
  r.ring = findField(m.fields, "ring") ? fieldReader(b, m, "ring", false) : fieldReader(b, m, "line", false);
  r.time_field = pointTimeField(b, m, point_time_field);
  if (r.time_field) r.time = fieldReader(b, m, r.time_field->name.c_str(), true);
  return r;
}

/// Points in message order (rows of an organized cloud one after the other) into out.scan, their raw
/// time values into `raw_t`; returns the largest |raw time|.
double readPoints(const RosBuffer& b, const CloudMessage& m, const PointReaders& rd, DecodedScan& out,
                  std::vector<double>& raw_t) {
  out.scan.points.reserve(static_cast<std::size_t>(m.points()));
  raw_t.reserve(rd.time_field ? static_cast<std::size_t>(m.points()) : 0);
  double max_abs_t = 0;
  for (std::uint32_t r = 0; r < m.height; ++r) {
    const std::uint8_t* row = m.data + static_cast<std::size_t>(r) * m.row_step;
    for (std::uint32_t c = 0; c < m.width; ++c) {
      const std::uint8_t* p = row + static_cast<std::size_t>(c) * m.point_step;
      LidarPoint pt;
      pt.p_lidar =
          Eigen::Vector3f(static_cast<float>(rd.x(p)), static_cast<float>(rd.y(p)), static_cast<float>(rd.z(p)));
      if (!pt.p_lidar.allFinite()) {
        ++out.dropped_nonfinite;
        continue;
      }
      if (rd.intensity.valid()) pt.intensity = static_cast<float>(rd.intensity(p));
      if (rd.ring.valid()) pt.ring = toRing(rd.ring(p));
      if (rd.time_field) {
        const double t = rd.time(p);
        if (!std::isfinite(t)) b.fail("data", "point time '" + rd.time_field->name + "' is not finite");
        raw_t.push_back(t);
        max_abs_t = std::max(max_abs_t, std::abs(t));
      }
      out.scan.points.push_back(pt);
    }
  }
  return max_abs_t;
}

/// Raw point times to ns: integer fields are ns, floating fields s (ns from 1e15 on); absolute from
/// 1e5 s on, else relative to the header stamp.
void applyRawPointTimes(DecodedScan& out, const Field& time_field, const std::vector<double>& raw_t,
                        double max_abs_t, std::int64_t header_ns) {
  const bool in_ns = !isFloat(time_field.datatype) || max_abs_t >= 1e15;
  const double to_ns = in_ns ? 1.0 : 1e9;
  out.absolute_times = max_abs_t * (in_ns ? 1e-9 : 1.0) >= 1e5;
  const std::int64_t base = out.absolute_times ? 0 : header_ns;
  std::vector<std::int64_t> t_ns(raw_t.size());
  for (std::size_t i = 0; i < raw_t.size(); ++i) t_ns[i] = base + std::llround(raw_t[i] * to_ns);
  applyPointTimes(out, t_ns);
}

}  // namespace

DecodedScan decodeRosPointCloud2(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt) {
  RosBuffer b(data, size, "sensor_msgs/PointCloud2");
  DecodedScan out;
  out.scan.sensor = opt.sensor;
  const CloudMessage m = readCloudMessage(b);
  out.header_utime = nsToUtimeRound(m.header_ns);
  // Layout checks before any point is read: every row inside the data, every used field inside the record.
  checkRowLayout(b, m);
  const PointReaders readers = pointReaders(b, m, opt.point_time_field);
  if (readers.time_field) out.time_field = readers.time_field->name;

  std::vector<double> raw_t;
  const double max_abs_t = readPoints(b, m, readers, out, raw_t);
  if (!readers.time_field) {  // no per-point times: utime = header.stamp, offsets 0
    out.scan.utime = out.header_utime;
    return out;
  }
  applyRawPointTimes(out, *readers.time_field, raw_t, max_abs_t, m.header_ns);
  return out;
}

DecodedScan decodeLivoxCustomMsg(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt) {
  RosBuffer b(data, size, "livox_ros_driver/CustomMsg");
  DecodedScan out;
  out.scan.sensor = opt.sensor;
  const std::int64_t header_ns = b.header();
  out.header_utime = nsToUtimeRound(header_ns);
  b.get<std::uint64_t>("timebase");
  b.get<std::uint32_t>("point_num");  // the points array's own length is authoritative
  b.get<std::uint8_t>("lidar_id");
  b.take(3, "rsvd");
  // CustomPoint: offset_time uint32 (ns), x, y, z float32, reflectivity, tag, line uint8 = 19 bytes.
  constexpr std::size_t kPointBytes = 4 + 3 * 4 + 3;
  const std::uint32_t n = b.count("points", kPointBytes);
  const std::uint8_t* p = b.take(static_cast<std::size_t>(n) * kPointBytes, "points");
  b.finish();
  out.time_field = "offset_time";
  out.scan.points.reserve(n);
  std::vector<std::int64_t> t_ns;
  t_ns.reserve(n);
  for (std::uint32_t i = 0; i < n; ++i, p += kPointBytes) {
    std::uint32_t offset_ns;
    float xyz[3];
    std::memcpy(&offset_ns, p, 4);
    std::memcpy(xyz, p + 4, 12);
    LidarPoint pt;
    pt.p_lidar = Eigen::Vector3f(xyz[0], xyz[1], xyz[2]);
    if (!pt.p_lidar.allFinite()) {
      ++out.dropped_nonfinite;
      continue;
    }
    pt.intensity = p[16];
    pt.ring = p[18];
    out.scan.points.push_back(pt);
    t_ns.push_back(header_ns + offset_ns);
  }
  applyPointTimes(out, t_ns);
  return out;
}

}  // namespace livo
