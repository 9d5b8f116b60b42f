// The keyframes' points with a memory budget: the newest stay in memory, older ones go to a spill file
// (appended, read back when a loop candidate needs them) once the points in memory exceed the budget.
// A loop closer over a long run keeps its memory bounded this way without forgetting old places.
#pragma once

#include "livo/loop/packed_points.hpp"

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace livo {

class KeyframeStore {
 public:
  /// `budget_bytes` 0: everything in memory. The spill file is created in `spill_dir` (default: the
  /// system's temporary directory) when first needed and removed by the destructor.
  explicit KeyframeStore(std::size_t budget_bytes = 0, std::string spill_dir = "");
  ~KeyframeStore();
  KeyframeStore(const KeyframeStore&) = delete;
  KeyframeStore& operator=(const KeyframeStore&) = delete;

  /// Stores a keyframe's points; returns its index. Throws std::runtime_error when the spill file
  /// cannot be written.
  int add(PackedPoints points);
  /// The points of keyframe `id` (from memory or the spill file).
  PackedPoints get(int id) const;
  std::size_t size() const { return entries_.size(); }
  std::size_t memoryBytes() const { return memory_bytes_; }
  std::size_t spilledBytes() const { return spilled_bytes_; }
  std::size_t spilledKeyframes() const { return spilled_; }
  const std::string& spillPath() const { return spill_path_; }

 private:
  struct Entry {
    PackedPoints points;        // empty once spilled
    std::uint64_t offset = 0;   // in the spill file
    std::uint64_t count = 0;
    double step = 0.0;
    bool spilled = false;
  };
  std::size_t budget_;
  std::string spill_dir_, spill_path_;
  mutable std::fstream file_;
  std::vector<Entry> entries_;
  std::size_t next_to_spill_ = 0;
  std::size_t memory_bytes_ = 0, spilled_bytes_ = 0, spilled_ = 0;
  void spillOldest();
};

}  // namespace livo
