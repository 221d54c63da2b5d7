// Sky light through the cones: a diffuse or specular cone that leaves the volumes without being fully
// occluded picks up the environment map prefiltered to its aperture, minus what the lights extracted from the
// map already carry (their shadow cones account for them), so that nothing is counted twice. Occlusion is
// read like a shadow cone's (§3.5), by the scene volume, the object volume and both, so that shading and
// relighting follow the same rule as direct light (ShadowMode): the virtual object gets its sky light and
// reflections of the surroundings; a real surface gets the change, the sky light the object now blocks (its
// ambient occlusion and contact shadow on the real ground: negative).
#pragma once

#include <span>
#include <vector>

#include "deltagi/environment.h"
#include "deltagi/options.h"
#include "pipeline/cone_trace.h"
#include "pipeline/gbuffer.h"
#include "pipeline/light_extraction.h"
#include "pipeline/shading.h"

namespace deltagi {

// The residual map (equirect minus the lights) prefiltered with von Mises-Fisher kernels exp(kappa (cos -
// 1)), kappa = 1 / (1 - cos(half-angle)): a kernel as concentrated as a cone of that half-angle (the same
// peak for a unit integral, 2 pi / kappa being the cone's solid angle). Each level is normalized by its
// discrete kernel sum, so that a uniform map stays exactly uniform. `lights` are in the environment frame.
SkyPyramid prefilterSky(const Image& equirect, std::span<const ExtractedLight> lights);

// The prefiltered residual radiance around `direction` (environment frame) for a cone of this half-angle
// tangent: bilinear within the two nearest levels, linear in log(half-angle) between them.
glm::vec3 skyRadiance(const SkyPyramid& sky, glm::vec3 direction, float tanHalfAngle);

// Per point: the sky radiance arriving through the diffuse cones (cosine-weighted like traceDiffuseCones(),
// to be multiplied by the albedo) and through the specular cone (to be multiplied by the specular colour),
// each cone's sky scaled by the shadow factor of `mode`. Zero for invalid points.
// `parts` says which of the two to trace (the other stays zero). With ShadowMode::DeltaShadow, cones that the
// objects do not occlude anywhere are skipped: their change is zero (shadowConeMeetsObjects). Only the points
// listed in `pixels` are traced when it is not empty (see traceShadowCones).
struct SkyLight {
    std::vector<glm::vec3> diffuse, specular;
};
enum class SkyParts { Both, Diffuse, Specular };
SkyLight traceSkyCones(std::span<const SurfacePoint> points, const Environment& environment,
                       const VisibilityVolumes& visibility, ShadowMode mode, const Options& options,
                       SkyParts parts = SkyParts::Both, std::span<const uint32_t> pixels = {});

}  // namespace deltagi
