// The per-frame inputs an application sets in code (camera, pose, photo), checked before each frame as the
// scene reader checks a file's: a bad one raises InputError, never a crash or a NaN image.
#include <bit>
#include <cmath>
#include <cstdint>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/transforms.h"

namespace deltagi {

void checkFrame(const Scene& scene) {
    const Camera& c = scene.camera;
    if (c.width < 1 || c.height < 1)
        throw InputError("camera",
                         fmt::format("expected a positive width and height, got {}x{}", c.width, c.height));
    if (!(c.fx > 0.0f && c.fy > 0.0f && std::isfinite(c.fx) && std::isfinite(c.fy) && std::isfinite(c.cx) &&
          std::isfinite(c.cy)))
        throw InputError("camera",
                         fmt::format("expected finite intrinsics with fx, fy > 0, got fx {}, fy {}, "
                                     "cx {}, cy {}",
                                     c.fx, c.fy, c.cx, c.cy));
    try {
        checkCameraPose(c.worldFromCamera);
    } catch (const InputError& e) {
        throw InputError("camera." + e.where(), e.message());
    }
    if (!scene.background) return;
    const Image& photo = *scene.background;
    if (photo.width() != c.width || photo.height() != c.height || photo.channels() != 3)
        throw InputError("background",
                         fmt::format("expected an RGB image of the camera's size {}x{}, got {}x{} "
                                     "with {} channels",
                                     c.width, c.height, photo.width(), photo.height(), photo.channels()));
    const std::span<const float> pixels = photo.data();
    // Every frame's photo: first whether any value is not finite, in one loop the compiler vectorizes (an
    // exponent of all ones), then where.
    bool allFinite = true;
    for (const float v : pixels) allFinite &= (std::bit_cast<uint32_t>(v) & 0x7F800000u) != 0x7F800000u;
    if (allFinite) return;
    for (size_t i = 0; i < pixels.size(); ++i)
        if (!std::isfinite(pixels[i]))
            throw InputError("background", fmt::format("pixel ({}, {}) is not finite ({})", i / 3 % c.width,
                                                       i / 3 / c.width, pixels[i]));
}

}  // namespace deltagi
