// Camera images of any supported pixel format to 8-bit gray (OpenCV for decoding and color).
#pragma once

#include "livo/common/types.hpp"

#include <string>

namespace livo {

/// Converts `in` (GRAY8, GRAY16 (scaled by 1/256), RGB8, BGR8, JPEG, PNG) to a packed GRAY8 image.
/// Returns false with a message in `*error` when the data cannot be decoded.
bool toGray8(const Image& in, Image& out, std::string* error);
/// The same, taking `in`: a packed GRAY8 image moves into `out` without a copy (the common case of every
/// camera frame); any other format converts as above.
bool toGray8(Image&& in, Image& out, std::string* error);

}  // namespace livo
