#include "pipeline/composite.h"

#include <cmath>

#include "core/parallel.h"

namespace deltagi {

void sanitize(Image& image) {
    for (float& v : image.data())
        if (!std::isfinite(v)) v = 0.0f;
}

namespace {

// Both forms: `realIndirect` empty means `realChange` is the whole change and no layers are made.
CompositeImages composite(const Image& background, const GBuffer& gbuffer,
                          std::span<const glm::vec3> objectRadiance, std::span<const glm::vec3> realChange,
                          std::span<const glm::vec3> realIndirect) {
    const int w = background.width(), h = background.height();
    const bool layers = !realIndirect.empty();
    CompositeImages out{Image(w, h, 3), Image(w, h, 1), Image(w, h, 3), {}, {}, {}};
    if (layers) out.object = Image(w, h, 4), out.shadow = Image(w, h, 3), out.indirect = Image(w, h, 3);
    auto finite = [](glm::vec3 v) {  // as sanitize(): no NaN or infinity in the images
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(v[k])) v[k] = 0.0f;
        return v;
    };
    // The 3-channel images' pixels written in place (Image::setRgb is a call per pixel).
    auto set = [](Image& image, size_t i, glm::vec3 v) {
        float* p = image.data().data() + 3 * i;
        p[0] = v.x, p[1] = v.y, p[2] = v.z;
    };
    const std::span<const float> bgPixels = background.data();
    const bool bgRgb = background.channels() == 3;
    parallelFor(0, h, 8, [&](int64_t y64) {
        const int y = static_cast<int>(y64);
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const glm::vec3 bg = bgRgb ? glm::vec3(bgPixels[3 * i], bgPixels[3 * i + 1], bgPixels[3 * i + 2])
                                       : background.rgb(x, y);
            const float coverage = gbuffer.coverage[i];
            const glm::vec3 change = layers ? realChange[i] + realIndirect[i] : realChange[i];
            const glm::vec3 real = glm::max(bg + change, glm::vec3(0.0f));
            const glm::vec3 object = glm::max(objectRadiance[i], glm::vec3(0.0f));
            const glm::vec3 c = finite(glm::mix(real, object, coverage));
            set(out.composite, i, c);
            out.objectMask.data()[i] = coverage;
            set(out.delta, i, finite(c - bg));
            if (!layers) continue;
            const glm::vec3 premultiplied = finite(object * coverage);
            float* o = out.object.data().data() + 4 * i;
            for (int k = 0; k < 3; ++k) o[k] = premultiplied[k];
            o[3] = coverage;
            const bool realShows = coverage < 1.0f;
            set(out.shadow, i, realShows ? finite(realChange[i]) : glm::vec3(0.0f));
            set(out.indirect, i, realShows ? finite(realIndirect[i]) : glm::vec3(0.0f));
        }
    });
    return out;
}

}  // namespace

CompositeImages differentialComposite(const Image& background, const GBuffer& gbuffer,
                                      std::span<const glm::vec3> objectRadiance,
                                      std::span<const glm::vec3> realChange) {
    return composite(background, gbuffer, objectRadiance, realChange, {});
}

CompositeImages differentialComposite(const Image& background, const GBuffer& gbuffer,
                                      std::span<const glm::vec3> objectRadiance,
                                      std::span<const glm::vec3> realShadow,
                                      std::span<const glm::vec3> realIndirect) {
    return composite(background, gbuffer, objectRadiance, realShadow, realIndirect);
}

}  // namespace deltagi
