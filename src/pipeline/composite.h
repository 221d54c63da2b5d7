// Stage 8: the differential composite (Debevec 1998). Real pixels: background + change, never below 0.
// Virtual pixels: the shaded object, blended over the real pixel by its coverage (anti-aliased silhouette).
#pragma once

#include <span>

#include "deltagi/image.h"
#include "pipeline/gbuffer.h"

namespace deltagi {

struct CompositeImages {
    Image composite;   // RGB
    Image objectMask;  // 1 channel, the coverage
    Image delta;       // composite - background
    // With the real change given in its two parts: the layers of RenderOutput (object RGBA premultiplied,
    // shadow, indirect); empty otherwise.
    Image object, shadow, indirect;
};

// `objectRadiance` and `realChange` hold one value per pixel (row-major).
CompositeImages differentialComposite(const Image& background, const GBuffer& gbuffer,
                                      std::span<const glm::vec3> objectRadiance,
                                      std::span<const glm::vec3> realChange);
// The same with the real change as its direct (shadow) and indirect parts, realChange = shadow + indirect,
// and the layers besides.
CompositeImages differentialComposite(const Image& background, const GBuffer& gbuffer,
                                      std::span<const glm::vec3> objectRadiance,
                                      std::span<const glm::vec3> realShadow,
                                      std::span<const glm::vec3> realIndirect);

// Replaces NaN and infinite values by 0 (the last guard before an image leaves the pipeline).
void sanitize(Image& image);

}  // namespace deltagi
