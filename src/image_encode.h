// Image pixels as files hold them, for encoders outside image_io.cpp (the live session's PNG and JPEG).
#pragma once

#include <cstdint>
#include <vector>

#include "deltagi/image.h"

namespace deltagi {

// The 8-bit sRGB bytes that writeImage() puts in a PNG: NaN and infinity as 0, clamped to [0, 1], the sRGB
// transfer function (alpha of a 4-channel image stays linear), rounded.
std::vector<uint8_t> srgb8Pixels(const Image& image);

// linearToSrgb() of image_io.cpp: the exact piecewise sRGB encoding of a linear value in [0, 1].
float linearToSrgbValue(float linear);

}  // namespace deltagi
