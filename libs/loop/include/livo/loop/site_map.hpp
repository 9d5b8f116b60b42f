// A map to come back to: the loop closer's keyframes saved at the end of a run (livo-run --save-map,
// livo-loop --save-map) and loaded by a later run to localise in (livo-run --prior-map). The index holds
// every keyframe's time, map-frame pose and place descriptor (searched whole: about 7.5 KB of memory a
// keyframe with the default 20 x 60 descriptor); the keyframes' points are grouped into square tiles of the map's x-y plane,
// one file each, read when a keyframe of the tile is verified and dropped (least recently used first)
// beyond a memory budget, so the points in memory stay bounded whatever the site's size.
//
// DIR/site.bin:  "LIVOSITE", u32 version 1, u32 0x01020304 (byte order), f64 tile_m, i32 rings,
//                i32 sectors, f64 descriptor min / max range and height cap, u64 keyframes, then per
//                keyframe: i64 utime, f64 pose[7] (x y z qx qy qz qw, the keyframe frame in the map),
//                i32 tile x, tile y, u64 offset and count (points in the tile file), f64 step (m per
//                unit of the packed points), f32 cells[rings * sectors].
// DIR/tiles/tile_X_Y.bin: "LIVOTILE", then int16 x y z triples (the keyframes' points in their frames).
#pragma once

#include "livo/common/so3.hpp"
#include "livo/common/types.hpp"
#include "livo/loop/packed_points.hpp"
#include "livo/loop/place_descriptor.hpp"

#include <cstdint>
#include <list>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace livo {

class LoopCloser;

/// Writes the loop closer's keyframes (map-frame poses of its last solve) as a site map into `dir`
/// (created; an existing site map there is replaced). Throws std::runtime_error naming the path.
void saveSiteMap(const std::string& dir, const LoopCloser& closer, const PlaceDescriptorConfig& descriptor,
                 double tile_m);

struct SiteKeyframe {
  Utime utime = 0;
  Pose T_map = Pose::Identity();  ///< the keyframe frame (keyframeFrame of its body pose) in the map
  std::int32_t tile_x = 0, tile_y = 0;
  std::uint64_t offset = 0, count = 0;  ///< its points in the tile file, in points
  double step = 0.01;
  PlaceDescriptor descriptor;
};

class SiteMap {
 public:
  /// Reads DIR/site.bin (not the tiles). `budget_mb` bounds the tiles' points held (0: no bound; the
  /// tile being read always stays). `descriptor` is the run's descriptor: a site map made with another
  /// one cannot be searched and is refused. Throws std::runtime_error naming the file and the problem.
  SiteMap(const std::string& dir, double budget_mb, const PlaceDescriptorConfig& descriptor);

  std::size_t size() const { return keyframes_.size(); }
  const SiteKeyframe& keyframe(int i) const { return keyframes_.at(static_cast<std::size_t>(i)); }
  /// Keyframe i's points in its frame; reads its tile when not held. Throws std::runtime_error naming
  /// the tile file when it is missing or shorter than the index says.
  std::vector<Vec3> points(int i);

  std::size_t tilesHeld() const { return tiles_.size(); }
  std::size_t tileReads() const { return tile_reads_; }
  std::size_t bytesHeld() const { return bytes_held_; }
  std::size_t indexBytes() const;
  const std::string& dir() const { return dir_; }

 private:
  using TileKey = std::pair<std::int32_t, std::int32_t>;
  struct Tile {
    std::vector<std::array<std::int16_t, 3>> points;
    std::list<TileKey>::iterator lru;
  };
  const Tile& tile(const TileKey& key);

  std::string dir_;
  double tile_m_ = 100.0;
  std::size_t budget_bytes_ = 0;
  std::vector<SiteKeyframe> keyframes_;
  std::map<TileKey, Tile> tiles_;
  std::list<TileKey> lru_;  ///< most recently used first
  std::size_t bytes_held_ = 0, tile_reads_ = 0;
};

}  // namespace livo
