// The sRGB encoding of image_io.cpp, for encoders outside it (the live session's colour scale; its PNG and
// JPEG bytes are encodeSrgb8()'s, include/deltagi/image.h).
#pragma once

#include <cstdint>
#include <vector>

#include "deltagi/image.h"

namespace deltagi {

// linearToSrgb() of image_io.cpp: the exact piecewise sRGB encoding of a linear value in [0, 1].
float linearToSrgbValue(float linear);

}  // namespace deltagi
