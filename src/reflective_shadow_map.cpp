#include "reflective_shadow_map.h"

#include <array>
#include <cmath>

#include "lights.h"
#include "parallel.h"

namespace deltagi {

namespace {

// One texel's ray; the beam's cross-section at distance t is areaConst + areaPerT2 * t^2.
struct TexelRay {
    glm::vec3 origin, dir, fluxIn;
    float areaConst, areaPerT2;
};

struct Face {
    glm::vec3 forward, right, up;
    float halfTan;  // perspective: tan of the half field of view; orthographic: half width
};

// An orthonormal basis around `forward`.
Face makeFace(glm::vec3 forward, float halfTan) {
    glm::vec3 helper = std::abs(forward.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
    glm::vec3 right = glm::normalize(glm::cross(forward, helper));
    glm::vec3 up = glm::cross(right, forward);
    return {forward, right, up, halfTan};
}

constexpr float kMinCos = 1e-3f;  // grazing texels: cap the footprint area

// Traces one face; returns its texels that hit inside the region, in row order.
template <typename RayForTexel>
std::vector<RsmTexel> traceFace(const RayScene& scene, const Bounds3f& regionBounds, int res,
                                RayForTexel&& rayForTexel) {
    std::vector<std::vector<RsmTexel>> rows(res);
    parallelFor(0, res, 4, [&](int64_t j) {
        std::vector<RsmTexel>& row = rows[j];
        for (int i = 0; i < res; ++i) {
            const auto [origin, dir, fluxIn, areaConst, areaPerT2] = rayForTexel(i, static_cast<int>(j));
            if (fluxIn.x <= 0.0f && fluxIn.y <= 0.0f && fluxIn.z <= 0.0f) continue;
            RayHit hit = scene.intersect(origin, dir);
            if (!hit.hit()) continue;
            const glm::vec3 p = hit.position;
            if (p.x < regionBounds.min.x || p.y < regionBounds.min.y || p.z < regionBounds.min.z ||
                p.x > regionBounds.max.x || p.y > regionBounds.max.y || p.z > regionBounds.max.z)
                continue;
            float cosTheta = std::max(glm::dot(hit.normal, -dir), kMinCos);
            float area = (areaConst + areaPerT2 * hit.t * hit.t) / cosTheta;
            row.push_back({p, hit.normal, hit.material->albedo * fluxIn, area});
        }
    });
    std::vector<RsmTexel> texels;
    for (auto& row : rows) texels.insert(texels.end(), row.begin(), row.end());
    return texels;
}

}  // namespace

ReflectiveShadowMap renderReflectiveShadowMap(const RayScene& scene, const Light& light,
                                              const VolumeRegion& region, int resolution) {
    ReflectiveShadowMap rsm;
    rsm.resolution = resolution;
    const Bounds3f regionBounds = region.bounds();
    const glm::vec3 center = regionBounds.center();
    const float radius = 0.5f * std::sqrt(3.0f) * region.size;
    const float res = static_cast<float>(resolution);

    if (light.type == Light::Type::Directional) {
        // Orthographic: a square window across the region's bounding sphere, rays starting outside the scene.
        rsm.faces = 1;
        Face face = makeFace(light.direction, radius);
        Bounds3f all = scene.bounds();
        all.extend(regionBounds);
        const float back = glm::length(all.diagonal()) + glm::length(center - all.center()) + radius;
        const float texelSide = 2.0f * radius / res;
        const glm::vec3 fluxIn = light.power() * (texelSide * texelSide);
        rsm.texels = traceFace(scene, regionBounds, resolution, [&](int i, int j) {
            float x = (2.0f * (i + 0.5f) / res - 1.0f) * face.halfTan;
            float y = (1.0f - 2.0f * (j + 0.5f) / res) * face.halfTan;
            glm::vec3 origin = center + x * face.right + y * face.up - back * face.forward;
            return TexelRay{origin, face.forward, fluxIn, texelSide * texelSide, 0.0f};
        });
        return rsm;
    }

    // Point and spot lights: one perspective frustum fitted around the region, or a cube map when the light
    // is inside (or too close to) the region's bounding sphere.
    std::vector<Face> faces;
    const glm::vec3 toCenter = center - light.position;
    const float dist = glm::length(toCenter);
    if (dist > 1.05f * radius) {
        float halfAngle = std::asin(radius / dist);
        faces.push_back(makeFace(toCenter / dist, std::tan(halfAngle) * 1.02f));
    } else {
        const std::array<glm::vec3, 6> axes = {glm::vec3(1, 0, 0),  glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0),
                                               glm::vec3(0, -1, 0), glm::vec3(0, 0, 1),  glm::vec3(0, 0, -1)};
        for (glm::vec3 a : axes) faces.push_back(makeFace(a, 1.0f));
    }
    rsm.faces = static_cast<int>(faces.size());
    for (const Face& face : faces) {
        const float texelSide = 2.0f * face.halfTan / res;
        std::vector<RsmTexel> texels = traceFace(scene, regionBounds, resolution, [&](int i, int j) {
            float x = (2.0f * (i + 0.5f) / res - 1.0f) * face.halfTan;
            float y = (1.0f - 2.0f * (j + 0.5f) / res) * face.halfTan;
            glm::vec3 d = face.forward + x * face.right + y * face.up;
            float r2 = 1.0f + x * x + y * y;
            // Solid angle of the texel on the plane at distance 1 (exact to first order).
            float solidAngle = texelSide * texelSide / (r2 * std::sqrt(r2));
            glm::vec3 dir = glm::normalize(d);
            glm::vec3 fluxIn = light.power() * (spotFalloff(light, dir) * solidAngle);
            return TexelRay{light.position, dir, fluxIn, 0.0f, solidAngle};
        });
        rsm.texels.insert(rsm.texels.end(), texels.begin(), texels.end());
    }
    return rsm;
}

}  // namespace deltagi
