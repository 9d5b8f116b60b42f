#include "livo/estimation/image_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace livo {

const char* toString(ImageStatus s) {
  switch (s) {
    case ImageStatus::Ok: return "ok";
    case ImageStatus::WrongSize: return "wrong_size";
    case ImageStatus::Black: return "black";
    case ImageStatus::Saturated: return "saturated";
    case ImageStatus::Frozen: return "frozen";
    case ImageStatus::Missing: return "missing";
  }
  return "?";
}

void ImageCheckCounters::count(ImageStatus s) {
  switch (s) {
    case ImageStatus::Ok: break;
    case ImageStatus::WrongSize: ++wrong_size; break;
    case ImageStatus::Black: ++black; break;
    case ImageStatus::Saturated: ++saturated; break;
    case ImageStatus::Frozen: ++frozen; break;
    case ImageStatus::Missing: ++missing; break;
  }
}

namespace {

/// A 64-bit hash of every byte of the visible rows, eight bytes per step (multiply and xor-shift per
/// word, the row's tail bytewise): a frozen image repeats its bytes exactly, so any change of a byte
/// changes the hash but for a 2^-64 chance.
std::uint64_t imageHash(const Image& img) {
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](std::uint64_t w) {
    h ^= w;
    h *= 0x9E3779B97F4A7C15ull;
    h ^= h >> 32;
  };
  for (int y = 0; y < img.height; ++y) {
    const std::uint8_t* row = img.data.data() + std::size_t(y) * std::size_t(img.row_stride);
    int x = 0;
    for (; x + 8 <= img.width; x += 8) {
      std::uint64_t w;
      std::memcpy(&w, row + x, sizeof w);
      mix(w);
    }
    for (; x < img.width; ++x) mix(row[x]);
  }
  return h;
}

}  // namespace

ImageStatus ImageCheck::check(const Image& img) {
  const int margin = static_cast<int>(std::ceil(3.0 * pixel_noise_)) + 2;
  const int step = std::max(1, static_cast<int>(std::sqrt(double(img.width) * double(img.height) / 4000.0)));
  std::size_t n = 0, lit = 0, bright = 0;
  for (int y = step / 2; y < img.height; y += step) {
    const std::uint8_t* row = img.data.data() + std::size_t(y) * std::size_t(img.row_stride);
    for (int x = step / 2; x < img.width; x += step) {
      ++n;
      lit += row[x] > margin;
      bright += row[x] >= 255 - margin;
    }
  }
  const std::uint64_t h = imageHash(img);
  const bool frozen = have_last_ && h == last_hash_;
  last_hash_ = h;
  have_last_ = true;
  if (n == 0) return ImageStatus::Ok;
  if (double(lit) <= 0.05 * double(n)) return ImageStatus::Black;
  if (double(bright) >= 0.8 * double(n)) return ImageStatus::Saturated;
  if (frozen) return ImageStatus::Frozen;
  return ImageStatus::Ok;
}

}  // namespace livo
