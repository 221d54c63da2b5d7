#include "composite.h"

#include <cmath>

#include "parallel.h"

namespace deltagi {

void sanitize(Image& image) {
    for (float& v : image.data())
        if (!std::isfinite(v)) v = 0.0f;
}

CompositeImages differentialComposite(const Image& background, const GBuffer& gbuffer,
                                      std::span<const glm::vec3> objectRadiance,
                                      std::span<const glm::vec3> realChange) {
    const int w = background.width(), h = background.height();
    CompositeImages out{Image(w, h, 3), Image(w, h, 1), Image(w, h, 3)};
    parallelFor(0, h, 8, [&](int64_t y64) {
        const int y = static_cast<int>(y64);
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const glm::vec3 bg = background.rgb(x, y);
            const float coverage = gbuffer.coverage[i];
            const glm::vec3 real = glm::max(bg + realChange[i], glm::vec3(0.0f));
            glm::vec3 c = glm::mix(real, glm::max(objectRadiance[i], glm::vec3(0.0f)), coverage);
            glm::vec3 d = c - bg;
            for (int k = 0; k < 3; ++k) {  // as sanitize(): no NaN or infinity in the images
                if (!std::isfinite(c[k])) c[k] = 0.0f;
                if (!std::isfinite(d[k])) d[k] = 0.0f;
            }
            out.composite.setRgb(x, y, c);
            out.objectMask.at(x, y, 0) = coverage;
            out.delta.setRgb(x, y, d);
        }
    });
    return out;
}

}  // namespace deltagi
