#include "livo/sim/world.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace livo::sim {

namespace {

constexpr double kEps = 1e-9;  // rays start just after their origin
constexpr int kBins = 16;      // SAH bins per axis
constexpr int kMaxDepth = 48;  // BVH depth cap (the traversal stack holds 64 entries)

Mat3 yawPitch(double yaw, double pitch) {
  return (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY())).toRotationMatrix();
}

// Slab test of a ray against a node's bounds (floats: the traversal is the hot loop); returns the
// entry distance or +inf on a miss. Zero direction components have a huge finite inverse.
inline float slabEntry(const float* lo, const float* hi, const float* o, const float* inv, float t_max) {
  float t0 = 0.f, t1 = t_max;
  for (int a = 0; a < 3; ++a) {
    const float tn = (lo[a] - o[a]) * inv[a];
    const float tf = (hi[a] - o[a]) * inv[a];
    t0 = std::max(t0, std::min(tn, tf));
    t1 = std::min(t1, std::max(tn, tf));
  }
  return t0 <= t1 ? t0 : std::numeric_limits<float>::infinity();
}

// Float bounds that contain the double ones.
inline void storeBounds(const Vec3& lo, const Vec3& hi, float* flo, float* fhi) {
  for (int a = 0; a < 3; ++a) {
    const double pad = 1e-5 * (1.0 + std::max(std::abs(lo[a]), std::abs(hi[a])));
    flo[a] = static_cast<float>(lo[a] - pad);
    fhi[a] = static_cast<float>(hi[a] + pad);
  }
}

}  // namespace

Primitive Primitive::box(const Vec3& center, const Vec3& size, double yaw, double pitch) {
  Primitive p;
  p.type = Type::Box;
  p.center = center;
  p.R_world_local = yawPitch(yaw, pitch);
  p.half = 0.5 * size;
  return p;
}

Primitive Primitive::cylinder(const Vec3& base_center, double radius, double height) {
  Primitive p;
  p.type = Type::Cylinder;
  p.center = base_center + Vec3(0.0, 0.0, 0.5 * height);
  p.half = Vec3(radius, radius, 0.5 * height);
  return p;
}

void Primitive::bounds(Vec3& lo, Vec3& hi) const {
  // |R| h bounds a rotated box; for cylinders R = I and half = (r, r, h/2).
  const Vec3 ext = R_world_local.cwiseAbs() * half;
  lo = center - ext;
  hi = center + ext;
}

World::World(std::vector<Primitive> primitives, TextureBank textures, std::uint64_t seed)
    : prims_(std::move(primitives)), textures_(std::move(textures)) {
  styles_.reserve(prims_.size() * kFacesPerPrimitive);
  for (std::size_t s = 0; s < prims_.size() * kFacesPerPrimitive; ++s) styles_.push_back(textures_.makeStyle(seed, s));
  if (prims_.empty()) return;
  std::vector<Vec3> lo(prims_.size()), hi(prims_.size());
  prim_bounds_.resize(prims_.size());
  for (std::size_t i = 0; i < prims_.size(); ++i) {
    prims_[i].bounds(lo[i], hi[i]);
    storeBounds(lo[i], hi[i], prim_bounds_[i].data(), prim_bounds_[i].data() + 3);
  }
  order_.resize(prims_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<int>(i);
  nodes_.reserve(2 * prims_.size());
  build(0, static_cast<int>(prims_.size()), lo, hi, 0);
}

namespace {

// Half the surface area of the box [a, b] (SAH costs compare areas, so the factor 2 does not matter).
double halfArea(const Vec3& a, const Vec3& b) {
  const Vec3 e = (b - a).cwiseMax(0.0);
  return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
}

// Bounds of the primitives ids[0..count) (box_*) and of their centroids (centroid_*).
struct BuildBounds {
  Vec3 box_lo, box_hi, centroid_lo, centroid_hi;
};

BuildBounds buildBounds(const int* ids, int count, const std::vector<Vec3>& lo, const std::vector<Vec3>& hi) {
  BuildBounds b;
  b.box_lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  b.box_hi = -b.box_lo;
  b.centroid_lo = b.box_lo;
  b.centroid_hi = b.box_hi;
  for (int k = 0; k < count; ++k) {
    const int i = ids[k];
    b.box_lo = b.box_lo.cwiseMin(lo[i]);
    b.box_hi = b.box_hi.cwiseMax(hi[i]);
    const Vec3 c = 0.5 * (lo[i] + hi[i]);
    b.centroid_lo = b.centroid_lo.cwiseMin(c);
    b.centroid_hi = b.centroid_hi.cwiseMax(c);
  }
  return b;
}

// SAH bin (0..kBins-1) of primitive i's centroid along `axis`; used both to cost and to partition.
int centroidBin(int i, int axis, const std::vector<Vec3>& lo, const std::vector<Vec3>& hi, const BuildBounds& b) {
  const double c = 0.5 * (lo[i][axis] + hi[i][axis]);
  return std::min(kBins - 1, static_cast<int>(kBins * (c - b.centroid_lo[axis]) /
                                              (b.centroid_hi[axis] - b.centroid_lo[axis])));
}

// Cheapest split so far: below bin `bin` + 1 of `axis` goes left; axis -1 = a leaf.
struct SahSplit {
  double cost = 0.0;
  int axis = -1, bin = 0;
};

// Bins the primitives along `axis` and keeps in `best` the split plane between bins that costs least:
// 0.3 area(node) + area(left) n_left + area(right) n_right.
void bestSplitOnAxis(const int* ids, int count, const std::vector<Vec3>& lo, const std::vector<Vec3>& hi,
                     const BuildBounds& bounds, int axis, SahSplit& best) {
  std::array<int, kBins> cnt{};
  std::array<Vec3, kBins> blo, bhi;
  blo.fill(Vec3::Constant(std::numeric_limits<double>::infinity()));
  bhi.fill(-Vec3::Constant(std::numeric_limits<double>::infinity()));
  for (int k = 0; k < count; ++k) {
    const int i = ids[k];
    const int b = centroidBin(i, axis, lo, hi, bounds);
    ++cnt[b];
    blo[b] = blo[b].cwiseMin(lo[i]);
    bhi[b] = bhi[b].cwiseMax(hi[i]);
  }
  // Sweep: right-side areas from the top, then left-side from the bottom.
  std::array<double, kBins> right_area{};
  std::array<int, kBins> right_cnt{};
  Vec3 rlo = blo[kBins - 1], rhi = bhi[kBins - 1];
  int rc = 0;
  for (int b = kBins - 1; b > 0; --b) {
    rlo = rlo.cwiseMin(blo[b]);
    rhi = rhi.cwiseMax(bhi[b]);
    rc += cnt[b];
    right_area[b] = halfArea(rlo, rhi);
    right_cnt[b] = rc;
  }
  Vec3 llo = blo[0], lhi = bhi[0];
  int lc = 0;
  for (int b = 0; b < kBins - 1; ++b) {
    llo = llo.cwiseMin(blo[b]);
    lhi = lhi.cwiseMax(bhi[b]);
    lc += cnt[b];
    if (lc == 0 || right_cnt[b + 1] == 0) continue;
    const double cost = 0.3 * halfArea(bounds.box_lo, bounds.box_hi) + halfArea(llo, lhi) * lc +
                        right_area[b + 1] * right_cnt[b + 1];
    if (cost < best.cost) {
      best.cost = cost;
      best.axis = axis;
      best.bin = b;
    }
  }
}

}  // namespace

// Top-down build with the surface area heuristic (SAH, MacDonald & Booth 1990): the split plane
// among 16 centroid bins per axis minimising area(left) n_left + area(right) n_right; leaves hold up
// to 4 primitives (or more when no split pays off).
int World::build(int first, int count, std::vector<Vec3>& lo, std::vector<Vec3>& hi, int depth) {
  const int index = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  Node n;
  const int* ids = order_.data() + first;
  const BuildBounds bounds = buildBounds(ids, count, lo, hi);
  storeBounds(bounds.box_lo, bounds.box_hi, n.lo, n.hi);
  SahSplit split;
  split.cost = halfArea(bounds.box_lo, bounds.box_hi) * count;  // cost of a leaf, in the same units
  if (count > 1 && depth < kMaxDepth) {
    for (int axis = 0; axis < 3; ++axis) {
      if (bounds.centroid_hi[axis] - bounds.centroid_lo[axis] <= 0.0) continue;  // centroids in one plane
      bestSplitOnAxis(ids, count, lo, hi, bounds, axis, split);
    }
  }
  if (split.axis < 0) {
    n.first = first;
    n.count = count;
    nodes_[static_cast<std::size_t>(index)] = n;
    return index;
  }
  // Same bin formula as in the costs, so both sides are non-empty.
  const auto mid_it = std::partition(order_.begin() + first, order_.begin() + first + count, [&](int i) {
    return centroidBin(i, split.axis, lo, hi, bounds) <= split.bin;
  });
  const int mid = static_cast<int>(mid_it - order_.begin());
  n.left = build(first, mid - first, lo, hi, depth + 1);
  n.right = build(mid, first + count - mid, lo, hi, depth + 1);
  nodes_[static_cast<std::size_t>(index)] = n;
  return index;
}

// Whether a hit at t on primitive i replaces `best`. Exact ties go to the lower primitive index, so
// that the result does not depend on the order in which primitives are tested.
inline bool beats(double t, int i, const Hit& best, double t_max) {
  if (!best.valid) return t <= t_max;
  return t < best.distance || (t == best.distance && i < best.surface / kFacesPerPrimitive);
}

bool World::intersect(int i, const Vec3& o, const Vec3& d, double t_max, Hit& best) const {
  const Primitive& p = prims_[static_cast<std::size_t>(i)];
  if (p.type == Primitive::Type::Box) return intersectBox(i, o, d, t_max, best);
  return intersectCylinder(i, o, d, t_max, best);
}

// Slabs in the box frame: the entry face (or the exit face when the origin is inside).
bool World::intersectBox(int i, const Vec3& o, const Vec3& d, double t_max, Hit& best) const {
  const Primitive& p = prims_[static_cast<std::size_t>(i)];
  const Vec3 ol = p.R_world_local.transpose() * (o - p.center);
  const Vec3 dl = p.R_world_local.transpose() * d;
  double t_in = -std::numeric_limits<double>::infinity(), t_out = std::numeric_limits<double>::infinity();
  int axis_in = 0, axis_out = 0;
  bool neg_in = false, neg_out = false;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dl[a]) < 1e-15) {
      if (std::abs(ol[a]) > p.half[a]) return false;
      continue;
    }
    const double inv = 1.0 / dl[a];
    double tn = (-p.half[a] - ol[a]) * inv, tf = (p.half[a] - ol[a]) * inv;
    if (tn > tf) std::swap(tn, tf);
    // A ray going +a enters through the -a face and leaves through the +a face.
    if (tn > t_in) { t_in = tn; axis_in = a; neg_in = dl[a] > 0; }
    if (tf < t_out) { t_out = tf; axis_out = a; neg_out = dl[a] < 0; }
  }
  if (t_out < t_in) return false;
  double t;
  int axis;
  bool neg;
  if (t_in > kEps) { t = t_in; axis = axis_in; neg = neg_in; }
  else if (t_out > kEps) { t = t_out; axis = axis_out; neg = neg_out; }  // origin inside the box
  else return false;
  if (!beats(t, i, best, t_max)) return false;
  const Vec3 q = ol + t * dl;
  const int j = (axis + 1) % 3, k = (axis + 2) % 3;
  best.valid = true;
  best.distance = t;
  best.surface = i * kFacesPerPrimitive + 2 * axis + (neg ? 1 : 0);
  best.normal = (neg ? -1.0 : 1.0) * p.R_world_local.col(axis);
  best.u = q[j] + p.half[j];
  best.v = q[k] + p.half[k];
  return true;
}

// Vertical cylinder: side (quadratic in t) and two caps.
bool World::intersectCylinder(int i, const Vec3& o, const Vec3& d, double t_max, Hit& best) const {
  const Primitive& p = prims_[static_cast<std::size_t>(i)];
  const double r = p.half.x(), hz = p.half.z();
  const double ox = o.x() - p.center.x(), oy = o.y() - p.center.y();
  int face = -1;
  double t_best = std::numeric_limits<double>::infinity();
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a > 1e-18) {
    const double b = 2.0 * (ox * d.x() + oy * d.y());
    const double c = ox * ox + oy * oy - r * r;
    const double disc = b * b - 4.0 * a * c;
    if (disc >= 0.0) {
      const double sq = std::sqrt(disc);
      for (const double t : {(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)}) {
        if (t <= kEps || std::abs(o.z() + t * d.z() - p.center.z()) > hz) continue;
        t_best = t;
        face = 0;
        break;
      }
    }
  }
  if (std::abs(d.z()) > 1e-15) {
    for (int cap = 0; cap < 2; ++cap) {
      const double zc = p.center.z() + (cap == 0 ? hz : -hz);
      const double t = (zc - o.z()) / d.z();
      if (t <= kEps || t >= t_best) continue;
      const double px = ox + t * d.x(), py = oy + t * d.y();
      if (px * px + py * py > r * r) continue;
      t_best = t;
      face = 1 + cap;
    }
  }
  if (face < 0 || !beats(t_best, i, best, t_max)) return false;
  const double px = ox + t_best * d.x(), py = oy + t_best * d.y();
  best.valid = true;
  best.distance = t_best;
  best.surface = i * kFacesPerPrimitive + face;
  if (face == 0) {
    best.normal = Vec3(px / r, py / r, 0.0);
    best.u = std::atan2(py, px) * r;
    best.v = o.z() + t_best * d.z() - p.center.z() + hz;
  } else {
    best.normal = Vec3(0.0, 0.0, face == 1 ? 1.0 : -1.0);
    best.u = px;
    best.v = py;
  }
  return true;
}

void World::finish(Hit& h, const Vec3& origin, const Vec3& dir, double footprint_rad) const {
  if (!h.valid) return;
  h.point = origin + h.distance * dir;
  const double footprint = footprint_rad * h.distance / std::max(h.cosIncidence(dir), 0.05);
  h.albedo = albedoAt(h.surface, h.u, h.v, footprint);
}

Hit World::raycast(const Vec3& origin, const Vec3& dir, double max_range, double footprint_rad) const {
  Hit best;
  if (nodes_.empty()) return best;
  float o[3], inv[3];
  for (int a = 0; a < 3; ++a) {
    o[a] = static_cast<float>(origin[a]);
    inv[a] = static_cast<float>(1.0 / (std::abs(dir[a]) > 1e-20 ? dir[a] : 1e-20));
  }
  // Stack of (node, entry distance): nodes entered beyond the current best hit are skipped. The float
  // limit is padded so that rounding never culls a node the double-precision test would enter.
  // (Two arrays rather than an array of pairs: an 8-byte load of two 4-byte stores stalls.)
  int stack_node[64];
  float stack_t[64];
  int top = 0;
  auto push = [&](int node, float t) {
    stack_node[top] = node;
    stack_t[top++] = t;
  };
  auto limit = [&] { return static_cast<float>((best.valid ? best.distance : max_range) * (1.0 + 1e-5) + 1e-4); };
  const Node& root = nodes_[0];
  const float t_root = slabEntry(root.lo, root.hi, o, inv, limit());
  if (t_root <= limit()) push(0, t_root);
  while (top > 0) {
    --top;
    const float lim = limit();
    if (stack_t[top] > lim) continue;
    const Node& n = nodes_[static_cast<std::size_t>(stack_node[top])];
    if (n.count > 0) {
      for (int k = n.first; k < n.first + n.count; ++k) intersect(order_[static_cast<std::size_t>(k)], origin, dir, max_range, best);
      continue;
    }
    // Visit the nearer child first (pushed last).
    const Node& l = nodes_[static_cast<std::size_t>(n.left)];
    const Node& r = nodes_[static_cast<std::size_t>(n.right)];
    const float tl = slabEntry(l.lo, l.hi, o, inv, lim);
    const float tr = slabEntry(r.lo, r.hi, o, inv, lim);
    if (tl <= tr) {
      if (tr <= lim) push(n.right, tr);
      if (tl <= lim) push(n.left, tl);
    } else {
      if (tl <= lim) push(n.left, tl);
      if (tr <= lim) push(n.right, tr);
    }
  }
  finish(best, origin, dir, footprint_rad);
  return best;
}

namespace {

// Whether the sphere (c, r) meets the cone from o around unit axis a with half-angle `half`, within
// `range` (conservative).
inline bool sphereInCone(const Vec3& c, double r, const Vec3& o, const Vec3& a, double half, double range) {
  const Vec3 v = c - o;
  const double d = v.norm();
  if (d <= r) return true;
  if (d - r > range) return false;
  const double angle = std::acos(std::clamp(v.dot(a) / d, -1.0, 1.0));
  return angle <= half + std::asin(std::min(1.0, r / d)) + 1e-9;
}

}  // namespace

void World::primitivesInCone(const Vec3& origin, const Vec3& axis, double half_angle_rad, double max_range,
                             std::vector<int>& out) const {
  out.clear();
  if (nodes_.empty()) return;
  auto sphere = [](const float* lo, const float* hi, Vec3& c) {
    const Vec3 l(lo[0], lo[1], lo[2]), h(hi[0], hi[1], hi[2]);
    c = 0.5 * (l + h);
    return 0.5 * (h - l).norm();
  };
  int stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--top])];
    Vec3 c;
    const double r = sphere(n.lo, n.hi, c);
    if (!sphereInCone(c, r, origin, axis, half_angle_rad, max_range)) continue;
    if (n.count == 0) {
      stack[top++] = n.left;
      stack[top++] = n.right;
      continue;
    }
    for (int k = n.first; k < n.first + n.count; ++k) {
      const int i = order_[static_cast<std::size_t>(k)];
      const auto& b = prim_bounds_[static_cast<std::size_t>(i)];
      const double ri = sphere(b.data(), b.data() + 3, c);
      if (sphereInCone(c, ri, origin, axis, half_angle_rad, max_range)) out.push_back(i);
    }
  }
  // Nearest first along the axis (where the axis ray enters the bounds, else the bounding sphere's
  // near side), so that the first hits bound the later tests. Ties by index: deterministic.
  float o[3], inv[3];
  for (int a = 0; a < 3; ++a) {
    o[a] = static_cast<float>(origin[a]);
    inv[a] = static_cast<float>(1.0 / (std::abs(axis[a]) > 1e-20 ? axis[a] : 1e-20));
  }
  std::vector<std::pair<float, int>> keyed;
  keyed.reserve(out.size());
  for (const int i : out) {
    const auto& b = prim_bounds_[static_cast<std::size_t>(i)];
    float key = slabEntry(b.data(), b.data() + 3, o, inv, static_cast<float>(max_range));
    if (!(key <= static_cast<float>(max_range))) {
      Vec3 c;
      const double r = sphere(b.data(), b.data() + 3, c);
      key = static_cast<float>((c - origin).norm() - r);
    }
    keyed.emplace_back(key, i);
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t k = 0; k < keyed.size(); ++k) out[k] = keyed[k].second;
}

Hit World::raycastAmong(const std::vector<int>& candidates, const Vec3& origin, const Vec3& dir, double max_range,
                        double footprint_rad) const {
  Hit best;
  float o[3], inv[3];
  for (int a = 0; a < 3; ++a) {
    o[a] = static_cast<float>(origin[a]);
    inv[a] = static_cast<float>(1.0 / (std::abs(dir[a]) > 1e-20 ? dir[a] : 1e-20));
  }
  for (const int i : candidates) {
    const auto& b = prim_bounds_[static_cast<std::size_t>(i)];
    const float lim = static_cast<float>((best.valid ? best.distance : max_range) * (1.0 + 1e-5) + 1e-4);
    if (slabEntry(b.data(), b.data() + 3, o, inv, lim) > lim) continue;
    intersect(i, origin, dir, max_range, best);
  }
  finish(best, origin, dir, footprint_rad);
  return best;
}

Hit World::raycastBruteForce(const Vec3& origin, const Vec3& dir, double max_range, double footprint_rad) const {
  Hit best;
  for (std::size_t i = 0; i < prims_.size(); ++i) intersect(static_cast<int>(i), origin, dir, max_range, best);
  finish(best, origin, dir, footprint_rad);
  return best;
}

double World::distanceToSurface(const Vec3& p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const Primitive& pr : prims_) {
    double d;
    if (pr.type == Primitive::Type::Box) {
      const Vec3 q = (pr.R_world_local.transpose() * (p - pr.center)).cwiseAbs();
      const Vec3 out = (q - pr.half).cwiseMax(0.0);
      d = out.squaredNorm() > 0.0 ? out.norm() : (pr.half - q).minCoeff();
    } else {
      const double rho = std::hypot(p.x() - pr.center.x(), p.y() - pr.center.y());
      const double dz = std::abs(p.z() - pr.center.z());
      const double er = rho - pr.half.x(), ez = dz - pr.half.z();
      d = (er <= 0.0 && ez <= 0.0) ? std::min(-er, -ez) : std::hypot(std::max(er, 0.0), std::max(ez, 0.0));
    }
    best = std::min(best, d);
  }
  return best;
}

double World::albedoAt(int surface, double u, double v, double footprint_m) const {
  return textures_.albedo(styles_[static_cast<std::size_t>(surface)], u, v, footprint_m);
}

double World::radiance(const Hit& h) const {
  static const Vec3 light = Vec3(0.35, 0.25, 0.9).normalized();
  return h.albedo * (0.65 + 0.35 * std::max(0.0, h.normal.dot(light)));
}

double World::skyRadiance(const Vec3& dir) { return 0.75 + 0.2 * std::clamp(dir.z(), -1.0, 1.0); }

}  // namespace livo::sim
