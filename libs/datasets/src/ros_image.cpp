// sensor_msgs/Image and sensor_msgs/CompressedImage -> Image (formats in ros_msgs.hpp).
#include "livo/datasets/ros_msgs.hpp"

#include "ros_buffer.hpp"

#include <algorithm>

namespace livo {

namespace {

std::uint32_t be32(const std::uint8_t* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | p[3];
}
std::uint32_t be16(const std::uint8_t* p) { return (std::uint32_t(p[0]) << 8) | p[1]; }

bool jpegSize(const std::uint8_t* d, std::size_t n, int& width, int& height) {
  // Segments after SOI: 0xFF, marker, big-endian length (including itself); the frame size is in the
  // first SOFn segment (C0..CF except C4 DHT, C8 JPG, CC DAC): precision, height, width.
  std::size_t i = 2;
  while (i + 4 <= n) {
    if (d[i] != 0xFF) return false;
    while (i < n && d[i] == 0xFF) ++i;  // fill bytes
    if (i >= n) return false;
    const std::uint8_t marker = d[i++];
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) continue;  // no length
    if (marker == 0xD9 || marker == 0xDA || i + 2 > n) return false;   // EOI / scan before any SOF
    const std::uint32_t len = be16(d + i);
    if (len < 2) return false;
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      if (len < 7 || i + 7 > n) return false;
      height = static_cast<int>(be16(d + i + 3));
      width = static_cast<int>(be16(d + i + 5));
      return width > 0 && height > 0;
    }
    i += len;
  }
  return false;
}

struct RawEncoding {
  PixelFormat in = PixelFormat::Gray8;  ///< layout of the message's pixels (before any conversion)
  int channels = 1;                      ///< bytes per pixel in the message
};

bool rawEncoding(const std::string& e, RawEncoding& r) {
  if (e == "mono8" || e == "8UC1") r = {PixelFormat::Gray8, 1};
  else if (e == "rgb8") r = {PixelFormat::Rgb8, 3};
  else if (e == "bgr8" || e == "8UC3") r = {PixelFormat::Bgr8, 3};
  else if (e == "rgba8") r = {PixelFormat::Rgb8, 4};
  else if (e == "bgra8" || e == "8UC4") r = {PixelFormat::Bgr8, 4};
  else if (e == "mono16" || e == "16UC1") r = {PixelFormat::Gray16, 2};
  else return false;
  return true;
}

}  // namespace

bool compressedImageInfo(const std::uint8_t* data, std::size_t size, PixelFormat& format, int& width, int& height) {
  static const std::uint8_t kPng[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (size >= 24 && std::equal(kPng, kPng + 8, data) && std::equal(data + 12, data + 16, "IHDR")) {
    const std::uint32_t w = be32(data + 16), h = be32(data + 20);
    if (w == 0 || h == 0 || w > 0x7fffffffu || h > 0x7fffffffu) return false;
    format = PixelFormat::Png;
    width = static_cast<int>(w);
    height = static_cast<int>(h);
    return true;
  }
  if (size >= 4 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) {
    format = PixelFormat::Jpeg;
    return jpegSize(data, size, width, height);
  }
  return false;
}

Image decodeRosImage(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt) {
  RosBuffer b(data, size, "sensor_msgs/Image");
  Image img;
  img.utime = nsToUtimeRound(b.header());
  const auto height = b.get<std::uint32_t>("height");
  const auto width = b.get<std::uint32_t>("width");
  const std::string encoding = b.string("encoding");
  const bool big_endian = b.get<std::uint8_t>("is_bigendian") != 0;
  const auto step = b.get<std::uint32_t>("step");
  std::uint32_t len = 0;
  const std::uint8_t* pix = b.bytes("data", len);
  b.finish();

  RawEncoding enc;
  if (!rawEncoding(encoding, enc))
    b.fail("encoding", "unsupported '" + encoding + "' (supported: mono8, 8UC1, rgb8, bgr8, 8UC3, rgba8, bgra8, "
                       "8UC4, mono16, 16UC1)");
  const auto side = static_cast<std::uint32_t>(opt.max_image_side);
  if (width == 0 || height == 0 || width > side || height > side)
    b.fail("width/height", "invalid size " + std::to_string(width) + "x" + std::to_string(height));
  if (static_cast<std::uint64_t>(width) * enc.channels > step)
    b.fail("step", std::to_string(step) + " is smaller than width * " + std::to_string(enc.channels) + " bytes");
  const std::uint64_t need = static_cast<std::uint64_t>(step) * height;
  if (need > len) b.fail("data", "holds " + std::to_string(len) + " bytes but step * height = " + std::to_string(need));

  img.width = static_cast<int>(width);
  img.height = static_cast<int>(height);
  img.format = enc.in;
  if (enc.in == PixelFormat::Gray16 && opt.mono16_bits > 0) {
    // 16-bit -> GRAY8: keep the 8 most significant of `mono16_bits` bits (saturated).
    const int shift = opt.mono16_bits - 8;
    img.format = PixelFormat::Gray8;
    img.row_stride = img.width;
    img.data.resize(static_cast<std::size_t>(width) * height);
    for (std::uint32_t r = 0; r < height; ++r) {
      const std::uint8_t* row = pix + static_cast<std::size_t>(r) * step;
      for (std::uint32_t c = 0; c < width; ++c) {
        const std::uint8_t* q = row + 2 * c;
        const std::uint32_t v = big_endian ? (std::uint32_t(q[0]) << 8 | q[1]) : (std::uint32_t(q[1]) << 8 | q[0]);
        img.data[static_cast<std::size_t>(r) * width + c] = static_cast<std::uint8_t>(std::min<std::uint32_t>(255, v >> shift));
      }
    }
  } else if (enc.channels == 4) {
    // rgba8 / bgra8: drop alpha, packed rows.
    img.row_stride = img.width * 3;
    img.data.resize(static_cast<std::size_t>(img.row_stride) * height);
    for (std::uint32_t r = 0; r < height; ++r)
      for (std::uint32_t c = 0; c < width; ++c)
        std::copy_n(pix + static_cast<std::size_t>(r) * step + 4 * c, 3,
                    img.data.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(r) * img.row_stride + 3 * c));
  } else {
    img.row_stride = static_cast<int>(step);
    img.data.assign(pix, pix + need);
    if (enc.in == PixelFormat::Gray16 && big_endian)  // stored little-endian
      for (std::size_t r = 0; r < height; ++r)
        for (std::size_t c = 0; c < width; ++c) std::swap(img.data[r * step + 2 * c], img.data[r * step + 2 * c + 1]);
  }
  return img;
}

Image decodeRosCompressedImage(const std::uint8_t* data, std::size_t size, const RosDecodeOptions& opt) {
  RosBuffer b(data, size, "sensor_msgs/CompressedImage");
  Image img;
  img.utime = nsToUtimeRound(b.header());
  const std::string format = b.string("format");
  std::uint32_t len = 0;
  const std::uint8_t* stream = b.bytes("data", len);
  b.finish();
  if (format.find("compressedDepth") != std::string::npos)
    b.fail("format", "'" + format + "' (compressedDepth) is not supported");
  if (!compressedImageInfo(stream, len, img.format, img.width, img.height))
    b.fail("data", "neither a JPEG nor a PNG stream with a readable size (format '" + format + "', " +
                       std::to_string(len) + " bytes)");
  if (img.width > opt.max_image_side || img.height > opt.max_image_side)
    b.fail("data", "image size " + std::to_string(img.width) + "x" + std::to_string(img.height) + " is too large");
  img.row_stride = 0;
  img.data.assign(stream, stream + len);
  return img;
}

}  // namespace livo
