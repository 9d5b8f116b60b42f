// The camera inset of the viewer (livo-viewer --camera): the latest image, shrunk by an integer factor
// (box average) to at most `max_width` pixels wide.
#pragma once

#include "livo/common/types.hpp"

namespace livo::viewer {

/// A packed Gray8 image shrunk by the smallest integer factor f with width / f <= max_width (f = 1 when
/// it already fits). Throws std::invalid_argument for another format, a short buffer or max_width < 1.
Image shrinkGray8(const Image& gray, int max_width);

}  // namespace livo::viewer
