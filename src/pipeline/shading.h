// Stages 6 and 7: the cone passes over G-buffer surfaces, and shading vs relighting (§3.3).
//
// Shading (virtual surfaces): direct light with shadow cones against both visibility volumes, plus indirect
// diffuse and specular from the full light volume. Relighting (real surfaces): the change the objects make:
// indirect from the delta volume (cones occluded by both visibility volumes) and, for direct light, the
// object's soft shadow only where the real scene does not shadow the surface already (§3.2).
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "deltagi/scene.h"
#include "pipeline/cone_trace.h"
#include "pipeline/gbuffer.h"

namespace deltagi {

// The scene's share of the relit shadow cones (traceSceneOcclusion), per point and light, computed on first
// use: kept from frame to frame by the renderer while the real surfaces, the lights, the options and the
// scene's visibility volume are unchanged (only the objects move).
struct SceneOcclusionCache {
    std::vector<float> occlusion;  // points x lights
    std::vector<uint8_t> known;
};

// Shadow cones (§3.5): for every point and light (index point * lights + light) the occlusion by the scene
// alone, the objects alone and both. Invalid points get zero occlusion. With `objectShadowOnly` (relighting
// with ShadowMode::DeltaShadow, where only scene - combined = -(1 - scene) * object counts), the objects'
// occlusion is traced first and the cones it is zero for get zero occlusion: their change is zero either way;
// the scene's occlusion of the others comes from `sceneCache` when given (else it is traced), and the two
// volumes are marched apart (traceSceneOcclusion, traceObjectOcclusion).
// Each pass traces the points listed in `pixels` (indices into `points`), or all of them when it is empty;
// the others get zero. The results are per point of `points` either way.
std::vector<ShadowOcclusion> traceShadowCones(std::span<const SurfacePoint> points,
                                              std::span<const Light> lights,
                                              const VisibilityVolumes& visibility, const Options& options,
                                              bool objectShadowOnly = false,
                                              std::span<const uint32_t> pixels = {},
                                              SceneOcclusionCache* sceneCache = nullptr);

// Diffuse cones: cosine-weighted incoming radiance sum_k w_k L_k (so that albedo times it is the reflected
// radiance). Zero for invalid points. With `fullLight`, `light` is the delta volume and the cones give the
// change of the incoming light (traceLightChangeCone): options.render.relight_cones "differential"; with
// `objectLightByRays` too, without the objects' own light (traceObjectBounceRays adds it). `apertureDeg`,
// when given, replaces options.diffuse.aperture_deg (the virtual objects' cones take
// options.diffuse.object_aperture_deg).
std::vector<glm::vec3> traceDiffuseCones(std::span<const SurfacePoint> points, const MipVolume& light,
                                         const VisibilityVolumes& visibility, const Options& options,
                                         std::span<const uint32_t> pixels = {},
                                         const MipVolume* fullLight = nullptr,
                                         const MipVolume* objectLight = nullptr,
                                         bool objectLightByRays = false,
                                         std::optional<float> apertureDeg = std::nullopt);

// The specular cone along the mirrored view direction, aperture from the material's roughness. Zero for
// invalid points and materials without a specular part. `fullLight` as for traceDiffuseCones.
std::vector<glm::vec3> traceSpecularCones(std::span<const SurfacePoint> points, const MipVolume& light,
                                          const VisibilityVolumes& visibility, const Options& options,
                                          std::span<const uint32_t> pixels = {},
                                          const MipVolume* fullLight = nullptr,
                                          const MipVolume* objectLight = nullptr);

// The BRDF of deltagi::Material times cos(theta_i) times the light's irradiance: unshadowed direct radiance.
glm::vec3 directRadiance(const SurfacePoint& point, const Light& light);

// One cell of the quadrature over a light's disk that directRadiance takes for a glossy lobe narrower than
// the disk: the direction of its centre, how far the disk is along it, and the cell's share of the point's
// unshadowed direct radiance (the shares sum to directRadiance).
struct DirectLightCell {
    glm::vec3 wi{0.0f};
    float distance = 0.0f;
    glm::vec3 radiance{0.0f};
};
// The cells of that quadrature at `point` (into `cells`, cleared first) where the lobe's Phong exponent n and
// the disk's angular radius R have n R^2 >= minLobeSpread (the disk about sqrt(minLobeSpread) times as wide
// as the lobe, or wider); none elsewhere, nor where directRadiance takes a closed form (matte points, lobes
// about as wide as the disk or wider, lights without a size).
void directLightCells(const SurfacePoint& point, const Light& light, float minLobeSpread,
                      std::vector<DirectLightCell>& cells);

// How a surface's direct light is shadowed.
enum class ShadowMode {
    Shaded,       // virtual surface: lit where neither scene nor objects occlude (1 - combined)
    SceneOnly,    // real surface rendered alone: (1 - scene)
    DeltaShadow,  // real surface relit: the change (1 - combined) - (1 - scene) (§3.2, no double shadow)
    DeltaSingleVisibility,  // real surface relit with one shared visibility: (1 - combined) - 1 (double
                            // shadow)
};

// The fraction of a light (or of the sky through a cone) that reaches a point, or its change, under `mode`.
float shadowFactor(const ShadowOcclusion& occlusion, ShadowMode mode);

// Per point: sum over lights of direct radiance times the shadow factor of `mode`, plus albedo * diffuse
// plus specular colour * specular (either span may be empty: no indirect light), plus the material's emission
// in the modes that render a surface (Shaded, SceneOnly), not in those that relight it.
// With `bounds` (of a `width`-wide image), only the points inside it are valid: the others are skipped.
// With `samples` (Shaded mode), a point's direct light before its shadow is the mean over its pixel's
// sub-samples (the valid ones), not the light at the point alone. With `indirect`, the diffuse and specular
// parts go there (one value per point) instead of into the result, which then holds the direct light alone.
std::vector<glm::vec3> combineLighting(std::span<const SurfacePoint> points, std::span<const Light> lights,
                                       std::span<const ShadowOcclusion> shadows, ShadowMode mode,
                                       std::span<const glm::vec3> diffuse,
                                       std::span<const glm::vec3> specular, const PixelRect* bounds = nullptr,
                                       int width = 0, const PixelSamples* samples = nullptr,
                                       std::vector<glm::vec3>* indirect = nullptr);

}  // namespace deltagi
