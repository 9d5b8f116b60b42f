// The simulated world: oriented boxes and vertical cylinders in a BVH, with textured surfaces.
//
// Raycasting returns the first surface along a ray: distance, point, outward normal, surface id (one
// per box face / cylinder part), surface coordinates (metres) and albedo (texture averaged over the
// ray's footprint). Radiance for the camera is view-independent (Lambertian under a fixed sky light),
// so brightness constancy holds across views, as direct methods assume.
#pragma once

#include "livo/common/so3.hpp"
#include "livo/sim/texture.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace livo::sim {

struct Primitive {
  enum class Type : std::uint8_t { Box, Cylinder };
  Type type = Type::Box;
  Vec3 center = Vec3::Zero();
  Mat3 R_world_local = Mat3::Identity();  ///< box axes (columns) in the world; cylinders: identity
  Vec3 half = Vec3::Constant(0.5);        ///< box half extents; cylinder: (radius, radius, half height)

  static Primitive box(const Vec3& center, const Vec3& size, double yaw = 0.0, double pitch = 0.0);
  static Primitive cylinder(const Vec3& base_center, double radius, double height);
  /// Axis-aligned bounds.
  void bounds(Vec3& lo, Vec3& hi) const;
};

/// Faces per primitive in surface ids: surface = primitive * kFacesPerPrimitive + face.
/// Box faces 0..5 = +x, -x, +y, -y, +z, -z (local); cylinder 0 = side, 1 = top, 2 = bottom.
constexpr int kFacesPerPrimitive = 8;

struct Hit {
  bool valid = false;
  double distance = 0.0;  ///< along the (unit) ray, metres
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  ///< outward unit normal of the surface
  int surface = -1;
  double u = 0.0, v = 0.0;  ///< surface coordinates, metres
  double albedo = 0.0;      ///< 0..1
  /// cos of the angle between the ray and the surface normal (0: grazing, 1: head on).
  double cosIncidence(const Vec3& dir) const { return std::abs(normal.dot(dir)); }
};

class World {
 public:
  World() = default;
  World(std::vector<Primitive> primitives, TextureBank textures, std::uint64_t seed);

  /// First hit along origin + t dir, 0 < t <= max_range; `dir` must be a unit vector. The albedo is
  /// averaged over a footprint of `footprint_rad` * distance / cos(incidence) metres.
  Hit raycast(const Vec3& origin, const Vec3& dir, double max_range, double footprint_rad = 0.0) const;
  /// Indices of the primitives whose bounds meet the cone from `origin` around the unit `axis` with
  /// half-angle `half_angle_rad`, up to `max_range`: a superset of what any ray inside the cone can
  /// hit (camera tiles use it to skip the BVH).
  void primitivesInCone(const Vec3& origin, const Vec3& axis, double half_angle_rad, double max_range,
                        std::vector<int>& out) const;
  /// raycast() among `candidates` only: the same hit whenever they include every primitive the ray
  /// can reach (e.g. from primitivesInCone()).
  Hit raycastAmong(const std::vector<int>& candidates, const Vec3& origin, const Vec3& dir, double max_range,
                   double footprint_rad = 0.0) const;
  /// Same result without the BVH (test oracle, slow).
  Hit raycastBruteForce(const Vec3& origin, const Vec3& dir, double max_range, double footprint_rad = 0.0) const;
  /// Unsigned distance from a point to the nearest surface (brute force, test oracle).
  double distanceToSurface(const Vec3& p) const;

  /// Camera radiance of a hit (view-independent, 0..1): albedo * (0.65 + 0.35 max(0, n.l)), l fixed.
  double radiance(const Hit& h) const;
  /// Radiance of rays that leave the world.
  static double skyRadiance(const Vec3& dir);
  /// Albedo of a surface point (as in raycast()).
  double albedoAt(int surface, double u, double v, double footprint_m) const;

  const std::vector<Primitive>& primitives() const { return prims_; }
  std::size_t numSurfaces() const { return styles_.size(); }
  const TextureBank& textures() const { return textures_; }

 private:
  struct Node {
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};  ///< bounds, rounded outwards
    int left = -1, right = -1;  ///< children (inner nodes)
    int first = 0, count = 0;   ///< range in order_ (leaves: count > 0)
  };
  int build(int first, int count, std::vector<Vec3>& lo, std::vector<Vec3>& hi, int depth);
  /// Intersects primitive i with the ray; updates `best` when closer than best.distance.
  bool intersect(int i, const Vec3& o, const Vec3& d, double t_max, Hit& best) const;
  bool intersectBox(int i, const Vec3& o, const Vec3& d, double t_max, Hit& best) const;
  bool intersectCylinder(int i, const Vec3& o, const Vec3& d, double t_max, Hit& best) const;
  void finish(Hit& h, const Vec3& origin, const Vec3& dir, double footprint_rad) const;

  std::vector<Primitive> prims_;
  std::vector<std::array<float, 6>> prim_bounds_;  ///< lo xyz, hi xyz (rounded outwards)
  std::vector<int> order_;
  std::vector<Node> nodes_;
  std::vector<SurfaceStyle> styles_;
  TextureBank textures_;
};

}  // namespace livo::sim
