// Emitting surfaces (materials with an `emission`) as area lights of the DGI pipeline, beside the point,
// spot and directional lights:
//   - their direct light at each G-buffer point, with shadows, by shadow rays towards points sampled over
//     the emitting triangles (by power, as the path tracer's next-event estimation samples them), traced at
//     the shadow cones' sparse pixels and filtered like them;
//   - their indirect light through the reflective shadow maps of stand-in lights: one Lambertian light per
//     emitting real mesh and open side, at its centroid, so that what they light is injected into the light
//     volumes like any other light's.
// Used with options.shadow.method "rays"; with "cones" the emission is injected into the light volumes and
// reaches surfaces through the diffuse cones only (one bounce, no shadows of its own).
#pragma once

#include <limits>
#include <span>
#include <vector>

#include "core/area_lights.h"
#include "core/environment_sampling.h"
#include "pipeline/shadow_rays.h"

namespace deltagi {

// relitShadowRect for traceAreaLightRays under ShadowMode::DeltaShadow: the image rectangle (grown by
// `margin`, within `bounds`) outside which the emitters' light on the real surfaces does not change
// (relitEmitterVolume of the box around their triangles); `bounds` itself where a virtual object emits (its
// light reaches the room wherever it shines).
PixelRect relitEmitterRect(const Camera& camera, const AreaLights& emitters, const ShadowRayScenes& rays,
                           const PixelRect& bounds, int margin);

// The direct radiance each point receives from the emitters `emitters` samples, or its change, under `mode`:
// Shaded, the light through both the scene and the objects; SceneOnly, through the scene alone (the emitters
// of the real scene); DeltaShadow, the change the objects make (the light a real emitter no longer sends,
// plus all a virtual emitter sends); DeltaSingleVisibility, as DeltaShadow with every real emitter's light
// taken as unshadowed by the scene. options.shadow.area_ray_samples rays per point on a jittered grid offset
// per pixel (seeded by the point's index). Traces the points listed in `pixels`, or all of them when it is
// empty; zero for the others and for invalid points.
std::vector<glm::vec3> traceAreaLightRays(std::span<const SurfacePoint> points, const AreaLights& emitters,
                                          const ShadowRayScenes& rays, const Options& options,
                                          ShadowMode mode, std::span<const uint32_t> pixels = {});

// The direct light of the environment map at each point, or its change, under `mode` (as
// traceAreaLightRays): options.shadow.area_ray_samples directions per point drawn by `sampler` (in proportion
// to the map's radiance, as the path tracer draws them), each a shadow ray to infinity through the scene and
// the objects, weighted by the BRDF. With it the map's lights (Light::fromEnvironment) light the volumes
// only, and the sky is not gathered through the cones: the shadows and the ambient occlusion the objects cast
// under the sky are those of the rays.
std::vector<glm::vec3> traceEnvironmentRays(std::span<const SurfacePoint> points,
                                            const EnvironmentSampler& sampler, const ShadowRayScenes& rays,
                                            const Options& options, ShadowMode mode,
                                            std::span<const uint32_t> pixels = {});

// A point's environment rays to infinity, tested against the objects' layer and the real scene, each only
// where the answer needs it. Which goes first is learnt at the point: the scene while it blocks at least one
// ray in kSceneFirstShare of those tested so far (a room's walls hide most of the sky, and its few triangles
// answer faster than a detailed object), else the objects (open ground blocks nothing above it). The
// answers do not depend on the order, only the time does.
class EnvironmentOcclusion {
  public:
    EnvironmentOcclusion(const RayScene* objects, const RayScene& scene, glm::vec3 origin)
        : objects_(objects), scene_(scene), origin_(origin) {}
    // Whether the objects block the ray and the scene does not (the light the objects take from a real
    // surface). Needs the objects' layer.
    bool objectsOnly(glm::vec3 wi) {
        if (sceneFirst()) return !sceneBlocks(wi) && objectsBlock(wi);
        return objectsBlock(wi) && !sceneBlocks(wi);
    }
    // Whether the scene or (where `mayMeetObjects`) the objects block the ray.
    bool either(glm::vec3 wi, bool mayMeetObjects) {
        if (!mayMeetObjects) return sceneBlocks(wi);
        if (sceneFirst()) return sceneBlocks(wi) || objectsBlock(wi);
        return objectsBlock(wi) || sceneBlocks(wi);
    }
    // Whether the next ray tests the scene first.
    bool sceneFirst() const {
        return sceneTests_ < kProbeRays || kSceneFirstShare * sceneBlocked_ >= sceneTests_;
    }

  private:
    // The share of scene rays that must be blocked for the scene to go first, and how many it goes first for
    // before the share is judged.
    static constexpr int kSceneFirstShare = 4, kProbeRays = 2;
    bool sceneBlocks(glm::vec3 wi) {
        const bool blocked = scene_.occluded(origin_, wi, 0.0f, std::numeric_limits<float>::infinity());
        ++sceneTests_;
        sceneBlocked_ += blocked;
        return blocked;
    }
    bool objectsBlock(glm::vec3 wi) const {
        return objects_->occludedTopLayer(origin_, wi, 0.0f, std::numeric_limits<float>::infinity());
    }

    const RayScene* objects_;
    const RayScene& scene_;
    glm::vec3 origin_;
    int sceneTests_ = 0, sceneBlocked_ = 0;
};

// The stand-in lights of the real scene's emitting meshes for the reflective shadow maps: per mesh, a
// Lambertian light (Light::lambertian) at its area-weighted centroid with the mesh's emitted power, facing
// along its mean normal, one per side that is open (a panel set against a ceiling emits downwards only); a
// hair off the surface so that its rays leave it. `realOnly` holds the real scene's triangles.
std::vector<Light> emitterStandInLights(const Scene& scene, const RayScene& realOnly);

}  // namespace deltagi
