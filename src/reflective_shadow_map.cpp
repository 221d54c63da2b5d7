#include "reflective_shadow_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "lights.h"
#include "parallel.h"

namespace deltagi {

namespace {

// One texel's ray; the beam's cross-section at distance t is areaConst + areaPerT2 * t^2.
struct TexelRay {
    glm::vec3 origin, dir, fluxIn;
    float areaConst, areaPerT2;
};

// One face of the map: an orthographic window (directional lights) or a perspective frustum.
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

// The faces of a light's map over a region and the ray of each texel.
class MapLayout {
  public:
    MapLayout(const RayScene& scene, const Light& light, const VolumeRegion& region, int resolution)
        : light_(light), res_(resolution) {
        const Bounds3f regionBounds = region.bounds();
        center_ = regionBounds.center();
        const float radius = 0.5f * std::sqrt(3.0f) * region.size;
        if (light.type == Light::Type::Directional) {
            // Orthographic: a square window across the region's bounding sphere, rays starting outside the
            // scene.
            faces_.push_back(makeFace(light.direction, radius));
            Bounds3f all = scene.bounds();
            all.extend(regionBounds);
            back_ = glm::length(all.diagonal()) + glm::length(center_ - all.center()) + radius;
            return;
        }
        // Point and spot lights: one perspective frustum fitted around the region, or a cube map when the
        // light is inside (or too close to) the region's bounding sphere.
        const glm::vec3 toCenter = center_ - light.position;
        const float dist = glm::length(toCenter);
        if (dist > 1.05f * radius) {
            const float halfAngle = std::asin(radius / dist);
            faces_.push_back(makeFace(toCenter / dist, std::tan(halfAngle) * 1.02f));
        } else {
            const std::array<glm::vec3, 6> axes = {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0),
                                                   glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                                                   glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)};
            for (glm::vec3 a : axes) faces_.push_back(makeFace(a, 1.0f));
        }
    }

    int faceCount() const { return static_cast<int>(faces_.size()); }
    float rayStart() const { return back_; }

    TexelRay ray(int face, int i, int j) const {
        const Face& f = faces_[face];
        const float res = static_cast<float>(res_);
        const float x = (2.0f * (i + 0.5f) / res - 1.0f) * f.halfTan;
        const float y = (1.0f - 2.0f * (j + 0.5f) / res) * f.halfTan;
        const float texelSide = 2.0f * f.halfTan / res;
        if (light_.type == Light::Type::Directional) {
            const glm::vec3 origin = center_ + x * f.right + y * f.up - back_ * f.forward;
            return {origin, f.forward, light_.power() * (texelSide * texelSide), texelSide * texelSide, 0.0f};
        }
        const glm::vec3 d = f.forward + x * f.right + y * f.up;
        const float r2 = 1.0f + x * x + y * y;
        // Solid angle of the texel on the plane at distance 1 (exact to first order).
        const float solidAngle = texelSide * texelSide / (r2 * std::sqrt(r2));
        const glm::vec3 dir = glm::normalize(d);
        const glm::vec3 fluxIn = light_.power() * (spotFalloff(light_, dir) * solidAngle);
        return {light_.position, dir, fluxIn, 0.0f, solidAngle};
    }

    // The texels [i0, i1] x [j0, j1] of `face` whose rays may meet the box `b` (a margin of one texel); none
    // (nullopt) when the box lies outside the face.
    std::optional<std::array<int, 4>> texelsCovering(int face, const Bounds3f& b) const {
        const Face& f = faces_[face];
        float xMin = INFINITY, xMax = -INFINITY, yMin = INFINITY, yMax = -INFINITY;
        for (int c = 0; c < 8; ++c) {
            const glm::vec3 p(c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y,
                              c & 4 ? b.max.z : b.min.z);
            float x, y;
            if (light_.type == Light::Type::Directional) {
                x = glm::dot(p - center_, f.right);
                y = glm::dot(p - center_, f.up);
            } else {
                const glm::vec3 d = p - light_.position;
                const float z = glm::dot(d, f.forward);
                if (z <= 1e-6f * glm::length(d))
                    return std::array<int, 4>{0, res_ - 1, 0, res_ - 1};  // behind
                x = glm::dot(d, f.right) / z;
                y = glm::dot(d, f.up) / z;
            }
            xMin = std::min(xMin, x), xMax = std::max(xMax, x), yMin = std::min(yMin, y),
            yMax = std::max(yMax, y);
        }
        const float res = static_cast<float>(res_);
        auto column = [&](float x) { return (x / f.halfTan + 1.0f) * 0.5f * res - 0.5f; };
        auto row = [&](float y) { return (1.0f - y / f.halfTan) * 0.5f * res - 0.5f; };
        const int i0 = static_cast<int>(std::floor(std::max(column(xMin), -2.0f))) - 1;
        const int i1 = static_cast<int>(std::ceil(std::min(column(xMax), res + 1.0f))) + 1;
        const int j0 = static_cast<int>(std::floor(std::max(row(yMax), -2.0f))) - 1;
        const int j1 = static_cast<int>(std::ceil(std::min(row(yMin), res + 1.0f))) + 1;
        if (i1 < 0 || j1 < 0 || i0 >= res_ || j0 >= res_) return std::nullopt;
        return std::array<int, 4>{std::max(i0, 0), std::min(i1, res_ - 1), std::max(j0, 0),
                                  std::min(j1, res_ - 1)};
    }

  private:
    const Light& light_;
    int res_;
    glm::vec3 center_{0.0f};
    float back_ = 0.0f;
    std::vector<Face> faces_;
};

// The texel (face, i, j) if its ray hits a surface inside the region.
std::optional<RsmTexel> traceTexel(const RayScene& scene, const MapLayout& layout,
                                   const Bounds3f& regionBounds, int res, int face, int i, int j) {
    const auto [origin, dir, fluxIn, areaConst, areaPerT2] = layout.ray(face, i, j);
    if (fluxIn.x <= 0.0f && fluxIn.y <= 0.0f && fluxIn.z <= 0.0f) return std::nullopt;
    const RayHit hit = scene.intersect(origin, dir);
    if (!hit.hit()) return std::nullopt;
    const glm::vec3 p = hit.position;
    if (p.x < regionBounds.min.x || p.y < regionBounds.min.y || p.z < regionBounds.min.z ||
        p.x > regionBounds.max.x || p.y > regionBounds.max.y || p.z > regionBounds.max.z)
        return std::nullopt;
    const float cosTheta = std::max(glm::dot(hit.normal, -dir), kMinCos);
    const float area = (areaConst + areaPerT2 * hit.t * hit.t) / cosTheta;
    const uint32_t index = static_cast<uint32_t>((static_cast<size_t>(face) * res + j) * res + i);
    return RsmTexel{p, hit.normal, hit.material->albedo * fluxIn, area, index};
}

// Renders every face row by row (rows in parallel, then concatenated in order). `rowTexels(face, j, out)`
// appends row j's texels in column order.
template <typename RowTexels>
ReflectiveShadowMap renderRows(const MapLayout& layout, int res, RowTexels&& rowTexels) {
    ReflectiveShadowMap rsm;
    rsm.resolution = res;
    rsm.faces = layout.faceCount();
    rsm.rayStart = layout.rayStart();
    std::vector<std::vector<RsmTexel>> rows(static_cast<size_t>(rsm.faces) * res);
    parallelFor(0, static_cast<int64_t>(rows.size()), 4,
                [&](int64_t r) { rowTexels(static_cast<int>(r / res), static_cast<int>(r % res), rows[r]); });
    for (const auto& row : rows) rsm.texels.insert(rsm.texels.end(), row.begin(), row.end());
    return rsm;
}

// The texels of each face that updateReflectiveShadowMap traces again (see texelsCovering), or nullopt when
// it renders the whole map afresh: objects beyond the scene the base was made for move a directional light's
// ray origins.
using FaceRects = std::vector<std::optional<std::array<int, 4>>>;
std::optional<FaceRects> retracedRects(const MapLayout& layout, const ReflectiveShadowMap& base,
                                       const Bounds3f& changed) {
    if (layout.rayStart() != base.rayStart) return std::nullopt;
    FaceRects rects(layout.faceCount());
    for (int f = 0; f < layout.faceCount(); ++f) rects[f] = layout.texelsCovering(f, changed);
    return rects;
}

}  // namespace

ReflectiveShadowMap renderReflectiveShadowMap(const RayScene& scene, const Light& light,
                                              const VolumeRegion& region, int resolution) {
    const MapLayout layout(scene, light, region, resolution);
    const Bounds3f regionBounds = region.bounds();
    return renderRows(layout, resolution, [&](int face, int j, std::vector<RsmTexel>& row) {
        for (int i = 0; i < resolution; ++i)
            if (auto t = traceTexel(scene, layout, regionBounds, resolution, face, i, j)) row.push_back(*t);
    });
}

ReflectiveShadowMap updateReflectiveShadowMap(const ReflectiveShadowMap& base, const RayScene& scene,
                                              const Light& light, const VolumeRegion& region,
                                              const Bounds3f& changed) {
    const int res = base.resolution;
    const MapLayout layout(scene, light, region, res);
    const std::optional<FaceRects> retraced = retracedRects(layout, base, changed);
    if (!retraced) return renderReflectiveShadowMap(scene, light, region, res);
    const Bounds3f regionBounds = region.bounds();
    const FaceRects& dirty = *retraced;
    auto byIndex = [](const RsmTexel& t, uint32_t index) { return t.index < index; };
    return renderRows(layout, res, [&](int face, int j, std::vector<RsmTexel>& row) {
        // The base's texels of this row, and the columns to trace again.
        const uint32_t rowStart = static_cast<uint32_t>((static_cast<size_t>(face) * res + j) * res);
        auto first = std::lower_bound(base.texels.begin(), base.texels.end(), rowStart, byIndex);
        auto last = std::lower_bound(first, base.texels.end(), rowStart + res, byIndex);
        const auto& rect = dirty[face];
        if (!rect || j < (*rect)[2] || j > (*rect)[3]) {
            row.assign(first, last);
            return;
        }
        const int i0 = (*rect)[0], i1 = (*rect)[1];
        for (auto t = first; t != last && t->index < rowStart + i0; ++t) row.push_back(*t);
        for (int i = i0; i <= i1; ++i)
            if (auto t = traceTexel(scene, layout, regionBounds, res, face, i, j)) row.push_back(*t);
        for (auto t = first; t != last; ++t)
            if (t->index > rowStart + i1) row.push_back(*t);
    });
}

std::vector<TexelRange> retracedTexels(const ReflectiveShadowMap& base, const RayScene& scene,
                                       const Light& light, const VolumeRegion& region,
                                       const Bounds3f& changed) {
    const int res = base.resolution;
    const MapLayout layout(scene, light, region, res);
    const std::optional<FaceRects> rects = retracedRects(layout, base, changed);
    if (!rects) return {{0, std::numeric_limits<uint32_t>::max()}};
    std::vector<TexelRange> ranges;
    for (int face = 0; face < layout.faceCount(); ++face) {
        const auto& rect = (*rects)[face];
        if (!rect) continue;
        for (int j = (*rect)[2]; j <= (*rect)[3]; ++j) {
            const uint32_t rowStart = static_cast<uint32_t>((static_cast<size_t>(face) * res + j) * res);
            ranges.push_back({rowStart + static_cast<uint32_t>((*rect)[0]),
                              rowStart + static_cast<uint32_t>((*rect)[1]) + 1});
        }
    }
    return ranges;
}

}  // namespace deltagi
