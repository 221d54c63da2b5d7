// The sRGB transfer functions of image_io.cpp, for code outside it: the live session's colour scale (its PNG
// and JPEG bytes are encodeSrgb8()'s, include/deltagi/image.h) and the textures' decoding (texture.cpp); and
// the PNG writer's bytes in memory.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "deltagi/image.h"

namespace deltagi {

// linearToSrgb() of image_io.cpp: the exact piecewise sRGB encoding of a linear value in [0, 1].
float linearToSrgbValue(float linear);
// The 8-bit sRGB code of a linear value as encodeSrgb8() writes it (clamped to [0, 1], NaN and infinities as
// 0, encoded exactly and rounded), from tables: the same byte as lround(255 * linearToSrgbValue(v)) for every
// float v in [0, 1], several times faster.
uint8_t linearToSrgb8(float linear);
// srgbToLinear() of image_io.cpp: the exact piecewise sRGB decoding of an encoded value in [0, 1].
float srgbToLinearValue(float encoded);
// srgbToLinearValue(i / 255) for every 8-bit value i, the table image_io.cpp reads 8-bit files with.
const std::array<float, 256>& srgb8ToLinearValues();

// The PNG file writeImage() writes for `image` (8-bit sRGB, encodeSrgb8()'s bytes), in memory. Throws
// InputError naming `where` when the encoder fails.
std::string encodePngBytes(const Image& image, const std::string& where);

}  // namespace deltagi
