#include "livo/loop/keyframe_store.hpp"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <stdexcept>

namespace livo {

namespace {
std::atomic<int> g_store_count{0};
}

KeyframeStore::KeyframeStore(std::size_t budget_bytes, std::string spill_dir)
    : budget_(budget_bytes), spill_dir_(std::move(spill_dir)) {}

KeyframeStore::~KeyframeStore() {
  if (file_.is_open()) file_.close();
  if (!spill_path_.empty()) {
    std::error_code ec;
    std::filesystem::remove(spill_path_, ec);
  }
}

int KeyframeStore::add(PackedPoints points) {
  memory_bytes_ += points.bytes();
  entries_.push_back(Entry{std::move(points), 0, 0, 0.0, false});
  // The newest keyframe always stays: a budget smaller than one keyframe spills all the others.
  while (budget_ > 0 && memory_bytes_ > budget_ && next_to_spill_ + 1 < entries_.size()) spillOldest();
  return static_cast<int>(entries_.size()) - 1;
}

void KeyframeStore::spillOldest() {
  Entry& e = entries_[next_to_spill_++];
  if (!file_.is_open()) {
    const std::filesystem::path dir = spill_dir_.empty() ? std::filesystem::temp_directory_path() : std::filesystem::path(spill_dir_);
    spill_path_ = (dir / ("livo_keyframes_" + std::to_string(::getpid()) + "_" + std::to_string(g_store_count++) + ".bin")).string();
    file_.open(spill_path_, std::ios::binary | std::ios::in | std::ios::out | std::ios::trunc);
    if (!file_) throw std::runtime_error("loop closer: cannot create the keyframe spill file " + spill_path_);
  }
  const auto& q = e.points.packed();
  file_.seekp(0, std::ios::end);
  e.offset = static_cast<std::uint64_t>(file_.tellp());
  e.count = q.size();
  e.step = e.points.step();
  file_.write(reinterpret_cast<const char*>(q.data()), static_cast<std::streamsize>(q.size() * sizeof(q[0])));
  file_.flush();
  if (!file_) throw std::runtime_error("loop closer: cannot write the keyframe spill file " + spill_path_ + " (disk full?)");
  memory_bytes_ -= e.points.bytes();
  spilled_bytes_ += q.size() * sizeof(q[0]);
  ++spilled_;
  e.points = PackedPoints();
  e.spilled = true;
}

PackedPoints KeyframeStore::get(int id) const {
  const Entry& e = entries_.at(static_cast<std::size_t>(id));
  if (!e.spilled) return e.points;
  std::vector<std::array<std::int16_t, 3>> q(e.count);
  file_.seekg(static_cast<std::streamoff>(e.offset));
  file_.read(reinterpret_cast<char*>(q.data()), static_cast<std::streamsize>(q.size() * sizeof(q[0])));
  if (!file_) {
    file_.clear();
    throw std::runtime_error("loop closer: cannot read keyframe " + std::to_string(id) + " back from " + spill_path_);
  }
  return PackedPoints(std::move(q), e.step);
}

}  // namespace livo
