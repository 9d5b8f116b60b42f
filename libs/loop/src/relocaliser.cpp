#include "livo/loop/relocaliser.hpp"

#include "livo/common/timing.hpp"

#include <cmath>
#include <cstdio>
#include <limits>

namespace livo {

namespace {

PlaceSearchConfig anyTime(PlaceSearchConfig c) {
  c.min_path_m = 0.0;  // every map keyframe may match: the map is another run
  return c;
}

/// A search query far along the path, so that every map keyframe (stored at path 0) is eligible.
constexpr double kQueryPath = 1e12;

}  // namespace

Relocaliser::Relocaliser(const LoopConfig& cfg, SiteMap& map)
    : cfg_(cfg), map_(map), selector_(cfg.keyframes), places_(anyTime(cfg.search)), verifier_(cfg.verify) {
  for (int i = 0; i < static_cast<int>(map_.size()); ++i) {
    PlaceEntry e;
    e.utime = map_.keyframe(i).utime;
    e.T_world_body = map_.keyframe(i).T_map;
    e.descriptor = map_.keyframe(i).descriptor;
    places_.add(std::move(e));
  }
}

bool Relocaliser::check(const Pose& K, const std::vector<Vec3>& local, bool bounded, RelocaliseStep& st, Pose& H) {
  const PlaceDescriptor d = PlaceDescriptor::compute(local, cfg_.descriptor);
  const std::vector<PlaceCandidate> cands = places_.search(d, kQueryPath);
  st.candidates += static_cast<int>(cands.size());
  const double path_since = selector_.pathLength() - path_at_match_m_;
  bool found = false;
  for (const PlaceCandidate& c : cands) {
    if (st.checked >= cfg_.verify_candidates) break;
    const SiteKeyframe& k = map_.keyframe(c.id);
    // Localised: the map keyframe must be where the current transform puts it, within the odometry's
    // drift since the last match. Not yet: no bound (the odometry's frame is unknown in the map's).
    const Pose predicted = bounded ? k.T_map.inverse() * T_map_odom_ * K : Pose::Identity();
    ++st.checked;
    const LoopCheck lc = verifier_.verify(map_.points(c.id), local, c.match.yaw_rad, predicted,
                                          bounded ? path_since : std::numeric_limits<double>::max() / 4);
    if (!lc.accepted) continue;
    const Pose H_c = k.T_map * lc.T_cand_query * K.inverse();
    if (bounded) {  // the prediction already singles out the place
      H = H_c;
      st.map_keyframe = c.id;
      return true;
    }
    // Not localised: every candidate is checked; two that verify at different places (a symmetric
    // room, look-alike blocks) make the try ambiguous, and it counts for nothing.
    if (found && !agree(H, H_c)) {
      ++ambiguous_;
      return false;
    }
    if (!found) {
      H = H_c;
      st.map_keyframe = c.id;
      found = true;
    }
  }
  return found;
}

RelocaliseStep Relocaliser::add(Utime t, const Pose& T_odom_body, const std::function<std::vector<Vec3>()>& scan) {
  RelocaliseStep st;
  if (first_frame_ < 0) first_frame_ = t;
  const bool key = selector_.offer(T_odom_body);
  const bool try_now = localised_ ? key : (key || ++frames_since_attempt_ >= cfg_.relocalise_every_frames);
  if (!try_now) return st;
  frames_since_attempt_ = 0;
  Stopwatch watch;
  ++attempts_;
  const Pose K = keyframeFrame(T_odom_body);
  const Pose K_inv = K.inverse();
  std::vector<Vec3> local = scan();
  for (Vec3& p : local) p = K_inv * p;

  Pose H = Pose::Identity();
  bool ok = check(K, local, localised_, st, H);
  if (ok && !localised_) {
    // Localise when two tries at different times agree on where the odometry's frame sits.
    if (have_hypothesis_ && hypothesis_t_ != t && agree(hypothesis_, H)) {
      localised_ = true;
      first_localised_ = t;
      st.localised_now = true;
    }
    hypothesis_ = H;
    hypothesis_t_ = t;
    have_hypothesis_ = true;
  }
  if (ok && localised_ && !st.localised_now) ok = fuse(K, H);
  if (ok && localised_) {
    if (st.localised_now) {  // the first anchor: the match itself, with the match's variance
      T_map_odom_ = H;
      var_t_ = std::pow(cfg_.graph.loop_sigma_m, 2);
      var_r_ = std::pow(cfg_.graph.loop_sigma_deg * M_PI / 180.0, 2);
    }
    anchors_.push_back(KeyframePose{t, K, T_map_odom_ * K});
    path_at_match_m_ = selector_.pathLength();
    st.matched = true;
    if (outside_) {
      outside_ = false;
      st.back_in_map = true;
    }
  } else if (localised_ && !outside_ && selector_.pathLength() - path_at_match_m_ > cfg_.outside_map_after_m) {
    outside_ = true;
    ++left_map_;
    st.left_map = true;
  }
  st.ms = watch.elapsedMs();
  ms_ += st.ms;
  return st;
}

bool Relocaliser::agree(const Pose& a, const Pose& b) const {
  const Pose diff = a.inverse() * b;
  return diff.translation().norm() < cfg_.relocalise_agree_m &&
         rotationAngle(diff.linear()) < cfg_.relocalise_agree_deg * M_PI / 180.0;
}

bool Relocaliser::fuse(const Pose& K, const Pose& H_meas) {
  // The odometry's drift since the last anchor widens the current transform's variance; the match
  // narrows it. Fused at the keyframe: its map pose moves from the prediction towards the match's by the
  // gains (translation and rotation apart), a match beyond 3 sigma of the prediction is refused.
  const double path = selector_.pathLength() - path_at_match_m_;
  const double q_t = std::pow(cfg_.graph.odometrySigmaM(path), 2);
  const double q_r = std::pow(cfg_.graph.odometrySigmaRad(path), 2);
  const double r_t = std::pow(cfg_.graph.loop_sigma_m, 2), r_r = std::pow(cfg_.graph.loop_sigma_deg * M_PI / 180.0, 2);
  const double p_t = var_t_ + q_t, p_r = var_r_ + q_r;
  const Pose pred = T_map_odom_ * K, meas = H_meas * K;
  const Vec3 dt = meas.translation() - pred.translation();
  const Vec3 dr = logSO3(pred.linear().transpose() * meas.linear());
  if (dt.norm() > 3.0 * std::sqrt(p_t + r_t) || dr.norm() > 3.0 * std::sqrt(p_r + r_r)) {
    ++gated_;
    var_t_ = p_t;  // the drift still happened
    var_r_ = p_r;
    return false;
  }
  const double k_t = p_t / (p_t + r_t), k_r = p_r / (p_r + r_r);
  Pose fused = Pose::Identity();
  fused.translation() = pred.translation() + k_t * dt;
  fused.linear() = pred.linear() * expSO3(k_r * dr);
  T_map_odom_ = fused * K.inverse();
  var_t_ = (1.0 - k_t) * p_t;
  var_r_ = (1.0 - k_r) * p_r;
  return true;
}

MapCorrection Relocaliser::anchors(bool all) const {
  MapCorrection c;
  c.first = (all || anchors_.empty()) ? 0 : static_cast<std::int32_t>(anchors_.size()) - 1;
  c.keyframes.assign(anchors_.begin() + c.first, anchors_.end());
  c.keyframes_total = static_cast<std::int32_t>(anchors_.size());
  c.T_map_odom = T_map_odom_;
  c.utime = anchors_.empty() ? 0 : anchors_.back().utime;
  c.final = true;
  return c;
}

std::string Relocaliser::summary() const {
  char buf[320];
  if (!localised_) {
    std::snprintf(buf, sizeof buf, "not localised in the site map (%zu keyframes): %d tries, %d checks, none agreed",
                  map_.size(), attempts_, checks().total());
    return buf;
  }
  std::snprintf(buf, sizeof buf,
                "localised %.2f s after the first frame; %zu anchors from %d tries (%d checks, %d accepted); left the "
                "map %d times; %zu tile reads; %.0f ms in all",
                toSeconds(first_localised_ - first_frame_), anchors_.size(), attempts_, checks().total(),
                checks().accepted, left_map_, map_.tileReads(), ms_);
  return buf;
}

void Relocaliser::addCounters(std::map<std::string, double>& c) const {
  checks().addCounters("reloc", c);
  c["reloc_site_keyframes"] = double(map_.size());
  c["reloc_localised"] = localised_ ? 1.0 : 0.0;
  c["reloc_time_to_localise_s"] = localised_ ? toSeconds(first_localised_ - first_frame_) : -1.0;
  c["reloc_tries"] = double(attempts_);
  c["reloc_anchors"] = double(anchors_.size());
  c["reloc_left_map"] = double(left_map_);
  c["reloc_matches_gated"] = double(gated_);
  c["reloc_tries_ambiguous"] = double(ambiguous_);
  c["reloc_tile_reads"] = double(map_.tileReads());
  c["reloc_tiles_held"] = double(map_.tilesHeld());
  c["reloc_tile_bytes_held"] = double(map_.bytesHeld());
  c["reloc_index_bytes"] = double(map_.indexBytes());
  c["reloc_ms_total"] = ms_;
}

}  // namespace livo
