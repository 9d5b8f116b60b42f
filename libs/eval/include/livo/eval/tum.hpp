// TUM trajectory files: one pose per line, "t x y z qx qy qz qw", t in seconds, the pose T_world_body
// (maps body-frame points into the world frame). Lines starting with '#' and blank lines are skipped.
#pragma once

#include "livo/common/so3.hpp"

#include <fstream>
#include <ostream>
#include <limits>
#include <string>
#include <vector>

namespace livo {

struct StampedPose {
  double t = 0.0;  ///< seconds
  Pose T_world_body = Pose::Identity();
};
using Trajectory = std::vector<StampedPose>;

/// Reads a TUM file. Throws std::runtime_error naming "file:line" on a malformed row (not exactly
/// 8 numbers, non-finite values, a quaternion whose norm is not within `kTumQuatNormTolerance` of 1),
/// on times that are not strictly increasing, and naming the file when it cannot be opened or holds
/// no pose. Quaternions are normalised on read.
Trajectory readTum(const std::string& path);
/// Same from a stream; `name` stands for the file name in error messages.
Trajectory readTum(std::istream& in, const std::string& name);

/// Accepted |‖q‖ - 1| on read (files written with 4 decimals still pass; a typo does not).
constexpr double kTumQuatNormTolerance = 1e-2;

/// Writes one line "t x y z qx qy qz qw\n": t with 9 decimals, position and quaternion with 9
/// decimals (nm / 1e-9 resolution, more than any estimator needs). qw >= 0.
void writeTum(std::ostream& out, const StampedPose& pose);

/// A line file continued by a restarted writer (trajectory.tum, frames.csv): a last line cut short by
/// a kill is cut off the file; `rows` counts its complete lines whose first field is a number (headers
/// and '#' lines are not rows) and `last_t` is the largest such number (-inf when none). `exists`: the
/// file was there and not empty (a writer continues it; else it starts a new one).
struct ContinuedFile {
  bool exists = false;
  std::size_t rows = 0;
  double last_t = -std::numeric_limits<double>::infinity();
};
ContinuedFile continueLineFile(const std::string& path);

/// Appends poses to a TUM file, one flushed line per pose, so that a killed process loses at most the
/// pose being written. Writes a '#' header line first.
class TumWriter {
 public:
  /// Opens (truncates) `path`; throws std::runtime_error naming the file when it cannot. With `append`
  /// an existing file is continued instead (a restarted writer): a last line cut short by a kill is
  /// removed, and poses at or before the file's last time are skipped (counted), so the file stays in
  /// strictly increasing time.
  explicit TumWriter(const std::string& path, bool append = false);
  /// Writes and flushes one line; throws std::runtime_error when the write fails (disk full).
  void write(const StampedPose& pose);
  void write(double t, const Pose& T_world_body) { write(StampedPose{t, T_world_body}); }
  /// Poses written by this writer (not those the file held before).
  std::size_t count() const { return count_; }
  /// Append mode: poses the file held when opened, its last time (-inf when none), poses skipped since.
  std::size_t previousCount() const { return previous_count_; }
  double lastTime() const { return last_t_; }
  std::size_t skipped() const { return skipped_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
  std::size_t count_ = 0;
  std::size_t previous_count_ = 0, skipped_ = 0;
  double last_t_ = -std::numeric_limits<double>::infinity();
};

}  // namespace livo
