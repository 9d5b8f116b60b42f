// The correlative translation (and, without planar patches, yaw) search of ScanRegistration
// (scan_registration.hpp, method step 1b) over the occupancy pyramid of the map's surfaces, and the
// thinning of the scored points. Internal to libs/estimation (scan_registration.cpp).
#pragma once

#include "livo/estimation/scan_registration.hpp"

#include <cstddef>
#include <vector>

namespace livo::scan_detail {

/// Indices of `pts` thinned to one per cube of `cell` (the first in scan order), then strided down to
/// at most `max_n`.
std::vector<std::size_t> spread(const std::vector<BodyPoint>& pts, double cell, int max_n);

/// A search candidate: yaw offset and translation offset from the initial pose.
struct Candidate {
  double yaw = 0.0;
  Vec3 t = Vec3::Zero();
  int score = -1;
  double tie = 0.0;  ///< distance from the initial pose in steps (ties go to the nearest)
};

/// Higher score first; on equal scores the nearer to the initial pose.
bool better(const Candidate& a, const Candidate& b);

/// The correlative search (scan_registration.hpp, step 1b). Returns the candidates of the finest level,
/// best first. Candidates that cannot reach `floor_score` are not counted to the end (a coarser level's
/// score is at least the finer one's: a rotation whose best cannot reach it is given up early).
std::vector<Candidate> correlativeSearch(const OccupancyPyramid& pyr, const std::vector<Vec3>& pts_body,
                                         const Pose& T0, const SearchBounds& b, int beam, double& yaw_step0,
                                         int floor_score = 0);

/// The distinct candidates to refine, best first (at most n; the next must be away from the kept).
std::vector<Candidate> distinct(const std::vector<Candidate>& cands, int n, double cell0, double yaw_step0);

}  // namespace livo::scan_detail
