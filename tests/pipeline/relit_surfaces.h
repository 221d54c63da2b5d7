// The real surfaces of a scene as its camera sees them, relit: for the tests of the relit passes that run
// over the rectangle of the objects' shadow volumes (shadow_rays_test, area_light_rays_test).
#pragma once

#include <cstring>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pipeline/gbuffer.h"
#include "pipeline/shadow_rays.h"
#include "pipeline/sparse_pass.h"

namespace deltagi::test {

// The ray scenes of `scene`'s real meshes and of its virtual ones over them, and the real surfaces its camera
// sees. `scene` must outlive it.
struct RelitSurfaces {
    explicit RelitSurfaces(const Scene& scene)
        : camera(scene.camera),
          realOnly(scene, SceneContent::RealOnly),
          objects(scene, SceneContent::VirtualOnly, &realOnly),
          rays{&realOnly, &objects, objectBounds(scene), objectSphereRadius(scene.virtuals)},
          points(renderRealSurfaces(scene.camera, realOnly)),
          image{0, 0, scene.camera.width, scene.camera.height} {}

    // The pixels whose `perPixel` values in `values` (one pass over every pixel) are not all zero; a failure
    // for each outside `rect`, named by `what`.
    template <typename T>
    int changedPixels(const std::vector<T>& values, size_t perPixel, const PixelRect& rect,
                      const std::string& what) const {
        int changed = 0;
        for (int y = 0; y < camera.height; ++y)
            for (int x = 0; x < camera.width; ++x) {
                const size_t i = static_cast<size_t>(y) * camera.width + x;
                bool zero = true;
                for (size_t k = 0; k < perPixel; ++k) zero = zero && isZero(values[i * perPixel + k]);
                if (zero) continue;
                ++changed;
                EXPECT_TRUE(x >= rect.x0 && x < rect.x1 && y >= rect.y0 && y < rect.y1)
                    << what << ": pixel " << x << ", " << y << " outside " << rect.x0 << ".." << rect.x1
                    << " x " << rect.y0 << ".." << rect.y1;
            }
        return changed;
    }
    // Whether `rect` covers less than `share` of the image.
    bool smallerThan(const PixelRect& rect, float share) const {
        return static_cast<float>(rect.x1 - rect.x0) * static_cast<float>(rect.y1 - rect.y0) <
               share * static_cast<float>(camera.width * camera.height);
    }
    // Whether the sparse pass of `trace` at `stride` with `filter` over `bounds` gives the bits of the pass
    // over the whole image.
    template <typename T, typename Trace>
    bool sameAsWholeImage(const PixelRect& bounds, int stride, int perPixel, const DenoiseSettings& filter,
                          Trace&& trace) const {
        const std::vector<T> whole = traceSparse<T>(points, image, camera, stride, perPixel, filter, trace);
        const std::vector<T> part = traceSparse<T>(points, bounds, camera, stride, perPixel, filter, trace);
        return whole.size() == part.size() &&
               std::memcmp(whole.data(), part.data(), whole.size() * sizeof(T)) == 0;
    }

    Camera camera;
    RayScene realOnly, objects;
    ShadowRayScenes rays;
    SurfacePoints points;
    PixelRect image;

  private:
    static Bounds3f objectBounds(const Scene& scene) {
        Bounds3f b;
        for (const TriangleMesh& m : scene.virtuals) b.extend(m.bounds());
        return b;
    }
    static bool isZero(const ShadowOcclusion& o) { return o.object == 0.0f && o.combined == 0.0f; }
    static bool isZero(glm::vec3 v) { return v == glm::vec3(0.0f); }
};

}  // namespace deltagi::test
