#include "gbuffer.h"

#include <cmath>

#include "parallel.h"

namespace deltagi {

namespace {

SurfacePoint toSurfacePoint(const RayHit& hit, glm::vec3 rayDir) {
    if (!hit.hit()) return {};
    return {hit.position, hit.normal, -rayDir, hit.material};
}

// The first surface along a camera ray if it is virtual.
RayHit visibleObjectHit(const RayScene& all, glm::vec3 eye, glm::vec3 dir) {
    RayHit hit = all.intersect(eye, dir);
    return hit.isVirtual ? hit : RayHit{};
}

}  // namespace

std::vector<SurfacePoint> renderRealSurfaces(const Camera& camera, const RayScene& realOnly) {
    std::vector<SurfacePoint> real(static_cast<size_t>(camera.width) * camera.height);
    const glm::vec3 eye = camera.position();
    parallelFor(0, camera.height, 2, [&](int64_t y) {
        for (int x = 0; x < camera.width; ++x) {
            const glm::vec3 dir = glm::normalize(camera.rayDirection(x + 0.5f, y + 0.5f));
            real[static_cast<size_t>(y) * camera.width + x] = toSurfacePoint(realOnly.intersect(eye, dir), dir);
        }
    });
    return real;
}

void renderObjectSurfaces(const Camera& camera, const RayScene& all, int samplesPerPixel, GBuffer& g) {
    const int width = camera.width, height = camera.height;
    const size_t count = static_cast<size_t>(width) * height;
    g.object.assign(count, {});
    g.coverage.assign(count, 0.0f);
    const glm::vec3 eye = camera.position();
    const int k = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<float>(samplesPerPixel)))));

    // Pixel centres first.
    parallelFor(0, height, 2, [&](int64_t y) {
        for (int x = 0; x < width; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            const glm::vec3 dir = glm::normalize(camera.rayDirection(x + 0.5f, y + 0.5f));
            g.object[i] = toSurfacePoint(visibleObjectHit(all, eye, dir), dir);
            g.coverage[i] = g.object[i].valid() ? 1.0f : 0.0f;
        }
    });
    if (k == 1) return;

    // Then the sub-samples of silhouette pixels (decided from the centres alone, so the pass is deterministic).
    std::vector<uint8_t> silhouette(count, 0);
    parallelFor(0, height, 8, [&](int64_t y) {
        for (int x = 0; x < width; ++x) {
            const bool centre = g.object[static_cast<size_t>(y) * width + x].valid();
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = static_cast<int>(y) + dy;
                    if (xx < 0 || yy < 0 || xx >= width || yy >= height) continue;
                    if (g.object[static_cast<size_t>(yy) * width + xx].valid() != centre)
                        silhouette[static_cast<size_t>(y) * width + x] = 1;
                }
        }
    });
    parallelFor(0, height, 2, [&](int64_t y) {
        for (int x = 0; x < width; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            if (!silhouette[i]) continue;
            int virtualCount = 0;
            float bestOffset = g.object[i].valid() ? 0.0f : INFINITY;
            for (int sy = 0; sy < k; ++sy)
                for (int sx = 0; sx < k; ++sx) {
                    const float ox = (sx + 0.5f) / k - 0.5f, oy = (sy + 0.5f) / k - 0.5f;
                    const glm::vec3 dir = glm::normalize(camera.rayDirection(x + 0.5f + ox, y + 0.5f + oy));
                    const RayHit hit = visibleObjectHit(all, eye, dir);
                    if (!hit.hit()) continue;
                    ++virtualCount;
                    const float offset = ox * ox + oy * oy;
                    if (offset < bestOffset) {
                        bestOffset = offset;
                        g.object[i] = toSurfacePoint(hit, dir);
                    }
                }
            g.coverage[i] = static_cast<float>(virtualCount) / static_cast<float>(k * k);
            if (virtualCount == 0) g.object[i] = {};
        }
    });
}

GBuffer renderGBuffer(const Camera& camera, const RayScene* all, const RayScene& realOnly, int samplesPerPixel) {
    GBuffer g;
    g.width = camera.width;
    g.height = camera.height;
    g.real = renderRealSurfaces(camera, realOnly);
    if (all) {
        renderObjectSurfaces(camera, *all, samplesPerPixel, g);
    } else {
        g.object.assign(g.real.size(), {});
        g.coverage.assign(g.real.size(), 0.0f);
    }
    return g;
}

}  // namespace deltagi
