// Camera-failure checks of a frame's image (libs/estimation image_check.hpp) against images whose
// kind is known by construction: textured, dark but textured, black with sensor noise, saturated,
// and the same bytes twice.
#include "livo/estimation/image_check.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace livo;

namespace {

Image makeImage(int w, int h, double mean, double texture, double noise, std::uint32_t seed) {
  Image img;
  img.width = w;
  img.height = h;
  img.row_stride = w + 16;  // a padded stride: only the visible pixels count
  img.data.assign(std::size_t(img.row_stride) * std::size_t(h), 7);
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double v = mean + texture * std::sin(0.13 * x) * std::cos(0.07 * y) + noise * n(rng);
      img.data[std::size_t(y) * std::size_t(img.row_stride) + std::size_t(x)] =
          static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  return img;
}

}  // namespace

TEST(ImageCheck, TellsEachFailureFromAGoodImage) {
  const double pixel_noise = 2.0;
  ImageCheck check(pixel_noise);
  EXPECT_EQ(check.check(makeImage(640, 512, 120, 60, pixel_noise, 1)), ImageStatus::Ok);
  EXPECT_EQ(check.check(makeImage(640, 512, 25, 15, pixel_noise, 2)), ImageStatus::Ok) << "dark but textured";
  EXPECT_EQ(check.check(makeImage(640, 512, 1, 0, pixel_noise, 3)), ImageStatus::Black) << "lens cap + noise";
  EXPECT_EQ(check.check(makeImage(640, 512, 254, 0, pixel_noise, 4)), ImageStatus::Saturated);
  const Image a = makeImage(640, 512, 120, 60, pixel_noise, 5);
  EXPECT_EQ(check.check(a), ImageStatus::Ok);
  EXPECT_EQ(check.check(a), ImageStatus::Frozen) << "the same bytes again";
  EXPECT_EQ(check.check(makeImage(640, 512, 120, 60, pixel_noise, 6)), ImageStatus::Ok) << "new noise: live again";
}

// Frozen means every visible byte repeated: one changed byte anywhere (a word's or a row tail's) makes
// the image live; bytes of the row padding beyond the width do not count.
TEST(ImageCheck, OneChangedByteIsNotFrozenPaddingIsIgnored) {
  const double pixel_noise = 2.0;
  Image a = makeImage(203, 50, 120, 60, pixel_noise, 11);  // 203: 25 words and a 3-byte tail per row
  Image padded;
  padded.width = a.width, padded.height = a.height, padded.row_stride = a.width + 5;
  padded.data.assign(std::size_t(padded.row_stride) * std::size_t(padded.height), 7);
  for (int y = 0; y < a.height; ++y)
    std::copy_n(a.data.begin() + std::ptrdiff_t(y) * a.row_stride, a.width,
                padded.data.begin() + std::ptrdiff_t(y) * padded.row_stride);
  for (const int x : {0, 77, 200, 202}) {  // in a word, and in the tail
    ImageCheck check(pixel_noise);
    EXPECT_EQ(check.check(padded), ImageStatus::Ok);
    Image b = padded;
    b.data[std::size_t(31 * b.row_stride + x)] ^= 1;
    EXPECT_EQ(check.check(b), ImageStatus::Ok) << "byte " << x << " of row 31 changed";
    Image c = b;
    c.data[std::size_t(12 * c.row_stride + c.width + 2)] ^= 0xff;  // padding only
    EXPECT_EQ(check.check(c), ImageStatus::Frozen) << "only the padding changed";
  }
}

TEST(ImageCheck, ThresholdsFollowThePixelNoise) {
  // A dim image whose signal is 10 gray levels: lit for a 1-level sensor, black for a 5-level one.
  const Image dim = makeImage(320, 240, 10, 2, 1.0, 7);
  EXPECT_EQ(ImageCheck(1.0).check(dim), ImageStatus::Ok);
  EXPECT_EQ(ImageCheck(5.0).check(dim), ImageStatus::Black);
}

TEST(ImageCheck, CountersCountEachKind) {
  ImageCheckCounters c;
  for (ImageStatus s : {ImageStatus::Ok, ImageStatus::Black, ImageStatus::Black, ImageStatus::Saturated,
                        ImageStatus::Frozen, ImageStatus::Missing, ImageStatus::WrongSize})
    c.count(s);
  EXPECT_EQ(c.black, 2u);
  EXPECT_EQ(c.saturated, 1u);
  EXPECT_EQ(c.frozen, 1u);
  EXPECT_EQ(c.missing, 1u);
  EXPECT_EQ(c.wrong_size, 1u);
  EXPECT_STREQ(toString(ImageStatus::Frozen), "frozen");
}
