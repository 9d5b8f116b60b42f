#include "livo/io/image_convert.hpp"

#include <utility>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace livo {

bool toGray8(const Image& in, Image& out, std::string* error) {
  auto fail = [&](const std::string& e) {
    if (error) *error = e;
    return false;
  };
  cv::Mat gray;
  const int w = in.width, h = in.height;
  try {
    switch (in.format) {
      case PixelFormat::Gray8:
        gray = cv::Mat(h, w, CV_8UC1, const_cast<std::uint8_t*>(in.data.data()), static_cast<std::size_t>(in.row_stride));
        break;
      case PixelFormat::Gray16: {
        cv::Mat m16(h, w, CV_16UC1, const_cast<std::uint8_t*>(in.data.data()), static_cast<std::size_t>(in.row_stride));
        m16.convertTo(gray, CV_8UC1, 1.0 / 256.0);
        break;
      }
      case PixelFormat::Rgb8:
      case PixelFormat::Bgr8: {
        cv::Mat c(h, w, CV_8UC3, const_cast<std::uint8_t*>(in.data.data()), static_cast<std::size_t>(in.row_stride));
        cv::cvtColor(c, gray, in.format == PixelFormat::Rgb8 ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
        break;
      }
      case PixelFormat::Jpeg:
      case PixelFormat::Png: {
        const cv::Mat buf(1, static_cast<int>(in.data.size()), CV_8UC1, const_cast<std::uint8_t*>(in.data.data()));
        gray = cv::imdecode(buf, cv::IMREAD_GRAYSCALE);
        if (gray.empty()) return fail(std::string("cannot decode ") + toString(in.format) + " image");
        if (gray.cols != w || gray.rows != h)
          return fail("decoded image is " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                      ", message says " + std::to_string(w) + "x" + std::to_string(h));
        break;
      }
    }
  } catch (const cv::Exception& e) {
    return fail(std::string("image conversion failed: ") + e.what());
  }
  out.utime = in.utime;
  out.width = gray.cols;
  out.height = gray.rows;
  out.row_stride = gray.cols;
  out.format = PixelFormat::Gray8;
  out.exposure_time_s = in.exposure_time_s;
  out.data.resize(static_cast<std::size_t>(gray.cols) * static_cast<std::size_t>(gray.rows));
  for (int r = 0; r < gray.rows; ++r)
    std::copy(gray.ptr<std::uint8_t>(r), gray.ptr<std::uint8_t>(r) + gray.cols, out.data.begin() + std::ptrdiff_t(r) * gray.cols);
  return true;
}

bool toGray8(Image&& in, Image& out, std::string* error) {
  if (in.format == PixelFormat::Gray8 && in.row_stride == in.width &&
      in.data.size() == std::size_t(in.width) * std::size_t(in.height)) {
    out = std::move(in);
    return true;
  }
  return toGray8(static_cast<const Image&>(in), out, error);
}

}  // namespace livo
