#include "livo/sim/world_gen.hpp"

#include "livo/sim/random.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace livo::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSlab = 0.2;  // wall / floor thickness

// Horizontal distance queries against the trajectory path (subsampled to <= 0.25 m spacing).
class PathClearance {
 public:
  explicit PathClearance(const std::vector<Vec3>& path) {
    double acc = 1e9;
    for (std::size_t i = 0; i < path.size(); ++i) {
      if (i > 0) acc += (path[i] - path[i - 1]).head<2>().norm();
      if (acc >= 0.25) {
        pts_.push_back(path[i].head<2>());
        acc = 0.0;
      }
    }
  }
  double distance(const Eigen::Vector2d& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& q : pts_) best = std::min(best, (q - p).squaredNorm());
    return std::sqrt(best) - 0.125;  // conservative by half the spacing
  }
  /// True when the yawed rectangle (centre, size x/y, yaw) stays `clearance` away from the path.
  bool clear(const Vec3& center, double sx, double sy, double yaw, double clearance) const {
    const Eigen::Vector2d c = center.head<2>();
    const double r = 0.5 * std::hypot(sx, sy);
    if (distance(c) >= r + clearance) return true;  // bounding circle clear
    // Otherwise test the rectangle against each path sample in the rectangle's frame.
    const double cy = std::cos(yaw), sny = std::sin(yaw);
    for (const auto& q : pts_) {
      const Eigen::Vector2d d = q - c;
      const double lx = cy * d.x() + sny * d.y(), ly = -sny * d.x() + cy * d.y();
      const double ex = std::max(std::abs(lx) - 0.5 * sx, 0.0), ey = std::max(std::abs(ly) - 0.5 * sy, 0.0);
      if (std::hypot(ex, ey) < clearance + 0.125) return false;
    }
    return true;
  }

 private:
  std::vector<Eigen::Vector2d> pts_;
};

void addRoomShell(std::vector<Primitive>& out, const Vec3& s) {
  const double X = s.x(), Y = s.y(), Z = s.z(), t = kSlab;
  out.push_back(Primitive::box({0, 0, -0.5 * t}, {X + 2 * t, Y + 2 * t, t}));     // floor
  out.push_back(Primitive::box({0, 0, Z + 0.5 * t}, {X + 2 * t, Y + 2 * t, t}));  // ceiling
  out.push_back(Primitive::box({0.5 * (X + t), 0, 0.5 * Z}, {t, Y + 2 * t, Z}));
  out.push_back(Primitive::box({-0.5 * (X + t), 0, 0.5 * Z}, {t, Y + 2 * t, Z}));
  out.push_back(Primitive::box({0, 0.5 * (Y + t), 0.5 * Z}, {X, t, Z}));
  out.push_back(Primitive::box({0, -0.5 * (Y + t), 0.5 * Z}, {X, t, Z}));
}

// A point against one of the four walls: wall index w (0 +x, 1 +y, 2 -x, 3 -y), position along the
// wall in [-0.5, 0.5] of its length, distance `inset` from it. Returns the yaw facing the wall.
double againstWall(const Vec3& s, int w, double along, double inset, Vec3& p) {
  const double yaw = w * 0.5 * kPi;
  const double half_depth = (w % 2 == 0 ? s.x() : s.y()) * 0.5;
  const double half_len = (w % 2 == 0 ? s.y() : s.x()) * 0.5;
  const Eigen::Vector2d n(std::cos(yaw), std::sin(yaw)), tangent(-n.y(), n.x());
  const Eigen::Vector2d q = n * (half_depth - inset) + tangent * (along * 2.0 * half_len);
  p = Vec3(q.x(), q.y(), 0.0);
  return yaw;
}

void furnishRoom(std::vector<Primitive>& out, const Vec3& s, double clutter, const PathClearance& path, SplitMix& rng) {
  const int items = static_cast<int>(std::lround(clutter * 28.0));
  const double keep = 0.6;  // clearance to the path, metres
  for (int n = 0; n < items; ++n) {
    const int type = rng.integer(0, 7);
    for (int attempt = 0; attempt < 40; ++attempt) {
      const Vec3 free(rng.uniform(-0.5, 0.5) * (s.x() - 1.0), rng.uniform(-0.5, 0.5) * (s.y() - 1.0), 0.0);
      const double yaw = rng.uniform(0.0, kPi);
      if (type <= 1) {  // crate, sometimes with a second one on top
        const Vec3 size(rng.uniform(0.3, 0.9), rng.uniform(0.3, 0.9), rng.uniform(0.3, 1.0));
        if (!path.clear(free, size.x(), size.y(), yaw, keep)) continue;
        out.push_back(Primitive::box(free + Vec3(0, 0, 0.5 * size.z()), size, yaw));
        if (rng.uniform() < 0.5) {
          const Vec3 top(0.7 * size.x(), 0.7 * size.y(), rng.uniform(0.2, 0.5));
          out.push_back(Primitive::box(free + Vec3(0, 0, size.z() + 0.5 * top.z()), top, yaw + rng.uniform(-0.6, 0.6)));
        }
      } else if (type == 2) {  // table: top and four legs
        const double L = rng.uniform(0.8, 1.6), W = rng.uniform(0.6, 0.9), Ht = rng.uniform(0.72, 0.78);
        if (!path.clear(free, L, W, yaw, keep)) continue;
        out.push_back(Primitive::box(free + Vec3(0, 0, Ht - 0.02), {L, W, 0.04}, yaw));
        const Mat3 R = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
        for (int k = 0; k < 4; ++k) {
          const Vec3 corner((k & 1 ? 1 : -1) * (0.5 * L - 0.06), (k & 2 ? 1 : -1) * (0.5 * W - 0.06), 0.0);
          out.push_back(Primitive::box(free + R * corner + Vec3(0, 0, 0.5 * (Ht - 0.04)), {0.05, 0.05, Ht - 0.04}, yaw));
        }
      } else if (type == 3) {  // pillar, floor to ceiling
        const double r = rng.uniform(0.12, 0.3);
        if (!path.clear(free, 2 * r, 2 * r, 0.0, keep)) continue;
        out.push_back(Primitive::cylinder(free, r, s.z()));
      } else if (type == 4) {  // cabinet against a wall
        const Vec3 size(rng.uniform(0.4, 0.6), rng.uniform(0.6, 1.6), rng.uniform(1.0, 2.0));
        Vec3 p;
        const double wyaw = againstWall(s, rng.integer(0, 3), rng.uniform(-0.4, 0.4), 0.5 * size.x() + 0.01, p);
        if (!path.clear(p, size.x(), size.y(), wyaw, keep)) continue;
        out.push_back(Primitive::box(p + Vec3(0, 0, 0.5 * size.z()), size, wyaw));
      } else if (type == 5) {  // panel leaning against a wall (tilted plane)
        const double H = rng.uniform(1.2, 2.0), W = rng.uniform(0.8, 1.5), tilt = rng.uniform(0.15, 0.35);
        Vec3 p;
        const double wyaw = againstWall(s, rng.integer(0, 3), rng.uniform(-0.4, 0.4), H * std::sin(tilt) + 0.05, p);
        if (!path.clear(p, 0.5, W, wyaw, keep)) continue;
        // Ry(tilt) turns the board's z axis towards +x (the wall after the yaw).
        const Vec3 up(std::cos(wyaw) * std::sin(tilt), std::sin(wyaw) * std::sin(tilt), std::cos(tilt));
        out.push_back(Primitive::box(p + 0.5 * H * up + Vec3(0, 0, 0.02), {0.03, W, H}, wyaw, tilt));
      } else if (type == 6) {  // frame / board on a wall (no clearance needed)
        Vec3 p;
        const double wyaw = againstWall(s, rng.integer(0, 3), rng.uniform(-0.45, 0.45), 0.02, p);
        const Vec3 size(0.04, rng.uniform(0.4, 1.4), rng.uniform(0.3, 1.0));
        out.push_back(Primitive::box(p + Vec3(0, 0, rng.uniform(1.0, std::max(1.1, s.z() - 0.8))), size, wyaw));
      } else {  // ceiling lamp, above head height
        const Vec3 size(rng.uniform(0.8, 1.4), rng.uniform(0.15, 0.4), 0.12);
        if (s.z() < 2.6) break;
        out.push_back(Primitive::box(free + Vec3(0, 0, s.z() - 0.25), size, yaw));
      }
      break;
    }
  }
}

void addCorridor(std::vector<Primitive>& out, const Vec3& s) {
  const double L = s.x(), W = s.y(), Z = s.z(), t = kSlab;
  out.push_back(Primitive::box({0, 0, -0.5 * t}, {L, W + 2 * t, t}));
  out.push_back(Primitive::box({0, 0, Z + 0.5 * t}, {L, W + 2 * t, t}));
  out.push_back(Primitive::box({0, 0.5 * (W + t), 0.5 * Z}, {L, t, Z}));
  out.push_back(Primitive::box({0, -0.5 * (W + t), 0.5 * Z}, {L, t, Z}));
}

// Buildings and street furniture along both sides of the path. With `repeat_m` > 0 the layout of the
// first repeat_m of path repeats along the rest: every block draws the same numbers (identical buildings
// and furniture wherever the road runs alike), the place-recognition trap of the loop-closure tests.
void addStreet(std::vector<Primitive>& out, const Vec3& s, double clutter, double repeat_m,
               const std::vector<Vec3>& path, const PathClearance& clear, SplitMix& rng) {
  Vec3 lo = Vec3::Constant(1e18), hi = -lo;
  for (const auto& p : path) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Vec3 mid = 0.5 * (lo + hi), ext = hi - lo + Vec3(240.0, 240.0, 0.0);
  out.push_back(Primitive::box({mid.x(), mid.y(), -0.5 * kSlab}, {ext.x(), ext.y(), kSlab}));

  // Arc length along the path for placing things at chosen distances.
  std::vector<double> arc(path.size(), 0.0);
  for (std::size_t i = 1; i < path.size(); ++i) arc[i] = arc[i - 1] + (path[i] - path[i - 1]).head<2>().norm();
  auto at = [&](double sq, Vec3& p, double& yaw) {
    const auto it = std::lower_bound(arc.begin(), arc.end(), std::fmod(sq, arc.back()));
    const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(it - arc.begin()), path.size() - 2);
    p = path[i];
    const Vec3 d = path[i + 1] - path[i];
    yaw = std::atan2(d.y(), d.x());
  };
  const double span = repeat_m > 0.0 ? std::min(repeat_m, arc.back()) : arc.back();
  const int copies = repeat_m > 0.0 ? static_cast<int>(std::ceil(arc.back() / span)) : 1;
  // One side's buildings and furniture along the road from arc length `off`, at most `span` long.
  const auto addBlock = [&](int side, double off) {
    // Buildings: frontage 8-30 m, gaps 2-12 m, facade 7-12 m from the path, depth 8-20 m.
    for (double sq = rng.uniform(0.0, 10.0); sq < span && off + sq < arc.back();) {
      const double front = rng.uniform(8.0, 30.0), depth = rng.uniform(8.0, 20.0);
      const double setback = rng.uniform(7.0, 12.0), height = rng.uniform(6.0, std::max(6.5, s.z()));
      Vec3 p;
      double yaw;
      at(off + sq + 0.5 * front, p, yaw);
      const double byaw = yaw + rng.uniform(-0.08, 0.08);
      const Vec3 left(-std::sin(yaw), std::cos(yaw), 0.0);
      const Vec3 c = p + side * (setback + 0.5 * depth) * left;
      if (clear.clear(c, front, depth, byaw, 6.5)) {
        out.push_back(Primitive::box({c.x(), c.y(), 0.5 * height}, {front, depth, height}, byaw));
        if (rng.uniform() < 0.35) {  // stepped upper floors
          const double h2 = rng.uniform(3.0, 9.0);
          out.push_back(Primitive::box({c.x(), c.y(), height + 0.5 * h2}, {0.7 * front, 0.6 * depth, h2}, byaw));
        }
      }
      sq += front + rng.uniform(2.0, 12.0);
    }
    if (clutter <= 0.0) return;
    // Street furniture: poles, parked cars and trees at the roadside.
    for (double sq = rng.uniform(0.0, 5.0); sq < span && off + sq < arc.back(); sq += rng.uniform(6.0, 18.0) / clutter) {
      Vec3 p;
      double yaw;
      at(off + sq, p, yaw);
      const Vec3 left(-std::sin(yaw), std::cos(yaw), 0.0);
      const int type = rng.integer(0, 2);
      if (type == 0) {
        const Vec3 c = p + side * 5.0 * left;
        if (clear.clear(c, 0.3, 0.3, 0.0, 3.0)) out.push_back(Primitive::cylinder({c.x(), c.y(), 0.0}, 0.12, rng.uniform(4.0, 7.0)));
      } else if (type == 1) {
        const Vec3 c = p + side * 4.6 * left;
        const Vec3 size(rng.uniform(3.8, 4.8), 1.8, rng.uniform(1.4, 1.7));
        if (clear.clear(c, size.x(), size.y(), yaw, 3.0)) {
          out.push_back(Primitive::box({c.x(), c.y(), 0.2 + 0.3 * size.z()}, {size.x(), size.y(), 0.6 * size.z()}, yaw));
          out.push_back(Primitive::box({c.x(), c.y(), 0.2 + 0.8 * size.z()}, {0.55 * size.x(), 0.9 * size.y(), 0.4 * size.z()}, yaw));
        }
      } else {
        const Vec3 c = p + side * 6.0 * left;
        if (clear.clear(c, 3.0, 3.0, yaw, 3.0)) {
          out.push_back(Primitive::cylinder({c.x(), c.y(), 0.0}, 0.2, 3.2));
          out.push_back(Primitive::box({c.x(), c.y(), 4.4}, {3.0, 3.0, 2.4}, yaw + rng.uniform(0.0, 1.5)));
        }
      }
    }
  };
  for (int side = -1; side <= 1; side += 2) {
    const SplitMix side_start = rng;
    for (int k = 0; k < copies; ++k) {
      if (repeat_m > 0.0) rng = side_start;  // every block draws what the first drew
      addBlock(side, k * span);
    }
  }
}

TextureKind textureKind(const std::string& t) {
  if (t == "images") return TextureKind::Images;
  if (t == "none") return TextureKind::None;
  return TextureKind::Noise;
}

}  // namespace

std::vector<std::string> resolveTexturePaths(const SimScenario& sc) {
  std::vector<std::string> out;
  for (const auto& p : sc.world.texture_images)
    out.push_back(!p.empty() && p[0] == '/' ? p : sc.base_dir + "/" + p);
  return out;
}

World makeWorld(const SimScenario& sc, const std::vector<Vec3>& path) {
  const WorldConfig& w = sc.world;
  const auto seed = static_cast<std::uint64_t>(w.seed >= 0 ? w.seed : sc.seed);  // world.seed: layout apart from noise
  SplitMix rng(hashKeys(seed, static_cast<std::uint64_t>(RngStream::World), 0));
  const PathClearance clear(path);
  std::vector<Primitive> prims;
  if (w.kind == "room") {
    addRoomShell(prims, w.size_m);
    furnishRoom(prims, w.size_m, w.clutter, clear, rng);
  } else if (w.kind == "corridor") {
    addCorridor(prims, w.size_m);
  } else if (w.kind == "street") {
    addStreet(prims, w.size_m, w.clutter, w.repeat_m, path, clear, rng);
  } else {  // wall
    prims.push_back(Primitive::box({w.size_m.x() + 0.25, 0.0, 1.4}, {0.5, w.size_m.y(), w.size_m.z()}));
  }
  TextureBank textures(textureKind(w.texture), resolveTexturePaths(sc), w.texture_scale_m, w.texture_tile_m);
  return World(std::move(prims), std::move(textures), seed);
}

}  // namespace livo::sim
