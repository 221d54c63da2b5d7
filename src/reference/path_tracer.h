// The reference path tracer's core: unidirectional paths with next-event estimation towards every light at
// every vertex, BRDF importance sampling (brdf_sampling.h) and Russian roulette. Sphere lights (a point or
// spot light with a radius) and emissive surfaces are lit by both strategies, next-event estimation of one
// point on the emitters (area_lights.h) and the BRDF-sampled ray that hits one, weighted by multiple
// importance sampling (Veach 1997, the power heuristic). renderReference() (include/deltagi/reference.h)
// takes two paths per camera sample, with and without the virtual objects (DifferentialPathTracer: one path
// while they are the same).
#pragma once

#include <span>

#include <glm/glm.hpp>

#include "core/area_lights.h"
#include "core/brdf_sampling.h"
#include "core/environment_sampling.h"
#include "core/lights.h"
#include "core/ray_scene.h"
#include "core/sampler.h"
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

// A path between two vertices: the hit it is at (vertex `bounce`, 0 = the camera ray's), what it carries and
// what it has gathered so far.
struct PathState {
    RayHit hit;
    glm::vec3 direction{0.0f};  // of the ray that reached `hit`
    glm::vec3 throughput{1.0f};
    glm::vec3 radiance{0.0f};
    glm::vec3 previousPosition{0.0f};  // the vertex before, and the pdf of the BRDF sample that left it
    float previousPdf = 0.0f;
    int bounce = 0;
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
    glm::vec3 radiance(glm::vec3 origin, glm::vec3 direction, Sampler& sampler) const;
    // The same, when the first hit along `direction` is already known.
    glm::vec3 radianceFromHit(const RayHit& firstHit, glm::vec3 direction, Sampler& sampler) const;
    // Continues `path` (at a hit) until it ends, adding what it gathers to path.radiance.
    void trace(PathState& path, Sampler& sampler) const;
    // Direct light reflected towards wo at a hit, one sample per light (2 random numbers per light, always
    // drawn, so that paths with and without the objects consume the same sequence), and one sample of the
    // environment (2 more numbers) weighted against BRDF sampling by the power heuristic (MIS).
    glm::vec3 directLight(const RayHit& hit, glm::vec3 wo, Sampler& sampler) const;
    // Light from emissive surfaces reflected towards wo at a hit: one point on the emitters, weighted by the
    // power heuristic against BRDF sampling (3 random numbers, always drawn).
    glm::vec3 emittedLight(const RayHit& hit, glm::vec3 wo, Sampler& sampler) const;

  private:
    friend class DifferentialPathTracer;
    glm::vec3 offsetOrigin(const RayHit& hit, glm::vec3 towards) const;
    // The light samples of directLight(): add(origin, direction, tMax, value) for each that brings light if
    // nothing lies between (origin + t direction, t < tMax; the caller tests the visibility).
    template <typename Add>
    void sampleLights(const RayHit& hit, glm::vec3 wo, Sampler& sampler, Add&& add) const;
    // The emitter sample of emittedLight() for its three random numbers, the same way.
    template <typename Add>
    void sampleEmitters(const RayHit& hit, glm::vec3 wo, float uTriangle, float u1, float u2,
                        Add&& add) const;
    // The MIS weight of an emitter that a BRDF sample of pdf `previousPdf` from `previousPosition` met at
    // `at` along `direction`, against emittedLight()'s sample of it.
    float emitterWeight(const RayHit& at, glm::vec3 direction, glm::vec3 previousPosition,
                        float previousPdf) const;
    // What the BRDF sample (s, from `hit`) of a path's last allowed vertex brings from `next`, the surface
    // it meets (or the environment it leaves to), with MIS weights; nothing beyond.
    glm::vec3 lastBounceLight(const RayHit& hit, const BrdfSample& s, const RayHit& next) const;
    // What the sphere lights bring along a BRDF sample (s, taken at `position`) whose ray meets `next` (or
    // leaves the scene): the radiance of each light's disk it passes through first, weighted by the power
    // heuristic against directLight()'s point on that disk. Per unit of the path's throughput after the
    // sample. A narrow glossy lobe under a wide lamp finds the lamp this way far more often than by points
    // on the disk.
    glm::vec3 lightsAlong(glm::vec3 position, const BrdfSample& s, const RayHit& next) const;
    // Carries `path` over the BRDF sample `s` taken at its hit: its throughput, Russian roulette (uRoulette)
    // and the direction and MIS state of the next vertex. False when the roulette ends the path.
    bool scatter(PathState& path, const BrdfSample& s, float uRoulette) const;

    const RayScene& rays_;
    const AreaLights& areaLights_;
    std::span<const Light> lights_;
    PathSettings settings_;
    const EnvironmentSampler* environment_;
};

// The two paths of a camera sample in the differential render, with and without the virtual objects, traced
// as one while they are the same path: they draw the same random numbers, so until a ray of the path meets
// an object they visit the same vertices, and only their shadow rays (and the emitters' MIS weights, when an
// object emits) can differ. The shared vertices are traced once, with two visibility tests per shadow ray
// (the real scene, then the objects); where a bounce ray meets an object the two continue apart. The same
// result as two PathTracers run with copies of one random sequence (but for a ray that meets an edge between
// two triangles, which the real scene alone may find on the other one), in about two thirds of the time.
class DifferentialPathTracer {
  public:
    // `with` traces the scene with the objects (its RayScene holds real and virtual meshes), `without` the
    // real scene alone; `objects` holds the virtual meshes alone. All must outlive this.
    DifferentialPathTracer(const PathTracer& with, const PathTracer& without, const RayScene& objects);

    struct Radiance {
        glm::vec3 with{0.0f}, without{0.0f};
    };
    // Both radiances arriving at `origin` from `direction`, whose first hit in the scene with the objects is
    // `firstHit`.
    Radiance radiance(glm::vec3 origin, glm::vec3 direction, const RayHit& firstHit, Sampler& sampler) const;

  private:
    const PathTracer& with_;
    const PathTracer& without_;
    const RayScene& objects_;
    bool sameEmitters_;  // no object emits: both sample the same emitters
};

}  // namespace deltagi
