// The sRGB encoding (and decoding) of image_io.cpp, for code outside it (the live session's colour scale; its PNG and
// JPEG bytes are encodeSrgb8()'s, include/deltagi/image.h).
#pragma once

#include <cstdint>
#include <vector>

#include "deltagi/image.h"

namespace deltagi {

// linearToSrgb() of image_io.cpp: the exact piecewise sRGB encoding of a linear value in [0, 1].
float linearToSrgbValue(float linear);
// srgbToLinear() of image_io.cpp: the exact piecewise sRGB decoding of an encoded value in [0, 1] (vertex
// colours of PLY files).
float srgbToLinearValue(float encoded);

}  // namespace deltagi
