#include "livo/eval/tum.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace livo {
namespace {

[[noreturn]] void fail(const std::string& name, std::size_t line, const std::string& what) {
  throw std::runtime_error(name + ":" + std::to_string(line) + ": " + what);
}

// Parses one whole token as a double; false on trailing garbage or an empty token.
bool parseDouble(const std::string& token, double& out) {
  if (token.empty()) return false;
  errno = 0;
  char* end = nullptr;
  out = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size() && errno != ERANGE;
}

const char* kColumnNames[8] = {"t", "x", "y", "z", "qx", "qy", "qz", "qw"};

}  // namespace

Trajectory readTum(std::istream& in, const std::string& name) {
  Trajectory traj;
  std::string text;
  std::size_t line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::istringstream tokens(text);
    std::string token;
    if (!(tokens >> token) || token[0] == '#') continue;  // blank line or comment

    double v[8];
    int n = 0;
    do {
      if (n == 8) fail(name, line_no, "expected 8 columns 't x y z qx qy qz qw', got more");
      if (!parseDouble(token, v[n]))
        fail(name, line_no, std::string("column '") + kColumnNames[n] + "': not a number: '" + token + "'");
      if (!std::isfinite(v[n]))
        fail(name, line_no, std::string("column '") + kColumnNames[n] + "': value is not finite");
      ++n;
    } while (tokens >> token);
    if (n != 8)
      fail(name, line_no, "expected 8 columns 't x y z qx qy qz qw', got " + std::to_string(n));

    const double qnorm = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
    if (std::abs(qnorm - 1.0) > kTumQuatNormTolerance)
      fail(name, line_no, "quaternion norm is " + std::to_string(qnorm) + ", expected 1");
    if (!traj.empty() && !(v[0] > traj.back().t)) {
      std::ostringstream msg;
      msg.precision(17);
      msg << "time " << v[0] << " is not after the previous time " << traj.back().t
          << " (times must be strictly increasing)";
      fail(name, line_no, msg.str());
    }
    StampedPose pose;
    pose.t = v[0];
    pose.T_world_body = poseFromArray(v + 1);
    traj.push_back(pose);
  }
  if (in.bad()) throw std::runtime_error(name + ": read error");
  if (traj.empty()) throw std::runtime_error(name + ": no poses (empty file or only comments)");
  return traj;
}

Trajectory readTum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open trajectory file");
  return readTum(in, path);
}

void writeTum(std::ostream& out, const StampedPose& pose) {
  const std::array<double, 7> a = poseToArray(pose.T_world_body);
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", pose.t, a[0], a[1], a[2],
                a[3], a[4], a[5], a[6]);
  out << buf;
}

ContinuedFile continueLineFile(const std::string& path) {
  ContinuedFile f;
  std::error_code ec;
  f.exists = std::filesystem::exists(path, ec) && std::filesystem::file_size(path, ec) > 0;
  if (!f.exists) return f;
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t nl = text.rfind('\n');
  const std::size_t keep = nl == std::string::npos ? 0 : nl + 1;
  if (keep < text.size()) {
    std::filesystem::resize_file(path, keep, ec);
    if (ec) throw std::runtime_error(path + ": cannot cut its partial last line: " + ec.message());
  }
  std::istringstream lines(text.substr(0, keep));
  std::string line;
  while (std::getline(lines, line)) {
    double t = 0;
    if (line.empty() || line[0] == '#' || !(std::istringstream(line) >> t)) continue;
    f.last_t = std::max(f.last_t, t);
    ++f.rows;
  }
  return f;
}

TumWriter::TumWriter(const std::string& path, bool append) : path_(path) {
  if (append) {
    const ContinuedFile f = continueLineFile(path);
    if (f.exists) {
      last_t_ = f.last_t;
      previous_count_ = f.rows;
      out_.open(path, std::ios::out | std::ios::app);
      if (!out_) throw std::runtime_error(path + ": cannot open trajectory file for appending");
      return;
    }
  }
  out_.open(path, std::ios::out | std::ios::trunc);
  if (!out_) throw std::runtime_error(path + ": cannot open trajectory file for writing");
  out_ << "# t x y z qx qy qz qw (T_world_body, t in s)\n" << std::flush;
  if (!out_) throw std::runtime_error(path + ": write failed");
}

void TumWriter::write(const StampedPose& pose) {
  if (!(pose.t > last_t_)) {  // at or before the last line: the file keeps strictly increasing time
    ++skipped_;
    return;
  }
  last_t_ = pose.t;
  writeTum(out_, pose);
  out_.flush();
  if (!out_) throw std::runtime_error(path_ + ": write failed after " + std::to_string(count_) + " poses");
  ++count_;
}

}  // namespace livo
