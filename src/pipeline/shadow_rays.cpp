#include "pipeline/shadow_rays.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "core/brdf_sampling.h"
#include "core/lights.h"

namespace deltagi {

namespace {

constexpr int64_t kPointGrain = 64;
// Random streams of hashToUnit for the per-pixel offset of the sample grid (two per light).
constexpr uint32_t kShadowRayStream = 5000;

// The largest k x k grid of G-buffer sub-samples (options.render.samples_per_pixel 16).
constexpr int kMaxPixelSamples = 16;
// A point's shadow rays against the scene alone are traced in packets from this many on (the photo-less
// background's 64 a light, kBackgroundRayFactor).
constexpr int kPacketShadowRays = 16;
// The random stream that rotates which sub-sample each of a pixel's rays starts from (one per light).
constexpr uint32_t kPixelSampleStream = 5500;
// The sub-samples of a pixel whose quadratures glossyShadowOcclusion weighs, at most: quality suite's
// cornell-textured, object_rel_rmse 0.134 with all (64 on a finer grid), 0.123 with 16 (the rays then spread
// over more of the pixel), 0.131 with 8; its shadow stage 233, 119 and 108 ms.
constexpr size_t kGlossyShadowSamples = 16;
// The lobes whose shadow glossyShadowOcclusion weighs: Phong exponent times the light's angular radius
// squared at least this (directLightCells), the disk about 1.4 times as wide as the lobe or wider. Wider
// lobes see the disk about evenly: the textured torus's frame (bench-cornell-torus-textured.json, exponent
// about 33 under a lamp 0.16 rad wide: 0.9-1.2) took 58-61 ms of shadows with any lobe that has a
// quadrature, 16-20 with this (as before); cornell-textured's figures the same with 1.5, 2 or 3, worse with
// 4 (0.123 -> 0.172): its gilded bands' lobes lie between.
constexpr float kGlossyShadowSpread = 2.0f;

}  // namespace

ShadowRaySampler::ShadowRaySampler(const Light& light, glm::vec3 p)
    : p_(p), target_(light.position), directional_(light.type == Light::Type::Directional) {
    if (directional_) {
        direction_ = -light.direction;
        if (light.angularRadius > 0.0f) {
            sized_ = true;
            frame_ = frameAround(direction_);
            oneMinusCos_ = 1.0f - std::cos(light.angularRadius);
        }
        return;
    }
    const glm::vec3 axis = p - light.position;
    const float d = glm::length(axis);
    if (light.radius > 0.0f && d > 0.0f) {
        sized_ = true;
        frame_ = frameAround(axis / d);
        radius_ = light.radius;
    }
}

ShadowRaySample ShadowRaySampler::operator()(float u, float v) const {
    ShadowRaySample s;
    if (directional_) {
        s.distance = std::numeric_limits<float>::infinity();
        s.wi = direction_;
        if (sized_) {
            // Uniform over the cone's solid angle.
            const float cosTheta = 1.0f - u * oneMinusCos_;
            const float sinTheta = std::sqrt(std::max(0.0f, 1.0f - cosTheta * cosTheta));
            const float phi = 2.0f * std::numbers::pi_v<float> * v;
            s.wi = glm::normalize(frame_ *
                                  glm::vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta));
        }
        return s;
    }
    glm::vec3 target = target_;
    if (sized_) {
        const glm::vec2 onDisk = radius_ * concentricDisk(u, v);
        target += frame_ * glm::vec3(onDisk, 0.0f);
    }
    const glm::vec3 toLight = target - p_;
    s.distance = glm::length(toLight);
    s.wi = s.distance > 0.0f ? toLight / s.distance : glm::vec3(0.0f);
    return s;
}

ShadowRaySample sampleShadowRay(const Light& light, glm::vec3 p, float u, float v) {
    return ShadowRaySampler(light, p)(u, v);
}

bool segmentMayMeetBox(glm::vec3 p, glm::vec3 target, float radius, const Bounds3f& box) {
    const glm::vec3 lo = box.min - radius, hi = box.max + radius;
    const glm::vec3 d = target - p;
    float t0 = 0.0f, t1 = 1.0f;
    for (int a = 0; a < 3; ++a) {
        if (std::abs(d[a]) < 1e-12f) {
            if (p[a] < lo[a] || p[a] > hi[a]) return false;
            continue;
        }
        const float inverse = 1.0f / d[a];
        float ta = (lo[a] - p[a]) * inverse, tb = (hi[a] - p[a]) * inverse;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        if (t0 > t1) return false;
    }
    return true;
}

bool coneMayMeetSphere(glm::vec3 p, glm::vec3 direction, float halfAngle, glm::vec3 sphereCentre,
                       float sphereRadius) {
    const glm::vec3 toCentre = sphereCentre - p;
    const float distance = glm::length(toCentre);
    if (distance <= sphereRadius) return true;
    const float angle = std::acos(glm::clamp(glm::dot(toCentre / distance, direction), -1.0f, 1.0f));
    return angle <= halfAngle + std::asin(sphereRadius / distance);
}

bool rayMayMeetSphere(glm::vec3 origin, glm::vec3 direction, float tMax, glm::vec3 sphereCentre,
                      float sphereRadius) {
    const glm::vec3 toCentre = sphereCentre - origin;
    const float t = std::clamp(glm::dot(toCentre, direction), 0.0f, tMax);
    const glm::vec3 apart = toCentre - t * direction;
    return glm::dot(apart, apart) <= sphereRadius * sphereRadius;
}

float objectSphereRadius(std::span<const TriangleMesh> meshes) {
    Bounds3f bounds;
    for (const TriangleMesh& m : meshes) bounds.extend(m.bounds());
    if (bounds.empty()) return 0.0f;
    const glm::vec3 centre = bounds.center();
    float radius2 = 0.0f;
    for (const TriangleMesh& m : meshes)
        for (const glm::vec3& v : m.positions) {
            const glm::vec3 d = v - centre;
            radius2 = std::max(radius2, glm::dot(d, d));
        }
    // A hair wider, so that rounding does not leave a vertex outside.
    return std::sqrt(radius2) * (1.0f + 1e-5f);
}

float shadowRayOffset(const RayScene& scene) {
    const Bounds3f bounds = scene.bounds();
    return kRayOffsetScale * std::max(bounds.empty() ? 1.0f : bounds.maxExtent(), 1e-3f);
}

namespace {

Bounds3f grownBy(Bounds3f b, float d) {
    b.min -= glm::vec3(d);
    b.max += glm::vec3(d);
    return b;
}

Bounds3f intersection(const Bounds3f& a, const Bounds3f& b) {
    Bounds3f both;
    both.min = glm::max(a.min, b.min);
    both.max = glm::min(a.max, b.max);
    return both;
}

// The number of slabs the shadow volume of one light is cut into along its rays (shadowVolumeBoxes): each
// slab's box is tight about its part, where one box about a slanted volume holds much that is not in it.
constexpr int kShadowVolumeSlabs = 16;
// The widest directional light (angular radius, radians: about 69 degrees) whose shadow volume is bounded
// (relitShadowVolume); wider ones change the whole image.
constexpr float kShadowVolumeMaxAngle = 1.2f;

// Boxes that together hold every point p of `scene` (grown by `slack`) whose segment towards a point q of the
// box `from` meets the box `objects`, appended to `boxes`; `distance` is at most the distance from any q to
// any point of `objects`. Such a p is q + t (b - q) = t b + (1 - t) q for a point b of `objects` and t >= 1,
// t at most the scene's diameter over `distance`. For a given t those points form the box t objects + (1 - t)
// from; over a slab of t, [t0, t1], the box around the two at t0 and t1 (each bound is linear in t). The
// slabs grow geometrically, as the volume widens.
void appendSegmentVolume(const Bounds3f& from, float distance, const Bounds3f& objects, const Bounds3f& scene,
                         float slack, std::vector<Bounds3f>& boxes) {
    Bounds3f all = scene;
    all.extend(from);
    const float far = std::max(1.0f, 1.001f * (glm::length(all.diagonal()) + slack) / distance);
    auto at = [&](float t) {
        Bounds3f b;
        b.min = t * objects.min + (1.0f - t) * from.max;
        b.max = t * objects.max + (1.0f - t) * from.min;
        return b;
    };
    for (int k = 0; k < kShadowVolumeSlabs; ++k) {
        const float t0 = std::pow(far, static_cast<float>(k) / kShadowVolumeSlabs);
        const float t1 =
            k + 1 == kShadowVolumeSlabs ? far : std::pow(far, static_cast<float>(k + 1) / kShadowVolumeSlabs);
        Bounds3f slab = at(t0);
        slab.extend(at(t1));
        slab = intersection(slab, scene);
        if (!slab.empty()) boxes.push_back(grownBy(slab, slack));
    }
}

// Boxes that together hold every point of `scene` (the real scene's box, grown by `slack`) from which a ray
// towards `light` (relitShadowVolume) can meet the objects, appended to `boxes`; false where none are sure
// to. `slack` covers the rays' offset from their surface and rounding.
bool shadowVolumeBoxes(const Light& light, const ShadowRayScenes& rays, const Bounds3f& scene, float slack,
                       std::vector<Bounds3f>& boxes) {
    auto add = [&](Bounds3f box, float grow) {
        box = intersection(grownBy(box, grow), scene);
        if (!box.empty()) boxes.push_back(grownBy(box, slack));
    };
    if (light.type == Light::Type::Directional) {
        // A point p whose ray towards the light (w within its angular radius a of wi) meets the objects at s
        // = p + t w, inside their box and their sphere (C, R): p - C = (s - C) - t w, in the ball of radius R
        // plus -t w, t at most the diameter T of the scene and the box. For t in a slab [t0, t1], -t w lies
        // t0 cos(a) to t1 along -wi and at most t1 sin(a) off it: a box in the frame of wi.
        if (!(light.angularRadius < kShadowVolumeMaxAngle)) return false;
        const glm::vec3 wi = -glm::normalize(light.direction);
        const glm::vec3 centre = rays.objectBounds.center();
        Bounds3f all = scene;
        all.extend(grownBy(rays.objectBounds, slack));
        const float reach = 1.001f * glm::length(all.diagonal()) + slack;
        const glm::vec3 helper = std::abs(wi.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
        const glm::vec3 e1 = glm::normalize(glm::cross(wi, helper)), e2 = glm::cross(wi, e1);
        const float cosA = std::cos(light.angularRadius), sinA = std::sin(light.angularRadius);
        for (int k = 0; k < kShadowVolumeSlabs; ++k) {
            const float t0 = reach * static_cast<float>(k) / kShadowVolumeSlabs;
            const float t1 = reach * static_cast<float>(k + 1) / kShadowVolumeSlabs;
            const float side = t1 * sinA;
            Bounds3f slab;
            for (int c = 0; c < 8; ++c)
                slab.extend(centre - (c & 1 ? t1 : t0 * cosA) * wi + (c & 2 ? side : -side) * e1 +
                            (c & 4 ? side : -side) * e2);
            add(slab, rays.boundingRadius() + slack);
        }
        return true;
    }
    // The light's disk lies in the cube of half-side r about L, each of its points at least |b - L| - r from
    // a point b of the objects' box.
    const glm::vec3 light0 = light.position;
    const Bounds3f box = grownBy(rays.objectBounds, slack);
    const float nearest =
        glm::length(glm::max(glm::max(box.min - light0, light0 - box.max), glm::vec3(0.0f)));
    if (!(nearest > light.radius + slack)) return false;  // the light's disk reaches into the box
    appendSegmentVolume(grownBy(Bounds3f{light0, light0}, light.radius), nearest - light.radius, box, scene,
                        slack, boxes);
    return true;
}

// The real scene's box for relitShadowVolume and relitEmitterVolume, grown by the slack they allow the rays'
// offset from their surface (twice: the point and its ray's start) and rounding; nullopt without objects.
struct VolumeScene {
    Bounds3f box;
    float slack;
};
std::optional<VolumeScene> volumeScene(const ShadowRayScenes& rays) {
    if (!rays.scene || !rays.objects || rays.objectBounds.empty()) return std::nullopt;
    const Bounds3f sceneBox = rays.scene->bounds();
    if (sceneBox.empty()) return std::nullopt;
    const float slack = 2.0f * shadowRayOffset(*rays.scene) + 1e-4f * std::max(sceneBox.maxExtent(), 1e-3f);
    return VolumeScene{grownBy(sceneBox, slack), slack};
}

}  // namespace

std::optional<std::vector<Bounds3f>> relitShadowVolume(std::span<const Light> lights,
                                                       const ShadowRayScenes& rays) {
    std::vector<Bounds3f> boxes;
    const std::optional<VolumeScene> scene = volumeScene(rays);
    if (!scene) return boxes;
    for (const Light& light : lights)
        if (!shadowVolumeBoxes(light, rays, scene->box, scene->slack, boxes)) return std::nullopt;
    return boxes;
}

std::optional<std::vector<Bounds3f>> relitEmitterVolume(const Bounds3f& emitters,
                                                        const ShadowRayScenes& rays) {
    std::vector<Bounds3f> boxes;
    const std::optional<VolumeScene> scene = volumeScene(rays);
    if (!scene || emitters.empty()) return boxes;
    const Bounds3f objects = grownBy(rays.objectBounds, scene->slack);
    const float distance = glm::length(
        glm::max(glm::max(objects.min - emitters.max, emitters.min - objects.max), glm::vec3(0.0f)));
    if (!(distance > scene->slack)) return std::nullopt;  // the emitters reach into the objects' box
    appendSegmentVolume(emitters, distance, objects, scene->box, scene->slack, boxes);
    return boxes;
}

PixelRect relitShadowRect(const Camera& camera, std::span<const Light> lights, const ShadowRayScenes& rays,
                          const PixelRect& bounds, int margin) {
    return shadowVolumeRect(camera, relitShadowVolume(lights, rays), bounds, margin);
}

PixelRect shadowVolumeRect(const Camera& camera, const std::optional<std::vector<Bounds3f>>& boxes,
                           const PixelRect& bounds, int margin) {
    if (bounds.empty()) return {};
    if (!boxes || !camera.distortion.none()) return bounds;
    const glm::mat4 cameraFromWorld = glm::inverse(camera.worldFromCamera);
    float u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
    for (const Bounds3f& box : *boxes) {
        const float nearest = 1e-6f * std::max(box.maxExtent(), 1e-3f);
        for (int c = 0; c < 8; ++c) {
            const glm::vec3 corner(c & 1 ? box.max.x : box.min.x, c & 2 ? box.max.y : box.min.y,
                                   c & 4 ? box.max.z : box.min.z);
            const glm::vec3 q(cameraFromWorld * glm::vec4(corner, 1.0f));
            // The box in front of the camera: its image is inside its corners' (a convex set's perspective
            // image is its corners' hull); one reaching the camera's plane may cover any pixel.
            if (!(q.z < -nearest)) return bounds;
            const glm::vec2 image = camera.imagePoint(q);
            u0 = std::min(u0, image.x), u1 = std::max(u1, image.x);
            v0 = std::min(v0, image.y), v1 = std::max(v1, image.y);
        }
    }
    if (!(u0 <= u1) || !(v0 <= v1)) return {};
    // Pixel x's point lies on the ray through x + 0.5: the pixels from floor(u0 - 0.5) to floor(u1 - 0.5),
    // one more on each side against rounding, then the margin; clamped before converting (far corners project
    // far).
    auto clampedPixel = [](float u, int lo, int hi) {
        return static_cast<int>(std::clamp(std::floor(u), static_cast<float>(lo), static_cast<float>(hi)));
    };
    const float pad = static_cast<float>(margin + 1);
    PixelRect rect;
    rect.x0 = clampedPixel(u0 - 0.5f - pad, bounds.x0, bounds.x1);
    rect.x1 = clampedPixel(u1 - 0.5f + pad, bounds.x0 - 1, bounds.x1 - 1) + 1;
    rect.y0 = clampedPixel(v0 - 0.5f - pad, bounds.y0, bounds.y1);
    rect.y1 = clampedPixel(v1 - 0.5f + pad, bounds.y0 - 1, bounds.y1 - 1) + 1;
    if (rect.empty()) return {};
    return rect;
}

int squareSampleCount(int samples) {
    const int side = std::max(1, static_cast<int>(std::sqrt(static_cast<float>(samples)) + 1e-3f));
    return side * side;
}

int shadowRayCount(const Light& light, int raySamples) {
    const bool sized =
        light.type == Light::Type::Directional ? light.angularRadius > 0.0f : light.radius > 0.0f;
    return sized ? squareSampleCount(raySamples) : 1;
}

namespace {

// The occlusion of `light` over a pixel's area, `points` its valid sub-samples (ShadowMode::Shaded): the
// light's jittered grid of samples, at least one per sub-sample, each ray from the next sub-sample in turn
// (starting at `rotation`, and shifted by the grid's row so that no sub-sample sees one column of the light
// only); each ray counts by its cosine at its sub-sample, and rays below a sub-sample's horizon not at all.
ShadowOcclusion pixelAreaOcclusion(std::span<const SurfacePoint* const> points, const Light& light,
                                   const ShadowRayScenes& rays, const Options& options, float offset,
                                   float jitterU, float jitterV, float rotation) {
    ShadowOcclusion o;
    // Out of a spot's cone (or of any light's reach) at every sub-sample: nothing to shadow.
    if (std::none_of(points.begin(), points.end(), [&](const SurfacePoint* q) {
            return sampleLight(light, q->position).irradiance != glm::vec3(0.0f);
        }))
        return o;
    const int n = static_cast<int>(points.size());
    const int lightCount = shadowRayCount(light, options.shadow.raySamples);
    const int side = static_cast<int>(std::lround(std::sqrt(static_cast<float>(lightCount))));
    const int count = std::max(lightCount, n);
    const int first = std::min(static_cast<int>(rotation * static_cast<float>(n)), n - 1);
    const RayScene* objects = rays.objects && !rays.objectBounds.empty() ? rays.objects : nullptr;
    std::array<std::optional<ShadowRaySampler>, kMaxPixelSamples> samplers;  // per sub-sample, on first use
    float total = 0.0f, byObjects = 0.0f, byScene = 0.0f, byEither = 0.0f;
    for (int k = 0; k < count; ++k) {
        const int stratum = k % lightCount;
        const int from = (first + k + stratum / side) % n;
        const SurfacePoint& q = *points[from];
        const auto [u, v] = jitteredGridPoint(stratum, side, jitterU, jitterV);
        if (!samplers[from]) samplers[from].emplace(light, q.position);
        const ShadowRaySample s = (*samplers[from])(u, v);
        const float weight = glm::dot(s.wi, q.normal);
        const float tMax = std::isfinite(s.distance) ? s.distance - 2.0f * offset : s.distance;
        if (!(weight > 0.0f) || !(tMax > 0.0f)) continue;
        const glm::vec3 origin = q.position + offset * q.normal;
        const bool object = objects && objects->occludedTopLayer(origin, s.wi, 0.0f, tMax);
        const bool scene = rays.scene->occluded(origin, s.wi, 0.0f, tMax);
        total += weight;
        byObjects += object ? weight : 0.0f;
        byScene += scene ? weight : 0.0f;
        byEither += object || scene ? weight : 0.0f;
    }
    // Every ray below its sub-sample's horizon: the pixel faces away from the light, its own attached
    // shadow. Occluded, not unoccluded: the edge-aware filter would otherwise spread the light's full
    // visibility from it into the lit-facing pixels next to it (a bright speck inside a torus' shadowed rim).
    o = total > 0.0f ? ShadowOcclusion{byScene / total, byObjects / total, byEither / total}
                     : ShadowOcclusion{1.0f, 1.0f, 1.0f};
    return o;
}

}  // namespace

std::vector<ShadowOcclusion> traceShadowRays(std::span<const SurfacePoint> points,
                                             std::span<const Light> lights, const ShadowRayScenes& rays,
                                             const Options& options, ShadowMode mode,
                                             std::span<const uint32_t> pixels, const PixelSamples* samples,
                                             int width) {
    std::vector<ShadowOcclusion> out(points.size() * lights.size());
    if (lights.empty() || !rays.scene) return out;
    const RayScene* objects = rays.objects && !rays.objectBounds.empty() ? rays.objects : nullptr;
    const bool relit = mode == ShadowMode::DeltaShadow;
    const bool sceneOnly = mode == ShadowMode::SceneOnly;
    const float offset = shadowRayOffset(*rays.scene);
    const glm::vec3 objectCentre = objects ? rays.objectBounds.center() : glm::vec3(0.0f);
    const float objectRadius = objects ? rays.boundingRadius() : 0.0f;

    forEachValidPoint(points, pixels, kPointGrain, [&](int64_t i) {
        const SurfacePoint& p = points[i];
        const glm::vec3 origin = p.position + offset * p.normal;
        const std::span<const SurfacePoint> area =
            samples && mode == ShadowMode::Shaded ? samples->of(i, width) : std::span<const SurfacePoint>{};
        std::array<const SurfacePoint*, kMaxPixelSamples> valid{};
        int validCount = 0;
        for (const SurfacePoint& q : area)
            if (q.valid() && validCount < kMaxPixelSamples) valid[validCount++] = &q;
        for (size_t l = 0; l < lights.size(); ++l) {
            const Light& light = lights[l];
            if (validCount > 0) {
                out[i * lights.size() + l] =
                    pixelAreaOcclusion(std::span(valid.data(), validCount), light, rays, options, offset,
                                       hashToUnit(i, kShadowRayStream + 2 * static_cast<uint32_t>(l)),
                                       hashToUnit(i, kShadowRayStream + 2 * static_cast<uint32_t>(l) + 1),
                                       hashToUnit(i, kPixelSampleStream + static_cast<uint32_t>(l)));
                continue;
            }
            const LightSample centre = sampleLight(light, p.position);
            if (centre.irradiance == glm::vec3(0.0f)) continue;
            if (glm::dot(centre.wi, p.normal) <= 0.0f) {
                // Facing away: its attached shadow (as pixelAreaOcclusion). Relit points carry the change
                // the objects make, none here.
                if (!relit) out[i * lights.size() + l] = {1.0f, 1.0f, 1.0f};
                continue;
            }
            // Relit points whose rays cannot reach the objects do not change: no rays at all.
            bool mayMeetObjects = objects != nullptr && !sceneOnly;
            if (mayMeetObjects && relit) {
                mayMeetObjects =
                    light.type == Light::Type::Directional
                        ? coneMayMeetSphere(origin, centre.wi, light.angularRadius, objectCentre,
                                            objectRadius)
                        : segmentMayMeetBox(origin, light.position, light.radius, rays.objectBounds);
                if (!mayMeetObjects) continue;
            }
            const int count = shadowRayCount(light, options.shadow.raySamples);
            const int side = static_cast<int>(std::lround(std::sqrt(static_cast<float>(count))));
            const float jitterU = hashToUnit(i, kShadowRayStream + 2 * static_cast<uint32_t>(l));
            const float jitterV = hashToUnit(i, kShadowRayStream + 2 * static_cast<uint32_t>(l) + 1);
            // Per sample: blocked by the objects, by the scene; the scene is tested only where needed.
            int byObjects = 0, byScene = 0, byEither = 0;
            const ShadowRaySampler sample(light, p.position);
            // Sample k: its direction, how far it reaches, and whether it is below the horizon (blocked).
            struct Ray {
                glm::vec3 wi;
                float tMax;
                bool horizon;
            };
            auto place = [&](int k) {
                const auto [u, v] = jitteredGridPoint(k, side, jitterU, jitterV);
                const ShadowRaySample s = sample(u, v);
                const float tMax = std::isfinite(s.distance) ? s.distance - 2.0f * offset : s.distance;
                return Ray{s.wi, tMax, glm::dot(s.wi, p.normal) <= 0.0f || !(tMax > 0.0f)};
            };
            if (!relit && !mayMeetObjects && count >= kPacketShadowRays && !rays.scene->base()) {
                // Many rays against the scene alone (a background without a photo's): from one point towards
                // one light they are coherent, traced in packets.
                thread_local std::vector<glm::vec3> directions;
                thread_local std::vector<float> reach;
                thread_local std::vector<uint8_t> blocked;
                directions.resize(static_cast<size_t>(count));
                reach.resize(static_cast<size_t>(count));
                blocked.resize(static_cast<size_t>(count));
                for (int k = 0; k < count; ++k) {
                    const Ray r = place(k);
                    directions[k] = r.wi;
                    reach[k] = r.horizon ? 0.0f : r.tMax;  // not traced: blocked below
                    byObjects += r.horizon;
                }
                rays.scene->occludedCoherent(origin, directions, reach, blocked);
                for (int k = 0; k < count; ++k) byScene += reach[k] <= 0.0f || blocked[k];
                byEither = byScene;
            } else {
                for (int k = 0; k < count; ++k) {
                    const auto [wi, tMax, horizon] = place(k);
                    // A relit ray that passes the objects' sphere by cannot meet them: no query.
                    const bool object =
                        horizon ||
                        (mayMeetObjects &&
                         (!relit || rayMayMeetSphere(origin, wi, tMax, objectCentre, objectRadius)) &&
                         objects->occludedTopLayer(origin, wi, 0.0f, tMax));
                    byObjects += object;
                    // Relit: a sample the objects leave alone does not change.
                    if (relit && !object) continue;
                    const bool scene = horizon || rays.scene->occluded(origin, wi, 0.0f, tMax);
                    byScene += scene;
                    byEither += scene || object;
                }
            }
            if (relit && byObjects == 0) continue;
            const float n = static_cast<float>(count);
            ShadowOcclusion& o = out[i * lights.size() + l];
            o.object = static_cast<float>(byObjects) / n;
            if (relit) {
                // Only the samples the objects block were tested against the scene: those count once in
                // `combined`; the others are the same with and without the objects, so scene and combined
                // carry only the change, which is all that DeltaShadow reads.
                o.scene = 0.0f;
                o.combined = static_cast<float>(byObjects - byScene) / n;
            } else {
                o.scene = static_cast<float>(byScene) / n;
                o.combined = static_cast<float>(byEither) / n;
            }
        }
    });
    return out;
}

float glossyShadowOcclusion(const SurfacePoint& p, std::span<const SurfacePoint> area, const Light& light,
                            const ShadowRayScenes& rays, float combined, int maxRays) {
    struct Candidate {
        float weight;
        const SurfacePoint* from;
        DirectLightCell cell;
    };
    thread_local std::vector<Candidate> candidates;
    thread_local std::vector<DirectLightCell> cells;
    thread_local std::vector<const SurfacePoint*> closedForm;
    candidates.clear();
    closedForm.clear();
    const auto luminance = [](glm::vec3 c) { return (c.x + c.y + c.z) * (1.0f / 3.0f); };
    double total = 0.0;
    const auto gather = [&](const SurfacePoint& q) {
        if (!q.valid()) return;
        directLightCells(q, light, kGlossyShadowSpread, cells);
        if (cells.empty()) {  // a closed form: no cells to trace
            closedForm.push_back(&q);
            return;
        }
        for (const DirectLightCell& c : cells) {
            const float w = luminance(c.radiance);
            if (!(w > 0.0f)) continue;
            total += w;
            candidates.push_back({w, &q, c});
        }
    };
    // At most kGlossyShadowSamples of the sub-samples, spread over the pixel: each costs its quadrature's
    // BRDF evaluations (up to 16 x 16), and the share changes little beyond.
    if (area.empty()) gather(p);
    const size_t stride = (area.size() + kGlossyShadowSamples - 1) / kGlossyShadowSamples;
    for (size_t k = 0; k < area.size(); k += std::max<size_t>(stride, 1)) gather(area[k]);
    if (candidates.empty()) return combined;
    // The sub-samples of a closed form count at the plain fraction.
    double untraced = 0.0;
    for (const SurfacePoint* q : closedForm) untraced += luminance(directRadiance(*q, light));
    total += untraced;
    if (!(total > 0.0)) return combined;
    const size_t traced = std::min(candidates.size(), static_cast<size_t>(std::max(maxRays, 1)));
    std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(traced),
                      candidates.end(),
                      [](const Candidate& a, const Candidate& b) { return a.weight > b.weight; });
    for (size_t k = traced; k < candidates.size(); ++k) untraced += candidates[k].weight;
    const RayScene* objects = rays.objects && !rays.objectBounds.empty() ? rays.objects : nullptr;
    const float offset = shadowRayOffset(*rays.scene);
    double visible = untraced * (1.0 - combined);
    for (size_t k = 0; k < traced; ++k) {
        const Candidate& c = candidates[k];
        const glm::vec3 origin = c.from->position + offset * c.from->normal;
        const float tMax = std::isfinite(c.cell.distance) ? c.cell.distance - 2.0f * offset : c.cell.distance;
        if (!(tMax > 0.0f)) {  // the light touches the point: no ray, as pixelAreaOcclusion
            total -= c.weight;
            continue;
        }
        const bool blocked = (objects && objects->occludedTopLayer(origin, c.cell.wi, 0.0f, tMax)) ||
                             rays.scene->occluded(origin, c.cell.wi, 0.0f, tMax);
        if (!blocked) visible += c.weight;
    }
    if (!(total > 0.0)) return combined;
    return static_cast<float>(std::clamp(1.0 - visible / total, 0.0, 1.0));
}

}  // namespace deltagi
