#include "pipeline/gbuffer.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/parallel.h"

namespace deltagi {

namespace {

// The smallest cosine between a camera ray and the surface it meets that widens a pixel's texture
// footprint: grazing surfaces are filtered as at about 84 degrees rather than over the whole image.
constexpr float kMinFootprintCosine = 0.1f;

// `pixelAngle`: the angle (radians) a pixel subtends, for the textures' filter footprint. Writes the fields
// in place (returning the 96-byte record by value cost the real G-buffer a tenth of its time).
// `hit` is the caller's to change (its material is looked up again in place). Without `lookUpTextures` a
// textured surface keeps its mesh's constant material and unmapped normal for now: returns true then.
bool toSurfacePoint(RayHit& hit, glm::vec3 rayDir, float pixelAngle, SurfacePoint& out,
                    bool lookUpTextures = true) {
    if (!hit.hit()) {
        out = SurfacePoint{};
        return false;
    }
    out.position = hit.position;
    out.toEye = -rayDir;
    out.material = hit.material;
    const bool varies = hit.varies;
    if (varies && lookUpTextures) {
        const float cosine = std::max(std::abs(glm::dot(hit.geometricNormal, rayDir)), kMinFootprintCosine);
        lookUpMaterial(hit, hit.t * pixelAngle / cosine);
    }
    out.normal = hit.normal;
    out.surface = hit.surface;
    return varies && !lookUpTextures;
}

// A pixel centre's textured material as the mean of its k x k sub-samples' (each filtered over its share of
// the pixel: together the pixel's area, supersampled), when they all show the centre's material; the
// normal-mapped normal as their normals' mean. False when they do not (the centre is looked up itself).
bool centreFromSubSamples(std::span<const SurfacePoint> subSamples, SurfacePoint& centre) {
    SurfaceMaterial sum;
    sum.roughness = 0.0f;
    sum.occlusion = 0.0f;
    glm::vec3 normal(0.0f);
    for (const SurfacePoint& p : subSamples) {
        if (p.material != centre.material) return false;
        sum.diffuse += p.surface.diffuse;
        sum.specular += p.surface.specular;
        sum.roughness += p.surface.roughness;
        sum.emission += p.surface.emission;
        sum.occlusion += p.surface.occlusion;
        normal += p.normal;
    }
    const float length = glm::length(normal);
    if (!(length > 1e-6f) || glm::dot(normal, centre.toEye) <= 0.0f) return false;
    const float weight = 1.0f / static_cast<float>(subSamples.size());
    sum.diffuse *= weight;
    sum.specular *= weight;
    sum.roughness *= weight;
    sum.emission *= weight;
    sum.occlusion *= weight;
    sum.model = centre.surface.model;
    centre.surface = sum;
    if (centre.material->normalTexture) centre.normal = normal / length;
    return true;
}

// A pixel's k x k samples ask for the finer grid (PixelSamples::fine) when they show a glossy lobe at most
// about 30 degrees wide (Phong exponent 20) and the normal turns between two neighbouring samples, half a
// pixel apart at k = 2, by more than the lobe is wide. The highlight may then lie in a part of the pixel the
// samples do not see, or fall on one of them and count for a quarter of the pixel. In a still
// (`narrowLobeGrids`), a narrow lobe (exponent n from kFineNarrowExponent, about 7 degrees wide) asks for it
// where |n_a - n_b|^2 > kFineLobeTurns / n (the
// mirror direction turns by about twice the lobe's half-width at half maximum, 1.18 / sqrt(n)); a wider one,
// and any in a session's frame, only where the normal turns by more than about 10 degrees and by four times
// as much (|n_a - n_b|^2 above
// kFineNormalDifference and 4 kFineLobeTurns / n): its highlight is smooth, and the finer grid costs more
// than it brings. A smooth glossy ball turns by a fraction of a degree per pixel away from its silhouette.
// Quality suite's cornell-textured (its glazes' lobes are narrow, n = 4,000, its gilded bands' about 100-200,
// and their normal maps turn by a degree or two per pixel), object_rel_rmse with the glossy pixels' shadows
// of glossyShadowOcclusion: 0.173 with the wide lobes' rule for all (839 finer pixels of 14,700), 0.123 with
// this, 0.121 with kFineLobeTurns 1; 0.167 with kFineNarrowExponent 200; without those shadows the finer
// grids alone made it worse (0.190: sharper highlights under a shadow fraction that holds for matte
// surfaces). Its still's G-buffer 38 -> 83 ms, shading 50 -> 146 (each finer pixel's 64 samples take the
// disk's quadrature); a frame of the vase would take twice as long (bench: 240 -> 480-520 ms). The narrow
// lobes' rule for every lobe would cost the textured torus's frame (exponent 33) 16 ms of G-buffer and 40 of
// shading.
constexpr float kFineMinExponent = 20.0f;
constexpr float kFineNarrowExponent = 100.0f;
// The finer grid's side: at least twice the pixel's k, and 8. A glaze's highlight on a bead or a rim is a
// line a tenth of a pixel tall, and 4 x 4 samples see it in one row of four or in two: cornell-textured's
// object_rel_rmse 0.200 with 4 x 4, 0.176 with 8 x 8, 0.174 with 12 x 12 (when only turns above 10 degrees
// took them).
constexpr int kFineGridSide = 8;
constexpr float kFineNormalDifference = 0.03f;
constexpr float kFineLobeTurns = 2.0f;

bool needsFinerGrid(std::span<const SurfacePoint> samples, int k, bool narrowLobeGrids) {
    // The largest turn first: most pixels have none, and their lobes' exponents are not worked out.
    float turn = 0.0f;
    auto pair = [&turn](const SurfacePoint& a, const SurfacePoint& b) {
        if (!a.valid() || !b.valid()) return;
        const glm::vec3 d = a.normal - b.normal;
        turn = std::max(turn, glm::dot(d, d));
    };
    for (int y = 0; y < k; ++y)
        for (int x = 0; x < k; ++x) {
            if (x + 1 < k) pair(samples[y * k + x], samples[y * k + x + 1]);
            if (y + 1 < k) pair(samples[y * k + x], samples[(y + 1) * k + x]);
        }
    if (!(turn > 0.0f)) return false;
    float exponent = 0.0f;
    for (const SurfacePoint& p : samples)
        if (p.valid() && p.surface.glossy()) exponent = std::max(exponent, p.surface.phongExponent());
    if (narrowLobeGrids && exponent >= kFineNarrowExponent) return turn > kFineLobeTurns / exponent;
    return exponent >= kFineMinExponent &&
           turn > std::max(kFineNormalDifference, 4.0f * kFineLobeTurns / exponent);
}

float pixelAngleOf(const Camera& camera) {
    return 1.0f / std::max(camera.fy, 1e-6f);
}

// The first surface along a camera ray if it is virtual. With the objects in a layer of their own, the real
// scene below is traced only for rays that meet an object, up to it (most rays near an object miss it).
RayHit visibleObjectHit(const RayScene& all, glm::vec3 eye, glm::vec3 dir) {
    const RayHit hit = all.base() ? all.intersectTopLayer(eye, dir) : all.intersect(eye, dir);
    if (!hit.isVirtual) return {};
    if (all.base() && all.base()->occluded(eye, dir, 0.0f, hit.t)) return {};
    return hit;
}

// visibleObjectHit for many rays: the objects' layer in packets.
void visibleObjectHits(const RayScene& all, glm::vec3 eye, std::span<const glm::vec3> directions,
                       std::span<RayHit> hits) {
    if (!all.base()) {
        for (size_t i = 0; i < directions.size(); ++i) hits[i] = visibleObjectHit(all, eye, directions[i]);
        return;
    }
    all.intersectCoherent(eye, directions, hits, true, true);
    // The real scene in front of the hits, in packets too (a ray that met no object is not traced).
    thread_local std::vector<float> reach;
    thread_local std::vector<uint8_t> blocked;
    reach.resize(directions.size());
    blocked.resize(directions.size());
    for (size_t i = 0; i < directions.size(); ++i) reach[i] = hits[i].isVirtual ? hits[i].t : 0.0f;
    all.base()->occludedCoherent(eye, directions, reach, blocked);
    for (size_t i = 0; i < directions.size(); ++i)
        if (!hits[i].isVirtual || blocked[i]) hits[i] = {};
}

// The surfaces seen through an m x m grid of positions in pixel (x, y), into `out` (m * m; invalid where
// no object shows), their textures filtered over their cells.
void traceSampleGrid(const Camera& camera, const RayScene& all, int x, int y, int m, SurfacePoint* out) {
    thread_local std::vector<glm::vec3> directions;
    thread_local std::vector<RayHit> hits;
    directions.clear();
    for (int sy = 0; sy < m; ++sy)
        for (int sx = 0; sx < m; ++sx)
            directions.push_back(glm::normalize(camera.rayDirection(
                static_cast<float>(x) + (sx + 0.5f) / m, static_cast<float>(y) + (sy + 0.5f) / m)));
    hits.resize(directions.size());
    visibleObjectHits(all, camera.position(), directions, hits);
    for (size_t s = 0; s < directions.size(); ++s)
        toSurfacePoint(hits[s], directions[s], pixelAngleOf(camera) / static_cast<float>(m), out[s]);
}

// The pixel rows and columns [x0, x1] x [y0, y1] whose rays may meet the box `b` (its corners' projections,
// with a margin for the sub-samples); the whole image when the box reaches behind the camera.
std::array<int, 4> pixelsCovering(const Camera& camera, const Bounds3f& b) {
    const std::array<int, 4> all = {0, camera.width - 1, 0, camera.height - 1};
    if (b.empty()) return {0, -1, 0, -1};
    // Through a lens' distortion the box's corners do not bound its image (a polynomial model may even fold
    // back outside the image): every pixel may see it.
    if (!camera.distortion.none()) return all;
    const glm::mat4 cameraFromWorld = glm::inverse(camera.worldFromCamera);
    float xMin = INFINITY, xMax = -INFINITY, yMin = INFINITY, yMax = -INFINITY;
    for (int c = 0; c < 8; ++c) {
        const glm::vec3 p(c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y, c & 4 ? b.max.z : b.min.z);
        const glm::vec3 q = glm::vec3(cameraFromWorld * glm::vec4(p, 1.0f));
        if (q.z > -1e-6f) return all;                  // at or behind the camera plane
        const glm::vec2 pixel = camera.imagePoint(q);  // no distortion here
        const float x = pixel.x, y = pixel.y;
        xMin = std::min(xMin, x), xMax = std::max(xMax, x), yMin = std::min(yMin, y),
        yMax = std::max(yMax, y);
    }
    constexpr float kMargin = 2.0f;
    auto clampTo = [](float v, int hi) {
        return static_cast<int>(std::clamp(v, -1.0f, static_cast<float>(hi) + 1.0f));
    };
    return {std::max(clampTo(std::floor(xMin - kMargin), camera.width), 0),
            std::min(clampTo(std::ceil(xMax + kMargin), camera.width), camera.width - 1),
            std::max(clampTo(std::floor(yMin - kMargin), camera.height), 0),
            std::min(clampTo(std::ceil(yMax + kMargin), camera.height), camera.height - 1)};
}

}  // namespace

SurfacePoints renderRealSurfaces(const Camera& camera, const RayScene& realOnly) {
    SurfacePoints real;
    renderRealSurfaces(camera, realOnly, real);
    return real;
}

void renderRealSurfaces(const Camera& camera, const RayScene& realOnly, SurfacePoints& real) {
    real.resize(static_cast<size_t>(camera.width) * camera.height);  // each point written in full below
    const glm::vec3 eye = camera.position();
    parallelFor(0, camera.height, 2, [&](int64_t y) {
        // A row's rays in packets, kRun at a time: their hits stay in the first-level cache until they are
        // turned into surface points (a whole row's RayHits, 85 KiB, did not).
        constexpr int kRun = 32;
        std::array<glm::vec3, kRun> directions;
        std::array<RayHit, kRun> hits;
        for (int x0 = 0; x0 < camera.width; x0 += kRun) {
            const int n = std::min(kRun, camera.width - x0);
            for (int k = 0; k < n; ++k)
                directions[k] =
                    glm::normalize(camera.rayDirection(x0 + k + 0.5f, static_cast<float>(y) + 0.5f));
            realOnly.intersectCoherent(eye, std::span(directions).first(n), std::span(hits).first(n), false,
                                       true);
            for (int k = 0; k < n; ++k)
                toSurfacePoint(hits[k], directions[k], pixelAngleOf(camera),
                               real[static_cast<size_t>(y) * camera.width + x0 + k]);
        }
    });
}

void renderObjectSurfaces(const Camera& camera, const RayScene& all, const Bounds3f& objectBounds,
                          int samplesPerPixel, GBuffer& g, bool narrowLobeGrids) {
    const int width = camera.width, height = camera.height;
    const size_t count = static_cast<size_t>(width) * height;
    if (g.object.size() == count && g.coverage.size() == count && g.objectIds.size() == count &&
        g.width == width && g.height == height) {
        // The last frame's rectangle cleared, in parallel (several MiB for a large object).
        const PixelRect w = g.written;
        parallelFor(w.y0, w.y1, 8, [&](int64_t y) {
            const size_t row = static_cast<size_t>(y) * width;
            std::fill(g.object.begin() + row + w.x0, g.object.begin() + row + w.x1, SurfacePoint{});
            std::fill(g.objectIds.begin() + row + w.x0, g.objectIds.begin() + row + w.x1, SurfaceId{});
            std::fill(g.coverage.begin() + row + w.x0, g.coverage.begin() + row + w.x1, 0.0f);
        });
    } else {  // a new camera: 15 MiB at 640 x 480, cleared in parallel
        g.object.resize(count);
        g.objectIds.resize(count);
        g.coverage.resize(count);
        parallelFor(0, height, 16, [&](int64_t y) {
            const size_t row = static_cast<size_t>(y) * width;
            std::fill(g.object.begin() + row, g.object.begin() + row + width, SurfacePoint{});
            std::fill(g.objectIds.begin() + row, g.objectIds.begin() + row + width, SurfaceId{});
            std::fill(g.coverage.begin() + row, g.coverage.begin() + row + width, 0.0f);
        });
    }
    g.width = width;
    g.height = height;
    const glm::vec3 eye = camera.position();
    const int k = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<float>(samplesPerPixel)))));

    // Pixel centres first, where the objects can be. With sub-samples, a textured centre's material is theirs
    // (centreFromSubSamples): its lookups wait (`deferred`, over the rectangle).
    const auto [x0, x1, y0, y1] = pixelsCovering(camera, objectBounds);
    g.written = x1 < x0 || y1 < y0 ? PixelRect{} : PixelRect{x0, y0, x1 + 1, y1 + 1};
    const size_t rectWidth = g.written.empty() ? 0 : static_cast<size_t>(x1 - x0 + 1);
    std::vector<uint8_t> deferred(k > 1 ? rectWidth * (g.written.empty() ? 0 : y1 - y0 + 1) : 0);
    auto inRect = [&](int64_t y, int x) {
        return static_cast<size_t>(y - y0) * rectWidth + static_cast<size_t>(x - x0);
    };
    parallelFor(y0, y1 + 1, 2, [&](int64_t y) {
        thread_local std::vector<glm::vec3> directions;
        thread_local std::vector<RayHit> hits;
        directions.clear();
        for (int x = x0; x <= x1; ++x)
            directions.push_back(glm::normalize(camera.rayDirection(x + 0.5f, static_cast<float>(y) + 0.5f)));
        hits.resize(directions.size());
        visibleObjectHits(all, eye, directions, hits);
        for (int x = x0; x <= x1; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            const RayHit& hit = hits[x - x0];
            if (hit.hit()) g.objectIds[i] = {hit.mesh, hit.triangle, hit.barycentric};
            if (toSurfacePoint(hits[x - x0], directions[x - x0], pixelAngleOf(camera), g.object[i], k == 1))
                deferred[inRect(y, x)] = 1;
            g.coverage[i] = g.object[i].valid() ? 1.0f : 0.0f;
        }
    });
    PixelSamples& samples = g.objectSamples;
    if (k == 1 || g.written.empty()) {
        samples.perPixel = k == 1 ? 0 : k * k;
        samples.rect = g.written;
        samples.slot.clear();
        samples.points.clear();
        return;
    }
    samples.perPixel = k * k;
    samples.rect = g.written;
    samples.finePerPixel = 0;
    samples.fineSlot.clear();
    samples.fine.clear();

    // Then the sub-samples of silhouette pixels (decided from the centres alone, so the pass is
    // deterministic), over the rectangle [x0, x1] x [y0, y1]. Every pixel that shows an object or lies on a
    // silhouette takes k x k sub-samples: the coverage, and the surfaces its direct light is shaded over.
    // They get slots in pixel order: each row counts its pixels here, and its slots start after the rows'
    // above.
    std::vector<uint8_t> silhouette(deferred.size());
    auto onSilhouette = [&](int64_t y, int x) -> uint8_t& { return silhouette[inRect(y, x)]; };
    std::vector<uint32_t> rowStart(static_cast<size_t>(y1 - y0) + 2, 0);
    // Whether pixel j's centre shows an object, read from the coverage (4 bytes a pixel, not the 96 of its
    // surface point) until a pixel's sub-samples set its own.
    auto centreShows = [&](size_t j) { return g.coverage[j] > 0.0f; };
    parallelFor(y0, y1 + 1, 8, [&](int64_t y) {
        uint32_t count = 0;
        for (int x = x0; x <= x1; ++x) {
            const bool centre = centreShows(static_cast<size_t>(y) * width + x);
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = static_cast<int>(y) + dy;
                    if (xx < 0 || yy < 0 || xx >= width || yy >= height) continue;
                    if (centreShows(static_cast<size_t>(yy) * width + xx) != centre) onSilhouette(y, x) = 1;
                }
            count += centre || onSilhouette(y, x);
        }
        rowStart[y - y0 + 1] = count;
    });
    for (size_t r = 1; r < rowStart.size(); ++r) rowStart[r] += rowStart[r - 1];
    // Sized only, keeping the memory of the frame before: a row's task writes each of its samples once, in
    // parallel (a few MiB for an object over a third of the image).
    samples.slot.resize(deferred.size());
    samples.points.resize(static_cast<size_t>(rowStart.back()) * k * k);
    // The pixels that ask for the finer grid (needsFinerGrid; at k = 2 only: the shadow rays spread over at
    // most 16 samples).
    std::vector<uint8_t> finer(k == 2 ? deferred.size() : 0);
    parallelFor(y0, y1 + 1, 2, [&](int64_t y) {
        // The row's sub-sample rays, in packets.
        thread_local std::vector<glm::vec3> directions;
        thread_local std::vector<RayHit> hits;
        directions.clear();
        for (int x = x0; x <= x1; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            if (!onSilhouette(y, x) && !centreShows(i)) continue;
            for (int sy = 0; sy < k; ++sy)
                for (int sx = 0; sx < k; ++sx) {
                    const float ox = (sx + 0.5f) / k - 0.5f, oy = (sy + 0.5f) / k - 0.5f;
                    directions.push_back(glm::normalize(
                        camera.rayDirection(x + 0.5f + ox, static_cast<float>(y) + 0.5f + oy)));
                }
        }
        hits.resize(directions.size());
        visibleObjectHits(all, eye, directions, hits);
        size_t next = 0;
        int32_t slot = static_cast<int32_t>(rowStart[y - y0]);
        for (int x = x0; x <= x1; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            const bool edge = onSilhouette(y, x);
            if (!edge && !centreShows(i)) {
                samples.slot[inRect(y, x)] = -1;
                continue;
            }
            samples.slot[inRect(y, x)] = slot;
            SurfacePoint* out = samples.points.data() + static_cast<size_t>(slot++) * k * k;
            int virtualCount = 0;
            for (int s = 0; s < k * k; ++s, ++next) {
                if (!hits[next].hit()) {
                    out[s] = SurfacePoint{};  // each slot written once: no object there
                    continue;
                }
                ++virtualCount;
                // Textures filtered over the sub-sample's share of the pixel (over the whole pixel,
                // quality suite's cornell-textured: object_rel_rmse 0.462 -> 0.517, blurred twice).
                toSurfacePoint(hits[next], directions[next], pixelAngleOf(camera) / static_cast<float>(k),
                               out[s]);
            }
            if (deferred[inRect(y, x)] &&
                !centreFromSubSamples({out, static_cast<size_t>(k * k)}, g.object[i])) {
                // Sub-samples of other surfaces: the centre's own lookup, its ray cast again (the same hit).
                const glm::vec3 dir =
                    glm::normalize(camera.rayDirection(x + 0.5f, static_cast<float>(y) + 0.5f));
                RayHit centre = visibleObjectHit(all, eye, dir);
                if (centre.hit()) toSurfacePoint(centre, dir, pixelAngleOf(camera), g.object[i]);
            }
            // A silhouette pixel's surface: the centre's if it shows an object, else the nearest
            // sub-sample's.
            float bestOffset = g.object[i].valid() ? 0.0f : INFINITY;
            SurfacePoint nearest = g.object[i];
            for (int sy = 0; sy < k; ++sy)
                for (int sx = 0; sx < k; ++sx) {
                    const float ox = (sx + 0.5f) / k - 0.5f, oy = (sy + 0.5f) / k - 0.5f;
                    const float offset = ox * ox + oy * oy;
                    if (out[sy * k + sx].valid() && offset < bestOffset) {
                        bestOffset = offset;
                        nearest = out[sy * k + sx];
                    }
                }
            if (edge) {  // inside an object the centre stays, coverage 1
                g.object[i] = virtualCount > 0 ? nearest : SurfacePoint{};
                g.coverage[i] = static_cast<float>(virtualCount) / static_cast<float>(k * k);
            }
            if (!finer.empty() && needsFinerGrid({out, static_cast<size_t>(k * k)}, k, narrowLobeGrids))
                finer[inRect(y, x)] = 1;
        }
    });

    // The finer grids, in slots numbered in pixel order (the same whatever the thread count).
    const int m = std::max(2 * k, kFineGridSide);
    std::vector<uint32_t> pixels;  // rect indices, in pixel order
    for (size_t r = 0; r < finer.size(); ++r)
        if (finer[r]) pixels.push_back(static_cast<uint32_t>(r));
    if (pixels.empty()) return;
    samples.finePerPixel = m * m;
    samples.fineSlot.assign(finer.size(), -1);
    samples.fine.resize(pixels.size() * m * m);
    for (size_t s = 0; s < pixels.size(); ++s) samples.fineSlot[pixels[s]] = static_cast<int32_t>(s);
    parallelFor(0, static_cast<int64_t>(pixels.size()), 16, [&](int64_t s) {
        const int x = x0 + static_cast<int>(pixels[s] % rectWidth);
        const int y = y0 + static_cast<int>(pixels[s] / rectWidth);
        traceSampleGrid(camera, all, x, y, m, samples.fine.data() + static_cast<size_t>(s) * m * m);
    });
}

}  // namespace deltagi
