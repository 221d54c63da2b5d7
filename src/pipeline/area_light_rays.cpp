#include "pipeline/area_light_rays.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include "core/brdf.h"
#include "core/brdf_sampling.h"
#include "pipeline/cone_trace.h"

namespace deltagi {

namespace {

constexpr int64_t kPointGrain = 64;
constexpr uint32_t kAreaLightStream = 7000;  // hashToUnit streams of the sample grid's offsets
constexpr uint32_t kEnvironmentStream = 7100;
// A point's rays against the scene alone are traced in packets from this many on (the photo-less
// background's, kBackgroundRayFactor times options.shadow.area_ray_samples).
constexpr int kPacketRays = 16;
// The widest grid of rays per point (options.shadow.area_ray_samples allows at most 256 = 16 x 16).
constexpr int kMaxRaySide = 16;
// Radians beyond a relit point's cull limit before a whole row of the map is passed over: far more than the
// floats' error in the pixel centres (about 1e-6), so that the row test never culls a sample the pixel test
// keeps (bit for bit the same samples).
constexpr float kRowCullMargin = 0.01f;

// What both kinds of rays need: the objects' layer (if any), the origins' offset, the objects' bounding
// sphere, and the sample grid of options.shadow.area_ray_samples.
struct RaySetup {
    const RayScene* objects;
    float offset;
    glm::vec3 objectCentre{0.0f};
    float objectRadius = 0.0f;
    int side, count;
    RaySetup(const ShadowRayScenes& rays, const Options& options)
        : objects(rays.objects && !rays.objectBounds.empty() ? rays.objects : nullptr),
          offset(shadowRayOffset(*rays.scene)),
          count(squareSampleCount(std::min(options.shadow.areaRaySamples, kMaxRaySide * kMaxRaySide))) {
        if (objects) {
            objectCentre = rays.objectBounds.center();
            objectRadius = rays.boundingRadius();
        }
        side = static_cast<int>(std::lround(std::sqrt(static_cast<float>(count))));
    }
};

// The cone of directions from a point towards a sphere (the objects' bounding sphere), for sampling it
// uniformly; invalid from inside the sphere.
struct ObjectCone {
    glm::vec3 axis{0.0f};
    float cosHalfAngle = 1.0f;
    bool valid() const { return cosHalfAngle < 1.0f; }
    float pdf() const { return 1.0f / (2.0f * std::numbers::pi_v<float> * (1.0f - cosHalfAngle)); }
};
ObjectCone objectCone(glm::vec3 origin, glm::vec3 centre, float radius) {
    const glm::vec3 toCentre = centre - origin;
    const float distance = glm::length(toCentre);
    // From inside (or at the surface of) the sphere every direction may meet the objects: no cone.
    if (!(radius > 0.0f) || !(distance > 1.001f * radius)) return {};
    const float sinHalfAngle = radius / distance;
    return {toCentre / distance, std::sqrt(1.0f - sinHalfAngle * sinHalfAngle)};
}

}  // namespace

PixelRect relitEmitterRect(const Camera& camera, const AreaLights& emitters, const ShadowRayScenes& rays,
                           const PixelRect& bounds, int margin) {
    if (emitters.anyVirtual()) return bounds;
    return shadowVolumeRect(camera, relitEmitterVolume(emitters.bounds(), rays), bounds, margin);
}

std::vector<glm::vec3> traceAreaLightRays(std::span<const SurfacePoint> points, const AreaLights& emitters,
                                          const ShadowRayScenes& rays, const Options& options,
                                          ShadowMode mode, std::span<const uint32_t> pixels) {
    std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
    if (emitters.empty() || !rays.scene) return out;
    const auto [objects, offset, objectCentre, objectRadius, side, count] = RaySetup(rays, options);

    forEachValidPoint(points, pixels, kPointGrain, [&](int64_t i) {
        const SurfacePoint& p = points[i];
        const SurfaceMaterial& m = p.surface;
        if (m.diffuse == glm::vec3(0.0f) && m.specular == glm::vec3(0.0f)) return;
        const glm::vec3 origin = p.position + offset * p.normal;
        const float jitterU = hashToUnit(i, kAreaLightStream), jitterV = hashToUnit(i, kAreaLightStream + 1);
        const float jitterT = hashToUnit(i, kAreaLightStream + 2);
        glm::vec3 sum(0.0f);
        // Sample k: a jittered grid over the point on the triangle, and a stratified (permuted) triangle
        // choice; nothing where the point cannot see it (behind either, or touching).
        struct Ray {
            AreaLightSample s;
            glm::vec3 wi;
            float d2, tMax, cosSurface, cosLight;
        };
        auto sampleRay = [&](int k) -> std::optional<Ray> {
            const auto [u1, u2] = jitteredGridPoint(k, side, jitterU, jitterV);
            const float uTriangle =
                (static_cast<float>((k * 5 + 3) % count) + jitterT) / static_cast<float>(count);
            const AreaLightSample s = emitters.sample(uTriangle, u1, u2);
            const glm::vec3 toLight = s.position - origin;
            const float d2 = glm::dot(toLight, toLight);
            if (!(d2 > 0.0f) || !(s.pdfArea > 0.0f)) return std::nullopt;
            const float d = std::sqrt(d2);
            const glm::vec3 wi = toLight / d;
            const float cosSurface = glm::dot(wi, p.normal);
            const float cosLight = std::abs(glm::dot(wi, s.normal));
            const float tMax = d - 2.0f * offset;
            if (cosSurface <= 0.0f || !(cosLight > 0.0f) || !(tMax > 0.0f)) return std::nullopt;
            return Ray{s, wi, d2, tMax, cosSurface, cosLight};
        };
        if (mode == ShadowMode::SceneOnly && count >= kPacketRays && !rays.scene->base()) {
            // Many rays against the scene alone (a background without a photo's), from one point: in packets.
            thread_local std::vector<glm::vec3> directions, light;
            thread_local std::vector<float> reach;
            thread_local std::vector<uint8_t> blocked;
            directions.assign(static_cast<size_t>(count), glm::vec3(0.0f));
            light.assign(static_cast<size_t>(count), glm::vec3(0.0f));
            reach.assign(static_cast<size_t>(count), 0.0f);  // 0: no ray
            blocked.resize(static_cast<size_t>(count));
            for (int k = 0; k < count; ++k) {
                const std::optional<Ray> r = sampleRay(k);
                if (!r || r->s.isVirtual) continue;
                directions[k] = r->wi;
                reach[k] = r->tMax;
                light[k] = evalBrdf(m, p.normal, p.toEye, r->wi) * r->s.radiance *
                           (r->cosSurface * r->cosLight / (r->d2 * r->s.pdfArea));
            }
            rays.scene->occludedCoherent(origin, directions, reach, blocked);
            for (int k = 0; k < count; ++k)
                if (reach[k] > 0.0f && !blocked[k]) sum += light[k];
            out[i] = sum / static_cast<float>(count);
            return;
        }
        for (int k = 0; k < count; ++k) {
            const std::optional<Ray> r = sampleRay(k);
            if (!r) continue;
            const auto& [s, wi, d2, tMax, cosSurface, cosLight] = *r;
            // Whether the objects can be in the way at all; a real emitter's light they cannot block does not
            // change.
            const bool mayMeetObjects =
                objects && segmentMayMeetBox(origin, s.position, 0.0f, rays.objectBounds);
            if (mode == ShadowMode::SceneOnly && s.isVirtual) continue;
            if (mode == ShadowMode::DeltaShadow && !s.isVirtual && !mayMeetObjects) continue;
            const bool byObjects = mayMeetObjects && mode != ShadowMode::SceneOnly &&
                                   objects->occludedTopLayer(origin, wi, 0.0f, tMax);
            if (mode == ShadowMode::DeltaShadow && !s.isVirtual && !byObjects) continue;
            float visibility = 0.0f;  // of the light, or its change
            switch (mode) {
                case ShadowMode::Shaded:
                    visibility = !byObjects && !rays.scene->occluded(origin, wi, 0.0f, tMax) ? 1.0f : 0.0f;
                    break;
                case ShadowMode::SceneOnly:
                    visibility = rays.scene->occluded(origin, wi, 0.0f, tMax) ? 0.0f : 1.0f;
                    break;
                case ShadowMode::DeltaShadow: {
                    const bool byScene = rays.scene->occluded(origin, wi, 0.0f, tMax);
                    // A virtual emitter adds its light where nothing blocks it; a real one loses it where
                    // only the objects block it.
                    visibility =
                        s.isVirtual ? (!byObjects && !byScene ? 1.0f : 0.0f) : (byScene ? 0.0f : -1.0f);
                    break;
                }
                case ShadowMode::DeltaSingleVisibility: {
                    const bool blocked = byObjects || rays.scene->occluded(origin, wi, 0.0f, tMax);
                    visibility = s.isVirtual ? (blocked ? 0.0f : 1.0f) : (blocked ? -1.0f : 0.0f);
                    break;
                }
            }
            if (visibility == 0.0f) continue;
            sum += evalBrdf(m, p.normal, p.toEye, wi) * s.radiance *
                   (visibility * cosSurface * cosLight / (d2 * s.pdfArea));
        }
        out[i] = sum / static_cast<float>(count);
    });
    return out;
}

std::vector<glm::vec3> traceEnvironmentRays(std::span<const SurfacePoint> points,
                                            const EnvironmentSampler& sampler, const ShadowRayScenes& rays,
                                            const Options& options, ShadowMode mode,
                                            std::span<const uint32_t> pixels) {
    std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
    if (!rays.scene) return out;
    const auto [objects, offset, objectCentre, objectRadius, side, count] = RaySetup(rays, options);

    forEachValidPoint(points, pixels, kPointGrain, [&](int64_t i) {
        const SurfacePoint& p = points[i];
        const SurfaceMaterial& m = p.surface;
        if (m.diffuse == glm::vec3(0.0f) && m.specular == glm::vec3(0.0f)) return;
        const glm::vec3 origin = p.position + offset * p.normal;
        const float jitterU = hashToUnit(i, kEnvironmentStream),
                    jitterV = hashToUnit(i, kEnvironmentStream + 1);
        // A relit point whose rays cannot reach the objects does not change.
        const bool objectsBelowHorizon = glm::length(objectCentre - origin) > objectRadius &&
                                         glm::dot(objectCentre - origin, p.normal) < -objectRadius;
        if (mode == ShadowMode::DeltaShadow && (!objects || objectsBelowHorizon)) return;
        // Relit: only directions towards the objects change, so a second set of samples is drawn uniformly
        // over the cone of directions of their bounding sphere, and both sets are combined by multiple
        // importance sampling (balance heuristic). The map's samples alone left most points near the objects
        // with one or two rays that meet them: a speckled shadow.
        const ObjectCone cone =
            mode == ShadowMode::DeltaShadow ? objectCone(origin, objectCentre, objectRadius) : ObjectCone{};
        // The cone's pdf per solid angle (0 outside it): the other term of the map's samples' balance
        // heuristic (both sets have `count` samples).
        auto conePdf = [&](glm::vec3 wi) {
            return cone.valid() && glm::dot(wi, cone.axis) >= cone.cosHalfAngle ? cone.pdf() : 0.0f;
        };
        EnvironmentOcclusion occlusion(objects, *rays.scene, origin);
        glm::vec3 sum(0.0f);
        // A cone wholly in the map's dark part (below a fish-eye light camera's horizon) gives nothing.
        if (cone.valid() && !sampler.darkCone(cone.axis, std::acos(cone.cosHalfAngle))) {
            const float jitterS = hashToUnit(i, kEnvironmentStream + 2),
                        jitterT = hashToUnit(i, kEnvironmentStream + 3);
            const glm::mat3 frame = frameAround(cone.axis);
            // The grid's columns share their angle from the axis, its rows their angle about it (point
            // c * (side + 1) of the grid lies in column c and row c).
            std::array<float, kMaxRaySide> cosThetas, sinThetas, cosPhis, sinPhis;
            for (int c = 0; c < side; ++c) {
                const glm::vec2 u = jitteredGridPoint(c * (side + 1), side, jitterS, jitterT);
                cosThetas[c] = 1.0f - u.x * (1.0f - cone.cosHalfAngle);
                sinThetas[c] = std::sqrt(std::max(0.0f, 1.0f - cosThetas[c] * cosThetas[c]));
                const float phi = 2.0f * std::numbers::pi_v<float> * u.y;
                cosPhis[c] = std::cos(phi);
                sinPhis[c] = std::sin(phi);
            }
            for (int k = 0; k < count; ++k) {
                const int c = k % side, r = k / side;
                const glm::vec3 wi = glm::normalize(
                    frame * glm::vec3(sinThetas[c] * cosPhis[r], sinThetas[c] * sinPhis[r], cosThetas[c]));
                const float cosSurface = glm::dot(wi, p.normal);
                if (cosSurface <= 0.0f) continue;
                const EnvironmentSampler::Value map = sampler.value(wi);
                if (map.radiance == glm::vec3(0.0f) || !occlusion.objectsOnly(wi)) continue;
                const float pdf = cone.pdf();
                const float weight = pdf / (pdf + map.pdf);
                sum -= evalBrdf(m, p.normal, p.toEye, wi) * map.radiance * (cosSurface * weight / pdf);
            }
        }
        // Relit: a map sample counts only if its ray may meet the objects' sphere (coneMayMeetSphere below).
        // Most do not; those whose pixel lies farther from the sphere's direction than the sphere's angular
        // radius plus the pixel's own are passed over before they are drawn (the same samples count).
        // A sample whose pixel's row lies farther in elevation from the sphere's direction than that, by a
        // margin for the floats, is passed over before its column is looked up (the same samples count).
        float cullCos = -2.0f;  // no culling
        glm::vec3 cullAxis(0.0f);
        float cullElevation = 0.0f, cullRowLimit = 0.0f;
        if (mode == ShadowMode::DeltaShadow) {
            const glm::vec3 toCentre = objectCentre - origin;
            const float distance = glm::length(toCentre);
            const float limit = distance > objectRadius
                                    ? std::asin(objectRadius / distance) + sampler.pixelRadius() + 1e-3f
                                    : std::numbers::pi_v<float>;
            if (limit < std::numbers::pi_v<float>) {
                cullAxis = toCentre / distance;
                cullCos = std::cos(limit);
                cullElevation = sampler.elevationOf(cullAxis);
                cullRowLimit = limit + kRowCullMargin;
            }
        }
        // The grid's columns share their u1, so their row and its test: found once per column.
        std::array<int, kMaxRaySide> rows;
        std::array<bool, kMaxRaySide> rowKept;
        if (cullCos > -2.0f)
            for (int c = 0; c < side; ++c) {
                rows[c] = sampler.rowOf(jitteredGridPoint(c, side, jitterU, jitterV).x);
                rowKept[c] = std::abs(sampler.rowElevation(rows[c]) - cullElevation) <= cullRowLimit;
            }
        for (int k = 0; k < count; ++k) {
            const auto [u1, u2] = jitteredGridPoint(k, side, jitterU, jitterV);
            EnvironmentSampler::Sample s;
            if (cullCos > -2.0f) {
                const int c = k % side;
                if (!rowKept[c]) continue;
                const glm::ivec2 pixel(sampler.columnOf(rows[c], u2), rows[c]);
                if (glm::dot(sampler.pixelCentre(pixel), cullAxis) < cullCos) continue;
                s = sampler.sample(u1, u2, pixel);
            } else {
                s = sampler.sample(u1, u2);
            }
            const float cosSurface = glm::dot(s.wi, p.normal);
            if (!(s.pdf > 0.0f) || cosSurface <= 0.0f || s.radiance == glm::vec3(0.0f)) continue;
            const bool mayMeetObjects = objects && mode != ShadowMode::SceneOnly &&
                                        coneMayMeetSphere(origin, s.wi, 0.0f, objectCentre, objectRadius);
            if (mode == ShadowMode::DeltaShadow && !mayMeetObjects) continue;
            float visibility = 0.0f;
            switch (mode) {
                case ShadowMode::Shaded:
                case ShadowMode::SceneOnly:
                    visibility = occlusion.either(s.wi, mayMeetObjects) ? 0.0f : 1.0f;
                    break;
                case ShadowMode::DeltaShadow:
                    visibility = occlusion.objectsOnly(s.wi) ? -1.0f : 0.0f;
                    break;
                case ShadowMode::DeltaSingleVisibility:
                    visibility = occlusion.either(s.wi, mayMeetObjects) ? -1.0f : 0.0f;
                    break;
            }
            if (visibility == 0.0f) continue;
            const float weight = cone.valid() ? s.pdf / (s.pdf + conePdf(s.wi)) : 1.0f;
            sum += evalBrdf(m, p.normal, p.toEye, s.wi) * s.radiance *
                   (visibility * cosSurface * weight / s.pdf);
        }
        out[i] = sum / static_cast<float>(count);
    });
    return out;
}

std::vector<Light> emitterStandInLights(const Scene& scene, const RayScene& realOnly) {
    std::vector<Light> lights;
    const Bounds3f bounds = realOnly.bounds();
    const float extent = bounds.empty() ? 1.0f : bounds.maxExtent();
    for (const TriangleMesh& mesh : scene.real) {
        if (!mesh.material.emits()) continue;
        double area = 0.0;
        glm::dvec3 centroid(0.0), normal(0.0), emitted(0.0);
        for (unsigned i = 0; i < mesh.triangles.size(); ++i) {
            const glm::uvec3 t = mesh.triangles[i];
            const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
            const glm::vec3 cross = glm::cross(b - a, c - a);
            const double triangleArea = 0.5 * glm::length(cross);
            area += triangleArea;
            emitted += triangleArea * glm::dvec3(triangleEmission(mesh, i));
            centroid += triangleArea * glm::dvec3(a + b + c) / 3.0;
            normal += 0.5 * glm::dvec3(cross);
        }
        // Only flat emitters (a panel, a screen) get stand-ins: a closed one (a glowing ball) has no side to
        // face, and its centroid lies inside it. Its light still reaches surfaces directly, by rays.
        if (!(area > 0.0) || !(glm::length(normal) >= 0.5 * area)) continue;
        const glm::vec3 centre(centroid / area);
        const glm::vec3 n(glm::normalize(normal));
        for (const float sideSign : {1.0f, -1.0f}) {
            const glm::vec3 facing = sideSign * n;
            const glm::vec3 position = centre + (1e-4f * extent) * facing;
            // A side set against another surface (within 1% of the scene's size) sends nothing out.
            const RayHit hit = realOnly.intersect(centre, facing, 1e-5f * extent);
            if (hit.hit() && hit.t < 0.01f * extent) continue;
            Light light;
            light.type = Light::Type::Spot;
            light.lambertian = true;
            light.position = position;
            light.direction = facing;
            light.innerAngleDeg = light.outerAngleDeg = 90.0f;
            // An emissive texture's mean over the panel; without one, the material's emission.
            light.color = mesh.material.emissiveTexture ? glm::vec3(emitted / area) : mesh.material.emission;
            // A Lambertian emitter of radiance L and area A sends L A cos(theta) per steradian.
            light.intensity = static_cast<float>(area);
            lights.push_back(light);
        }
    }
    return lights;
}

}  // namespace deltagi
