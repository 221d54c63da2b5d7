// The reference path tracer's core: unidirectional paths with next-event estimation towards every light at
// every vertex, BRDF importance sampling (brdf_sampling.h) and Russian roulette. Emissive surfaces are lit by
// both strategies, next-event estimation of one point on the emitters (area_lights.h) and the BRDF-sampled
// ray that hits one, weighted by multiple importance sampling (Veach 1997, the power heuristic).
// renderReference() (include/deltagi/reference.h) runs it twice per camera sample, with and without the
// virtual objects.
#pragma once

#include <span>

#include <glm/glm.hpp>

#include "core/area_lights.h"
#include "core/environment_sampling.h"
#include "core/lights.h"
#include "core/ray_scene.h"
#include "core/rng.h"
#include "deltagi/scene.h"

namespace deltagi {

// One point on a light, as seen from p: like sampleLight(), but a point or spot light with a radius is a
// sphere whose silhouette disk (facing p) is sampled uniformly by (u1, u2): averaging over many samples gives
// the penumbra of a sphere light of the same intensity. Directional lights and lights without a radius ignore
// (u1, u2).
LightSample sampleLightPoint(const Light& light, glm::vec3 p, float u1, float u2);

struct PathSettings {
    int rouletteStartBounce = 3;  // vertices from this index on (0 = first hit) continue with probability q
    int maxBounces = 256;         // a safety bound
    float rayOffset = 1e-4f;      // world units; see kRayOffsetScale (core/ray_scene.h)
};

class PathTracer {
  public:
    // Holds references: `rays`, `areaLights` (the emitters of the same meshes), `lights` and `environment`
    // must outlive the tracer. Lights extracted from the environment map (Light::fromEnvironment) are
    // skipped: the map itself is sampled, when there is one.
    PathTracer(const RayScene& rays, const AreaLights& areaLights, std::span<const Light> lights,
               PathSettings settings, const EnvironmentSampler* environment = nullptr)
        : rays_(rays),
          areaLights_(areaLights),
          lights_(lights),
          settings_(settings),
          environment_(environment) {}

    // Radiance arriving at `origin` from `direction` (unit): what the surface it hits emits and reflects, or
    // the environment when it leaves the scene. Point, spot and directional lights are not visible to the
    // ray.
    glm::vec3 radiance(glm::vec3 origin, glm::vec3 direction, Rng& rng) const;
    // The same, when the first hit along `direction` is already known.
    glm::vec3 radianceFromHit(const RayHit& firstHit, glm::vec3 direction, Rng& rng) const;
    // Direct light reflected towards wo at a hit, one sample per light (2 random numbers per light, always
    // drawn, so that paths with and without the objects consume the same sequence), and one sample of the
    // environment (2 more numbers) weighted against BRDF sampling by the power heuristic (MIS).
    glm::vec3 directLight(const RayHit& hit, glm::vec3 wo, Rng& rng) const;
    // Light from emissive surfaces reflected towards wo at a hit: one point on the emitters, weighted by the
    // power heuristic against BRDF sampling (3 random numbers, always drawn).
    glm::vec3 emittedLight(const RayHit& hit, glm::vec3 wo, Rng& rng) const;

  private:
    glm::vec3 offsetOrigin(const RayHit& hit, glm::vec3 towards) const;
    glm::vec3 environmentLight(const RayHit& hit, glm::vec3 wo, float u1, float u2) const;

    const RayScene& rays_;
    const AreaLights& areaLights_;
    std::span<const Light> lights_;
    PathSettings settings_;
    const EnvironmentSampler* environment_;
};

}  // namespace deltagi
