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
