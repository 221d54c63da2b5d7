#include "pipeline/reflective_shadow_map.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "core/environment.h"
#include "core/lights.h"
#include "core/parallel.h"

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

// Whether the ray from `origin` along `dir` (t >= 0) meets the box `b` (slab test; a component of `dir` that
// is zero meets the box's slab only from inside it).
bool rayMeetsBox(glm::vec3 origin, glm::vec3 dir, const Bounds3f& b) {
    float tNear = 0.0f, tFar = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (dir[a] == 0.0f) {
            if (origin[a] < b.min[a] || origin[a] > b.max[a]) return false;
            continue;
        }
        const float inv = 1.0f / dir[a];
        float t0 = (b.min[a] - origin[a]) * inv, t1 = (b.max[a] - origin[a]) * inv;
        if (t0 > t1) std::swap(t0, t1);
        tNear = std::max(tNear, t0);
        tFar = std::min(tFar, t1);
        if (tNear > tFar) return false;
    }
    return true;
}

// The faces of a light's map over a region and the ray of each texel.
class MapLayout {
  public:
    MapLayout(const RayScene& scene, const Light& light, const VolumeRegion& region, int resolution)
        : light_(light), cone_(light), res_(resolution) {
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

    // False when no texel of `face` can carry light: all its directions lie outside the light's reach (a
    // spot's outer cone, a Lambertian emitter's front) by a margin, as the cube-map face above a spot light
    // pointing down.
    bool faceMayCarryLight(int face) const {
        if (light_.type == Light::Type::Directional) return true;
        const Face& f = faces_[face];
        const float toAxis = std::acos(std::clamp(glm::dot(f.forward, light_.direction), -1.0f, 1.0f));
        const float faceRadius = std::atan(f.halfTan * std::numbers::sqrt2_v<float>);  // to its corners
        return toAxis - faceRadius < cone_.reach() + glm::radians(1.0f);
    }
    float rayStart() const { return back_; }

    // False only where ray(face, i, j) carries no light for sure (outside a spot's cone), found without
    // working the ray out.
    bool mayCarryLight(int face, int i, int j) const {
        if (light_.type == Light::Type::Directional) return true;
        const Face& f = faces_[face];
        const glm::vec2 p = texelCentre(face, i, j);
        return cone_.mayReach(f.forward + p.x * f.right + p.y * f.up);
    }

    TexelRay ray(int face, int i, int j) const {
        const Face& f = faces_[face];
        const float res = static_cast<float>(res_);
        const auto [x, y] = texelCentre(face, i, j);
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
        const glm::vec3 fluxIn = light_.power() * (cone_.falloff(dir) * solidAngle);
        return {light_.position, dir, fluxIn, 0.0f, solidAngle};
    }

    // The texels [i0, i1] x [j0, j1] of `face` whose rays may meet the box `b` (a margin of one texel); none
    // (nullopt) when the box lies outside the face. A perspective face's rays only reach the part of the box
    // in front of the light (along the face's axis): the box is clipped to that half-space before it is
    // projected, so that the faces looking away from the objects trace nothing.
    std::optional<std::array<int, 4>> texelsCovering(int face, const Bounds3f& b) const {
        if (b.empty()) return std::nullopt;
        const Face& f = faces_[face];
        float xMin = INFINITY, xMax = -INFINITY, yMin = INFINITY, yMax = -INFINITY;
        auto project = [&](glm::vec3 p, float z) {
            const glm::vec3 d = light_.type == Light::Type::Directional ? p - center_ : p - light_.position;
            const float x = glm::dot(d, f.right), y = glm::dot(d, f.up);
            const float s = light_.type == Light::Type::Directional ? 1.0f : 1.0f / z;
            xMin = std::min(xMin, x * s), xMax = std::max(xMax, x * s);
            yMin = std::min(yMin, y * s), yMax = std::max(yMax, y * s);
        };
        std::array<glm::vec3, 8> corners;
        std::array<float, 8> depth;  // along the face's axis, from the light
        for (int c = 0; c < 8; ++c) {
            corners[c] =
                glm::vec3(c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y, c & 4 ? b.max.z : b.min.z);
            depth[c] = glm::dot(corners[c] - light_.position, f.forward);
        }
        if (light_.type == Light::Type::Directional) {
            for (const glm::vec3& p : corners) project(p, 1.0f);
        } else {
            // Clip at a small depth: the rays of the face leave the light inside its frustum, so a point
            // closer than `nearDepth` to the light's plane is only on a ray when it is within about
            // nearDepth * sqrt(3) of the light, i.e. when the (slightly grown) box holds the light.
            const float nearDepth =
                1e-4f * (glm::length(b.diagonal()) + glm::length(b.center() - light_.position));
            Bounds3f grown = b;
            grown.min -= glm::vec3(2.0f * nearDepth), grown.max += glm::vec3(2.0f * nearDepth);
            if (grown.contains(light_.position)) return std::array<int, 4>{0, res_ - 1, 0, res_ - 1};
            for (int c = 0; c < 8; ++c) {
                if (depth[c] >= nearDepth) project(corners[c], depth[c]);
                for (int axis = 0; axis < 3; ++axis) {  // the box's edges from c to its neighbours
                    const int n = c | (1 << axis);
                    if (n == c || (depth[c] >= nearDepth) == (depth[n] >= nearDepth)) continue;
                    const float t = (nearDepth - depth[c]) / (depth[n] - depth[c]);
                    project(corners[c] + t * (corners[n] - corners[c]), nearDepth);
                }
            }
            if (xMin > xMax) return std::nullopt;  // the box is behind the face
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
    // Texel (i, j)'s centre on `face`'s plane at distance 1 (orthographic: its offset from the centre), along
    // the face's right and up.
    glm::vec2 texelCentre(int face, int i, int j) const {
        const float halfTan = faces_[face].halfTan, res = static_cast<float>(res_);
        return {(2.0f * (i + 0.5f) / res - 1.0f) * halfTan, (1.0f - 2.0f * (j + 0.5f) / res) * halfTan};
    }

    const Light& light_;
    SpotCone cone_;
    int res_;
    glm::vec3 center_{0.0f};
    float back_ = 0.0f;
    std::vector<Face> faces_;
};

// The viewpoint whose side of real surfaces a light's map keeps (renderReflectiveShadowMap): a directional
// light's; none for a point or spot light, which stands in the room.
std::optional<glm::vec3> sideKeptFrom(const Light& light, std::optional<glm::vec3> viewpoint) {
    return light.type == Light::Type::Directional ? viewpoint : std::nullopt;
}

// The texel `index` made from its ray's closest hit, if that hit is on a surface inside the region (and, with
// a viewpoint, on the viewpoint's side of a real surface).
// The hit's textures are looked up here, filtered over the texel's area on the surface (its rays are cast
// with texturesLater): those of its reflectance only, which is all the texel carries into the light volume (a
// normal map's lookup cost the textured benchmark torus's maps ~1 ms a frame for a normal nothing read).
std::optional<RsmTexel> texelFromHit(RayHit hit, const TexelRay& ray, const Bounds3f& regionBounds,
                                     uint32_t index, const std::optional<glm::vec3>& viewpoint) {
    if (!hit.hit() || !regionBounds.contains(hit.position)) return std::nullopt;
    if (viewpoint && !hit.isVirtual && glm::dot(hit.geometricNormal, *viewpoint - hit.position) < 0.0f)
        return std::nullopt;
    const float cosTheta = std::max(glm::dot(hit.normal, -ray.dir), kMinCos);
    const float area = (ray.areaConst + ray.areaPerT2 * hit.t * hit.t) / cosTheta;
    if (hit.varies)
        hit.surface = surfaceMaterialAt(*hit.mesh, hit.triangle, hit.barycentric.x, hit.barycentric.y,
                                        std::sqrt(area), nullptr);
    return RsmTexel{hit.position, hit.normal, hit.surface.volumeReflectance() * ray.fluxIn, area, index};
}

uint32_t texelIndex(int res, int face, int i, int j) {
    return static_cast<uint32_t>((static_cast<size_t>(face) * res + j) * res + i);
}

bool carriesLight(const TexelRay& ray) {
    return ray.fluxIn.x > 0.0f || ray.fluxIn.y > 0.0f || ray.fluxIn.z > 0.0f;
}

// The texel (face, i, j) if its ray hits a surface inside the region.
std::optional<RsmTexel> traceTexel(const RayScene& scene, const MapLayout& layout,
                                   const Bounds3f& regionBounds, int res, int face, int i, int j,
                                   const std::optional<glm::vec3>& viewpoint) {
    const TexelRay ray = layout.ray(face, i, j);
    if (!carriesLight(ray)) return std::nullopt;
    return texelFromHit(scene.intersect(ray.origin, ray.dir, 0.0f, INFINITY, true), ray, regionBounds,
                        texelIndex(res, face, i, j), viewpoint);
}

// traceTexel() over a layered `scene` whose base layer is the scene a map was rendered over, `baseTexel` the
// texel there (null: none). Where the ray misses the top layer, the closest hit is the base layer's, which
// the map holds already: only the rays that meet the objects are traced again below them.
std::optional<RsmTexel> retraceTexel(const RayScene& scene, const MapLayout& layout,
                                     const Bounds3f& regionBounds, int res, int face, int i, int j,
                                     const RsmTexel* baseTexel, const std::optional<glm::vec3>& viewpoint) {
    if (!scene.base()) return traceTexel(scene, layout, regionBounds, res, face, i, j, viewpoint);
    const TexelRay ray = layout.ray(face, i, j);
    if (!carriesLight(ray)) return std::nullopt;
    RayHit hit = scene.intersectTopLayer(ray.origin, ray.dir, 0.0f, INFINITY, true);
    if (!hit.hit()) return baseTexel ? std::optional(*baseTexel) : std::nullopt;
    const RayHit below = scene.base()->intersect(ray.origin, ray.dir, 0.0f, hit.t, true);
    if (below.hit()) hit = below;
    return texelFromHit(hit, ray, regionBounds, texelIndex(res, face, i, j), viewpoint);
}

// Appends `rows` in order to `texels`, grown once to their total and copied into place in parallel (tens of
// MiB for a point light's cube map); with `texelVoxel`, each texel's voxel is appended to `voxels` as it is
// copied.
void appendRows(const std::vector<std::vector<RsmTexel>>& rows, RsmTexels& texels,
                const TexelVoxels* texelVoxel = nullptr,
                std::vector<uint32_t, UnsetAllocator<uint32_t>>* voxels = nullptr) {
    std::vector<size_t> start(rows.size() + 1, texels.size());
    for (size_t r = 0; r < rows.size(); ++r) start[r + 1] = start[r] + rows[r].size();
    texels.resize(start.back());  // not initialized: every new texel (and voxel) is written below
    if (texelVoxel) voxels->resize(start.back());
    parallelFor(0, static_cast<int64_t>(rows.size()), 16, [&](int64_t r) {
        if (!texelVoxel) {
            std::copy(rows[r].begin(), rows[r].end(), texels.begin() + static_cast<ptrdiff_t>(start[r]));
            return;
        }
        for (size_t k = 0, t = start[r]; k < rows[r].size(); ++k, ++t) {
            texels[t] = rows[r][k];
            (*voxels)[t] = texelVoxel->index(rows[r][k].position);
        }
    });
}

// Renders every face row by row, rows in parallel. `rowTexels(face, j, out)` appends row j's texels in column
// order to `out`. The rows are then joined into one block of exactly their size, each texel's voxel in
// `region` found as it is copied: only the texels that hit a surface in the region take memory (a map whose
// rays mostly miss it, an environment light's, stays small).
template <typename RowTexels>
ReflectiveShadowMap renderRows(const MapLayout& layout, int res, const VolumeRegion& region,
                               RowTexels&& rowTexels) {
    ReflectiveShadowMap rsm;
    rsm.resolution = res;
    rsm.faces = layout.faceCount();
    rsm.rayStart = layout.rayStart();
    rsm.voxelRegion = region;
    std::vector<std::vector<RsmTexel>> rows(static_cast<size_t>(rsm.faces) * res);
    parallelFor(0, static_cast<int64_t>(rows.size()), 4,
                [&](int64_t r) { rowTexels(static_cast<int>(r / res), static_cast<int>(r % res), rows[r]); });
    const TexelVoxels texelVoxel(region);
    appendRows(rows, rsm.texels, &texelVoxel, &rsm.voxels);
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
                                              const VolumeRegion& region, int resolution,
                                              std::optional<glm::vec3> viewpoint) {
    viewpoint = sideKeptFrom(light, viewpoint);
    const MapLayout layout(scene, light, region, resolution);
    const Bounds3f regionBounds = region.bounds();
    // A row's rays are traced in packets: a point or spot light's all leave its position, a directional
    // light's are parallel.
    const bool directional = light.type == Light::Type::Directional;
    std::vector<char> faceLit(static_cast<size_t>(layout.faceCount()));
    for (int f = 0; f < layout.faceCount(); ++f)
        faceLit[static_cast<size_t>(f)] = layout.faceMayCarryLight(f);
    // A ray that does not meet the region (grown by a margin against rounding) hits nothing in it: most of a
    // directional light's window, a square around the region's bounding sphere.
    Bounds3f reach = regionBounds;
    const glm::vec3 margin(1e-3f * std::max(regionBounds.maxExtent(), 1e-6f));
    reach.min -= margin, reach.max += margin;
    // A ray from a light inside the box meets it at once.
    const bool fromInside = !directional && reach.contains(light.position);
    return renderRows(layout, resolution, region, [&](int face, int j, std::vector<RsmTexel>& row) {
        if (!faceLit[static_cast<size_t>(face)]) return;
        // A thread's row buffers, kept from row to row.
        thread_local std::vector<TexelRay> rays;
        thread_local std::vector<int> columns;
        thread_local std::vector<glm::vec3> origins, directions;
        thread_local std::vector<RayHit> hits;
        rays.clear();
        columns.clear();
        origins.clear();
        directions.clear();
        for (int i = 0; i < resolution; ++i) {
            if (!layout.mayCarryLight(face, i, j)) continue;
            const TexelRay ray = layout.ray(face, i, j);
            if (!carriesLight(ray) || (!fromInside && !rayMeetsBox(ray.origin, ray.dir, reach))) continue;
            rays.push_back(ray);
            columns.push_back(i);
            if (directional || origins.empty()) origins.push_back(ray.origin);
            directions.push_back(ray.dir);
        }
        hits.resize(rays.size());  // each written in full by intersectCoherent
        scene.intersectCoherent(origins, directions, hits, false, true);
        row.reserve(rays.size());
        for (size_t k = 0; k < rays.size(); ++k)
            if (auto t = texelFromHit(hits[k], rays[k], regionBounds,
                                      texelIndex(resolution, face, columns[k], j), viewpoint))
                row.push_back(*t);
    });
}

RsmUpdate traceRsmUpdate(const ReflectiveShadowMap& base, const RayScene& scene, const Light& light,
                         const VolumeRegion& region, const Bounds3f& changed,
                         std::optional<glm::vec3> viewpoint) {
    viewpoint = sideKeptFrom(light, viewpoint);
    const int res = base.resolution;
    const MapLayout layout(scene, light, region, res);
    const std::optional<FaceRects> rects = retracedRects(layout, base, changed);
    RsmUpdate update;
    update.rayStart = layout.rayStart();
    if (!rects) {
        update.retraced = {{0, std::numeric_limits<uint32_t>::max()}};
        update.texels = renderReflectiveShadowMap(scene, light, region, res, viewpoint).texels;
        return update;
    }
    // One row of a face's rectangle per piece of work.
    struct Row {
        int face, j, i0, i1;
    };
    std::vector<Row> rows;
    for (int face = 0; face < layout.faceCount(); ++face)
        if (const auto& rect = (*rects)[face])
            for (int j = (*rect)[2]; j <= (*rect)[3]; ++j) rows.push_back({face, j, (*rect)[0], (*rect)[1]});
    const Bounds3f regionBounds = region.bounds();
    std::vector<std::vector<RsmTexel>> traced(rows.size());
    auto byIndex = [](const RsmTexel& t, uint32_t index) { return t.index < index; };
    parallelFor(0, static_cast<int64_t>(rows.size()), 4, [&](int64_t r) {
        const auto [face, j, i0, i1] = rows[r];
        auto b =
            std::lower_bound(base.texels.begin(), base.texels.end(), texelIndex(res, face, i0, j), byIndex);
        for (int i = i0; i <= i1; ++i) {
            const uint32_t index = texelIndex(res, face, i, j);
            while (b != base.texels.end() && b->index < index) ++b;
            const RsmTexel* baseTexel = b != base.texels.end() && b->index == index ? &*b : nullptr;
            if (auto t = retraceTexel(scene, layout, regionBounds, res, face, i, j, baseTexel, viewpoint))
                traced[r].push_back(*t);
        }
    });
    appendRows(traced, update.texels);
    update.retraced.reserve(rows.size());
    for (const Row& row : rows)
        update.retraced.push_back(
            {texelIndex(res, row.face, row.i0, row.j), texelIndex(res, row.face, row.i1, row.j) + 1});
    return update;
}

ReflectiveShadowMap applyRsmUpdate(const ReflectiveShadowMap& base, const RsmUpdate& update) {
    ReflectiveShadowMap map;
    map.resolution = base.resolution;
    map.faces = base.faces;
    map.rayStart = update.rayStart;
    map.texels.reserve(base.texels.size() + update.texels.size());
    auto b = base.texels.begin();
    auto u = update.texels.begin();
    for (const TexelRange& range : update.retraced) {
        for (; b != base.texels.end() && b->index < range.first; ++b) map.texels.push_back(*b);
        while (b != base.texels.end() && b->index < range.last) ++b;  // traced again
        for (; u != update.texels.end() && u->index < range.last; ++u) map.texels.push_back(*u);
    }
    map.texels.insert(map.texels.end(), b, base.texels.end());
    return map;
}

ReflectiveShadowMap updateReflectiveShadowMap(const ReflectiveShadowMap& base, const RayScene& scene,
                                              const Light& light, const VolumeRegion& region,
                                              const Bounds3f& changed) {
    return applyRsmUpdate(base, traceRsmUpdate(base, scene, light, region, changed));
}

std::vector<int> rsmResolutions(const Options& options, std::span<const Light> lights,
                                const VolumeRegion& region) {
    std::vector<int> out(lights.size());
    for (size_t l = 0; l < lights.size(); ++l)
        out[l] = rsmResolutionCeiling(options.rsm.resolution, options.volume.resolution,
                                      lights[l].type == Light::Type::Directional);
    if (options.rsm.resolution > 0 || lights.size() < 2) return out;
    // A light's largest irradiance (luminance) over the region's centre and corners, on a surface facing it.
    std::vector<float> irradiance(lights.size(), 0.0f);
    float brightest = 0.0f;
    for (size_t l = 0; l < lights.size(); ++l) {
        for (int c = 0; c < 9; ++c) {
            const glm::vec3 corner(c & 1 ? 1.0f : 0.0f, c & 2 ? 1.0f : 0.0f, c & 4 ? 1.0f : 0.0f);
            const glm::vec3 p = region.origin + region.size * (c == 8 ? glm::vec3(0.5f) : corner);
            const glm::vec3 e = sampleLight(lights[l], p).irradiance;
            irradiance[l] = std::max(irradiance[l], luminance(e));
        }
        brightest = std::max(brightest, irradiance[l]);
    }
    if (!(brightest > 0.0f) || !std::isfinite(brightest)) return out;
    for (size_t l = 0; l < lights.size(); ++l) {
        const int ceiling = out[l];
        const float wanted = static_cast<float>(ceiling) * std::sqrt(irradiance[l] / brightest);
        // The nearest power of two times the floor (in octaves), between the floor and the ceiling.
        int resolution = std::max(ceiling / kAutoRsmMinShare, 1);
        while (resolution * 2 <= ceiling &&
               static_cast<float>(resolution) * std::numbers::sqrt2_v<float> <= wanted)
            resolution *= 2;
        out[l] = resolution;
    }
    return out;
}

std::vector<int8_t> rsmViewSides(std::span<const TriangleMesh> meshes, glm::vec3 viewpoint) {
    constexpr float kTolerance = 1e-4f;
    std::vector<int8_t> sides;
    for (const TriangleMesh& mesh : meshes)
        for (const glm::uvec3& t : mesh.triangles) {
            const glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
            const glm::vec3 normal = glm::cross(b - a, c - a);
            const float area2 = glm::length(normal);
            if (!(area2 > 0.0f)) {  // degenerate: no ray hits it
                sides.push_back(1);
                continue;
            }
            const glm::vec3 toViewpoint = viewpoint - a;
            const float distance = glm::dot(normal / area2, toViewpoint);
            const float scale = glm::length(toViewpoint) + glm::length(b - a) + glm::length(c - a);
            sides.push_back(distance > kTolerance * scale ? 1 : distance < -kTolerance * scale ? -1 : 0);
        }
    return sides;
}

}  // namespace deltagi
