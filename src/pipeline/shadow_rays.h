// Stage 6, shadows by rays: the fraction of each light that reaches a G-buffer point, from shadow rays cast
// towards points spread over the light's area, against the real scene's and the virtual objects' triangles.
//
// The paper's shadow cone (§3.5, shading.h) reads the visibility volumes: an occluder smaller than a coarse
// voxel fills it, so its shadow comes out too wide and too dark, and it ends where the volumes end. On a CPU
// a ray against the triangles costs about as much as a cone step, so the default is rays
// (options.shadow.method); the cones stay available. The result has the same form as the cones'
// (ShadowOcclusion), is traced at the same sparse pixels and goes through the same edge-aware filter.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "core/ray_scene.h"
#include "deltagi/scene.h"
#include "pipeline/gbuffer.h"
#include "pipeline/shading.h"

namespace deltagi {

// What shadow rays are cast against.
struct ShadowRayScenes {
    const RayScene* scene = nullptr;    // the real scene alone
    const RayScene* objects = nullptr;  // the virtual objects (only this layer of it is tested); may be null
    Bounds3f objectBounds;              // of the virtual objects: rays that cannot reach it skip `objects`
    // The radius of a sphere about objectBounds' centre that holds the objects (objectSphereRadius); 0: half
    // the box's diagonal. Rays aimed at the objects aim into it.
    float objectRadius = 0.0f;
    float boundingRadius() const {
        return objectRadius > 0.0f ? objectRadius : 0.5f * glm::length(objectBounds.diagonal());
    }
};

// The radius of the smallest sphere about the centre of the meshes' bounding box that holds all their
// vertices: tighter than half the box's diagonal (a ball's is sqrt(3) times smaller).
float objectSphereRadius(std::span<const TriangleMesh> meshes);

// One point on a light for shadow sample (u, v) in [0,1)^2 seen from `p`: the direction towards it and how
// far it is. A sphere light (radius > 0) is sampled uniformly over its disk facing `p` (as the path tracer
// samples it), a directional light with an angular radius over its cone of directions; a light without a
// size always gives its centre (or its direction).
struct ShadowRaySample {
    glm::vec3 wi{0.0f};
    float distance = 0.0f;  // infinity for directional lights
};
ShadowRaySample sampleShadowRay(const Light& light, glm::vec3 p, float u, float v);

// sampleShadowRay for the many samples of one point: what depends on the light and the point alone (the
// disk's or the cone's frame) worked out once.
class ShadowRaySampler {
  public:
    ShadowRaySampler(const Light& light, glm::vec3 p);
    ShadowRaySample operator()(float u, float v) const;

  private:
    glm::vec3 p_, target_, direction_{0.0f};
    glm::mat3 frame_{1.0f};
    float radius_ = 0.0f, oneMinusCos_ = 0.0f;
    bool directional_ = false, sized_ = false;
};

// The culling tests of the relit rays (conservative: a ray they reject cannot meet the objects). Whether a
// segment from `p` to any point within `radius` of `target` can meet `box` (every such segment stays within
// `radius` of the segment p-target, so the box is grown by `radius`; slab test):
bool segmentMayMeetBox(glm::vec3 p, glm::vec3 target, float radius, const Bounds3f& box);
// Whether the ray origin + t direction (unit), 0 <= t <= tMax, passes within `sphereRadius` of
// `sphereCentre`.
bool rayMayMeetSphere(glm::vec3 origin, glm::vec3 direction, float tMax, glm::vec3 sphereCentre,
                      float sphereRadius);
// Whether a ray from `p` within `halfAngle` of `direction` can pass within `sphereRadius` of `sphereCentre`.
bool coneMayMeetSphere(glm::vec3 p, glm::vec3 direction, float halfAngle, glm::vec3 sphereCentre,
                       float sphereRadius);

// Boxes that together hold every point of the real scene (`rays.scene`'s box) from which a relit shadow ray
// (ShadowMode::DeltaShadow, traceShadowRays) towards one of `lights` can meet the objects: a ray from within
// the rays' offset of the point towards any point of a light's disk (or any direction of a directional
// light's cone) that meets the objects' box (a directional light: their bounding sphere). No boxes where no
// ray can meet them (no objects); nullopt where no boxes are sure to hold them (a light's disk reaching into
// the objects' box, a directional light wider than about 69 degrees).
std::optional<std::vector<Bounds3f>> relitShadowVolume(std::span<const Light> lights,
                                                       const ShadowRayScenes& rays);
// The same for rays towards points of the box `emitters` (traceAreaLightRays' real emitters): nullopt where
// the box reaches into the objects'.
std::optional<std::vector<Bounds3f>> relitEmitterVolume(const Bounds3f& emitters,
                                                        const ShadowRayScenes& rays);
// The part of `camera`'s image that `boxes` (relitShadowVolume's, relitEmitterVolume's) cover, grown by
// `margin` pixels on every side and clipped to `bounds`: every point outside it gets zeros from their rays.
// `bounds` itself where the boxes are unknown (nullopt), reach the camera's plane, or the camera has lens
// distortion; empty where there are no boxes.
PixelRect shadowVolumeRect(const Camera& camera, const std::optional<std::vector<Bounds3f>>& boxes,
                           const PixelRect& bounds, int margin);
// shadowVolumeRect of relitShadowVolume(lights, rays).
PixelRect relitShadowRect(const Camera& camera, std::span<const Light> lights, const ShadowRayScenes& rays,
                          const PixelRect& bounds, int margin);

// How far shadow rays start off their surface, as the path tracer offsets its own (so that DGI and its
// reference agree on grazing light): kRayOffsetScale times the scene's size.
float shadowRayOffset(const RayScene& scene);

// A sample count rounded down to a square (a jittered side x side grid), at least 1.
int squareSampleCount(int samples);

// Sample k of a side x side grid over [0, 1)^2, each cell's point offset by (jitterU, jitterV) in [0, 1)
// (the same for every cell of one point: a stratified pattern that differs from point to point).
inline glm::vec2 jitteredGridPoint(int k, int side, float jitterU, float jitterV) {
    return {(static_cast<float>(k % side) + jitterU) / static_cast<float>(side),
            (static_cast<float>(k / side) + jitterV) / static_cast<float>(side)};
}

// Shadow rays per point and light for options.shadow.ray_samples: a square number, 1 for a light without a
// size.
int shadowRayCount(const Light& light, int raySamples);

// For every point and light (index point * lights + light), the fraction of the light's samples that do not
// reach the point (the light's side of the surface, a sample below the horizon counts as blocked): by the
// scene alone, by the objects alone, by both. Points facing away from a light, or out of its reach, get zero,
// as the cones give them. Under ShadowMode::DeltaShadow (relighting), where only scene - combined counts, a
// point whose rays cannot meet the objects, or meet none, gets zeros: its change is zero either way.
// Samples lie on a jittered grid offset per pixel (seeded by the point's index: the same with any number of
// threads). Traces the points listed in `pixels` (indices into `points`), or all of them when it is empty.
// With `samples` (ShadowMode::Shaded; `points` are the pixels of an image `width` wide), a pixel's rays start
// from its sub-samples in turn (at least one ray each) and each ray counts by its cosine there: the fractions
// are those of the light over the pixel's area, which combineLighting multiplies with the mean of the
// sub-samples' unshadowed light.
std::vector<ShadowOcclusion> traceShadowRays(std::span<const SurfacePoint> points,
                                             std::span<const Light> lights, const ShadowRayScenes& rays,
                                             const Options& options, ShadowMode mode,
                                             std::span<const uint32_t> pixels = {},
                                             const PixelSamples* samples = nullptr, int width = 0);

// A sphere light's shadow over a glossy pixel (ShadowMode::Shaded): combineLighting multiplies the pixel's
// unshadowed direct light by the fraction of the light that reaches it, which holds where every point of
// the disk counts alike (a matte surface). A lobe narrower than the disk sees part of it: where a shadow
// covers part of the disk, the highlight is as bright as the part it sees is visible (a gilded band under
// the vase's own rim: 0.06 to 1.2 times the plain fraction along one highlight line). This is the occlusion
// that makes the product right there: 1 - the visible share of the pixel's direct light, from rays towards
// the cells of the disk's quadrature (directLightCells, for lobes at least about 1.4 times narrower than the
// disk) over up to 16 of the pixel's sub-samples `area` (or its point `p`), the `maxRays` cells that carry
// most of that light traced, the rest counted as visible by 1 - `combined`, the plain occlusion. Where no
// sub-sample has such a lobe, `combined` as it is. Deterministic (the cells' centres).
float glossyShadowOcclusion(const SurfacePoint& p, std::span<const SurfacePoint> area, const Light& light,
                            const ShadowRayScenes& rays, float combined, int maxRays);

}  // namespace deltagi
