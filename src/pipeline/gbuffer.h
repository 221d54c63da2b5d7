// Stage 5: the G-buffer from the camera: per pixel, the real surface the photo shows (a ray against the real
// scene alone), the virtual surface in front of it if any, and the coverage of virtual objects over the
// pixel's sub-samples, which anti-aliases the silhouette in the composite. Depth comparison decides which
// pixels are virtual (§3.3).
#pragma once

#include <span>
#include <vector>

#include "core/large_blocks.h"
#include "core/parallel.h"
#include "core/ray_scene.h"
#include "deltagi/scene.h"

namespace deltagi {

struct SurfacePoint {
    glm::vec3 position{0.0f};
    glm::vec3 normal{0.0f};              // unit, facing the camera
    glm::vec3 toEye{0.0f};               // unit, from the surface to the camera
    const Material* material = nullptr;  // null: no surface
    SurfaceMaterial surface;             // the material at this point (textures filtered over the pixel)
    bool valid() const { return material != nullptr; }
};

// A rectangle of pixels [x0, x1) x [y0, y1) that holds every valid point of a pass (the others are skipped).
struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool empty() const { return x0 >= x1 || y0 >= y1; }
};
// Calls body(i) in parallel for the valid points among `pixels` (indices into `points`), or among all points
// when `pixels` is empty: how the cone passes visit a sparse subset of the image (`grain` points per task).
template <typename Body>
void forEachValidPoint(std::span<const SurfacePoint> points, std::span<const uint32_t> pixels, int64_t grain,
                       Body&& body) {
    if (pixels.empty()) {
        parallelFor(0, static_cast<int64_t>(points.size()), grain, [&](int64_t i) {
            if (points[i].valid()) body(i);
        });
        return;
    }
    parallelFor(0, static_cast<int64_t>(pixels.size()), grain, [&](int64_t k) {
        const int64_t i = pixels[k];
        if (points[i].valid()) body(i);
    });
}

// Calls body(indices) in parallel for consecutive groups of the valid points among `pixels` (or all points),
// the valid ones of `grain` candidates a group (never empty): for passes that trace the points of a group
// together (the cones in SIMD lanes).
template <typename Body>
void forEachValidPointGroup(std::span<const SurfacePoint> points, std::span<const uint32_t> pixels,
                            int64_t grain, Body&& body) {
    const int64_t count = static_cast<int64_t>(pixels.empty() ? points.size() : pixels.size());
    parallelFor(0, (count + grain - 1) / grain, 1, [&](int64_t group) {
        std::vector<int64_t> valid;
        valid.reserve(static_cast<size_t>(grain));
        for (int64_t k = group * grain; k < std::min(count, (group + 1) * grain); ++k) {
            const int64_t i = pixels.empty() ? k : pixels[k];
            if (points[i].valid()) valid.push_back(i);
        }
        if (!valid.empty()) body(std::span<const int64_t>(valid));
    });
}

// Per-pixel surfaces (28 MiB at 640 x 480) in large blocks: a first render faults their pages in at once,
// in huge pages where the kernel has them (core/large_blocks.h), not one 4 KiB page at a time.
using SurfacePoints = std::vector<SurfacePoint, LargeBlockAllocator<SurfacePoint>>;

// The surfaces seen through a k x k grid of sub-pixel positions in every pixel of a rectangle: what the
// objects' direct light is shaded over, so that a pixel shows the mean of its area as the path tracer's
// does (a shadow edge or a fold inside a pixel), not the light at its centre alone.
// Pixels whose glossy surface turns sharply inside them (a gilded rim, a crease, a bead narrower than a
// pixel) have a finer grid instead (`fine`, 8 x 8 or 2k x 2k): a highlight there covers a part of the pixel
// that k x k samples miss or count twice (quality suite's cornell-textured, a gilded vase: object_rel_rmse
// 0.459 -> 0.293 with 4 x 4, with shading's disk quadrature 0.243; 0.176 with 8 x 8; 839 of its 14,700
// object pixels).
struct PixelSamples {
    int perPixel = 0;  // k * k; 0: none
    PixelRect rect;    // the pixels that may have them
    // Per pixel of `rect`, row by row: its slot in `points`, or -1 (none: it shows no object and lies on no
    // silhouette). Empty: pixel k of `rect` has slot k.
    std::vector<int32_t> slot;
    SurfacePoints points;           // perPixel per slot; invalid: no object there
    int finePerPixel = 0;           // max(2k, 8)^2; 0: none
    std::vector<int32_t> fineSlot;  // per pixel of `rect`: its slot in `fine`, or -1 (empty: none)
    SurfacePoints fine;             // finePerPixel per slot
    // The samples of image pixel `i` (of an image `width` wide): its fine ones where it has them; empty
    // where it has none (outside the rectangle among them).
    std::span<const SurfacePoint> of(size_t i, int width) const {
        if (perPixel == 0) return {};
        const int x = static_cast<int>(i % static_cast<size_t>(width)), y = static_cast<int>(i / width);
        if (x < rect.x0 || x >= rect.x1 || y < rect.y0 || y >= rect.y1) return {};
        const size_t k = static_cast<size_t>(y - rect.y0) * (rect.x1 - rect.x0) + (x - rect.x0);
        if (!fineSlot.empty() && fineSlot[k] >= 0)
            return std::span<const SurfacePoint>(fine).subspan(
                static_cast<size_t>(fineSlot[k]) * finePerPixel, finePerPixel);
        const int64_t s = slot.empty() ? static_cast<int64_t>(k) : slot[k];
        if (s < 0) return {};
        return std::span<const SurfacePoint>(points).subspan(static_cast<size_t>(s) * perPixel, perPixel);
    }
};

// The virtual half of the G-buffer; the real half (renderRealSurfaces) is kept apart, since it does not
// change while only the objects move.
// Where on a virtual object a pixel centre's ray lands: the mesh, its triangle and the barycentric weights of
// the triangle's second and third vertices. Temporal reuse follows the point from frame to frame by it.
struct SurfaceId {
    const TriangleMesh* mesh = nullptr;  // null: the centre shows no virtual object
    uint32_t triangle = 0;
    glm::vec2 barycentric{0.0f};
};

struct GBuffer {
    int width = 0, height = 0;
    SurfacePoints object;  // the virtual surface seen in the pixel, where coverage > 0
    // The virtual surface at the pixel's centre (per pixel, like object).
    std::vector<SurfaceId, LargeBlockAllocator<SurfaceId>> objectIds;
    // The fraction of sub-samples that see a virtual object first.
    std::vector<float, LargeBlockAllocator<float>> coverage;
    // The pixels that renderObjectSurfaces wrote: outside them object and coverage are empty, so they hold
    // every virtual point, and a G-buffer kept from frame to frame is cleared there only.
    PixelRect written;
    // The virtual surfaces at the sub-samples of every pixel that shows an object (samplesPerPixel > 1).
    PixelSamples objectSamples;
};

// The real surfaces behind the pixel centres (what the photo shows): rays against the real scene alone. They
// do not change while only the virtual objects move, so FrameRenderer keeps them between frames.
SurfacePoints renderRealSurfaces(const Camera& camera, const RayScene& realOnly);
// The same into `real` (resized; its memory is reused from frame to frame as the camera moves).
void renderRealSurfaces(const Camera& camera, const RayScene& realOnly, SurfacePoints& real);

// The virtual half of `g` (object, coverage): `all` holds the real and the virtual surfaces (the virtual
// objects' layer over the real scene's, see RayScene), whose virtual objects lie inside `objectBounds`: only
// pixels near the bounds' projection can see them. One ray per pixel centre decides which pixels are virtual;
// pixels on a silhouette (whose 3x3 neighbourhood has both kinds) take `samplesPerPixel` sub-samples on a
// regular k x k grid for their coverage. The virtual surface nearest the pixel centre represents the pixel.
// Every pixel with a virtual point keeps the virtual surfaces of its k x k sub-samples (g.objectSamples).
// `g` may hold an earlier frame's (of the same camera): only its written pixels are cleared. Glossy pixels
// whose normal turns by more than their lobe is wide take a finer grid (PixelSamples::fine); with
// `narrowLobeGrids` (a still) those of narrow lobes do wherever it turns by more than the lobe, not only by
// more than about 10 degrees (gbuffer.cpp, needsFinerGrid).
void renderObjectSurfaces(const Camera& camera, const RayScene& all, const Bounds3f& objectBounds,
                          int samplesPerPixel, GBuffer& g, bool narrowLobeGrids = false);

}  // namespace deltagi
