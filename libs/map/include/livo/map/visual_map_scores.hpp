// Patch scores used by the visual map: Shi-Tomasi corner score for new points (docs/algorithms.md 5.1) and
// zero-mean normalised cross-correlation between stored patches for reference selection (5.3).
#pragma once

#include "livo/map/visual_point.hpp"

#include <array>

namespace livo {

using PatchValues = std::array<float, PatchPyramid::kSize * PatchPyramid::kSize>;

/// Shi-Tomasi score at pixel `px` (rounded to the nearest pixel): the smaller eigenvalue of the
/// gradient tensor M = mean over the 8x8 box [u-4, u+3] x [v-4, v+3] of [gx^2, gx gy; gx gy, gy^2],
/// gx = (I(x+1, y) - I(x-1, y)) / 2 (central differences), i.e.
///   lambda_min = (a + c) / 2 - sqrt(((a - c) / 2)^2 + b^2),  M = [a b; b c]   (gray levels^2).
/// Returns -1 when the box or its gradient neighbours leave the image (or the image is not Gray8).
double shiTomasiScore(const Image& gray, const Vec2& px);

/// The kSize x kSize patch proper of one crop level (the crop without its margin), row-major.
PatchValues patchOfLevel(const PatchPyramid& pyramid, int level);

/// Zero-mean normalised cross-correlation in [-1, 1]:
///   NCC = sum (a_i - mean a)(b_i - mean b) / sqrt(sum (a_i - mean a)^2 sum (b_i - mean b)^2).
/// Invariant to affine intensity changes (so to exposure). 0 when either patch is flat.
double ncc(const PatchValues& a, const PatchValues& b);

}  // namespace livo
