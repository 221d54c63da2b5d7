#include "gbuffer.h"

#include <cmath>

#include "parallel.h"

namespace deltagi {

namespace {

SurfacePoint toSurfacePoint(const RayHit& hit, glm::vec3 rayDir) {
    if (!hit.hit()) return {};
    return {hit.position, hit.normal, -rayDir, hit.material};
}

}  // namespace

GBuffer renderGBuffer(const Camera& camera, const RayScene& all, const RayScene& realOnly, int samplesPerPixel) {
    GBuffer g;
    g.width = camera.width;
    g.height = camera.height;
    const size_t count = static_cast<size_t>(g.width) * g.height;
    g.real.resize(count);
    g.object.resize(count);
    g.coverage.assign(count, 0.0f);
    const int k = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<float>(samplesPerPixel)))));
    const glm::vec3 eye = camera.position();
    const bool hasVirtual = &all != &realOnly;  // a background render passes the real scene twice

    parallelFor(0, g.height, 2, [&](int64_t y) {
        for (int x = 0; x < g.width; ++x) {
            const size_t i = static_cast<size_t>(y) * g.width + x;
            const glm::vec3 centreDir = glm::normalize(camera.rayDirection(x + 0.5f, y + 0.5f));
            g.real[i] = toSurfacePoint(realOnly.intersect(eye, centreDir), centreDir);
            if (!hasVirtual) continue;
            // Sub-samples on a k x k grid; the virtual hit nearest the pixel centre represents the pixel.
            int virtualCount = 0;
            float bestOffset = INFINITY;
            for (int sy = 0; sy < k; ++sy)
                for (int sx = 0; sx < k; ++sx) {
                    const float ox = (sx + 0.5f) / k - 0.5f, oy = (sy + 0.5f) / k - 0.5f;
                    const glm::vec3 dir = glm::normalize(camera.rayDirection(x + 0.5f + ox, y + 0.5f + oy));
                    const RayHit hit = all.intersect(eye, dir);
                    if (!hit.hit() || !hit.isVirtual) continue;
                    ++virtualCount;
                    const float offset = ox * ox + oy * oy;
                    if (offset < bestOffset) {
                        bestOffset = offset;
                        g.object[i] = toSurfacePoint(hit, dir);
                    }
                }
            g.coverage[i] = static_cast<float>(virtualCount) / static_cast<float>(k * k);
        }
    });
    return g;
}

}  // namespace deltagi
