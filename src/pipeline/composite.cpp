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
    parallelFor(0, h, 8, [&](int64_t y64) {
        const int y = static_cast<int>(y64);
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const glm::vec3 bg = background.rgb(x, y);
            const float coverage = gbuffer.coverage[i];
            const glm::vec3 change = layers ? realChange[i] + realIndirect[i] : realChange[i];
            const glm::vec3 real = glm::max(bg + change, glm::vec3(0.0f));
            const glm::vec3 object = glm::max(objectRadiance[i], glm::vec3(0.0f));
            const glm::vec3 c = finite(glm::mix(real, object, coverage));
            out.composite.setRgb(x, y, c);
            out.objectMask.at(x, y, 0) = coverage;
            out.delta.setRgb(x, y, finite(c - bg));
            if (!layers) continue;
            const glm::vec3 premultiplied = finite(object * coverage);
            for (int k = 0; k < 3; ++k) out.object.at(x, y, k) = premultiplied[k];
            out.object.at(x, y, 3) = coverage;
            const bool realShows = coverage < 1.0f;
            out.shadow.setRgb(x, y, realShows ? finite(realChange[i]) : glm::vec3(0.0f));
            out.indirect.setRgb(x, y, realShows ? finite(realIndirect[i]) : glm::vec3(0.0f));
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
