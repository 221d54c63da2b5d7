// Temporal reuse (beyond the paper): the objects' radiance and the real surfaces' change of direct light
// (their shadows) averaged at each pixel with the same surface point's in the last frames, found by
// reprojection. The cone and ray results of one frame change in steps as the objects move through the voxel
// grid and a shadow ray's visibility flips; the mean over a few frames follows the motion smoothly (README,
// "Stable frames"). The real surfaces' indirect change is left alone: it is non-zero almost everywhere, and
// averaging it too cost about 10 ms a frame for a smaller gain (Cornell box, objects along x: 0.46 -> 0.43 on
// real pixels; along y 0.96 -> 0.75).
//
// A window, not a running average: a frame's result is the mean of its own values and those of at most
// `frames - 1` frames before it, each the value that frame computed itself (never one already averaged). So
// a sequence rendered in chunks gives the same frames as rendered at once when each chunk starts
// `frames - 1` frames early, and once the objects and the camera stop, frame `frames` after the stop is the
// still render of that pose exactly.
//
// Reprojection: a real surface point is where it was (the real scene does not move); a virtual one is the
// same barycentric point of the same triangle, at that frame's vertex positions (or, when every vertex moved
// by one shift, the point shifted back: no vertex lookups). A kept frame's value counts
// where that frame showed the same kind of surface (the same object) at the reprojected depth (within 2 %),
// interpolated bilinearly over its pixels that did. Each kept value is clamped to the range of the current
// frame's values over the pixel's 3 x 3 neighbourhood (of the same surface kind): the history follows the
// noise and the steps, but not a shadow or a reflection that has moved on (no ghosting).
#pragma once

#include <deque>
#include <span>
#include <vector>

#include "deltagi/scene.h"
#include "pipeline/gbuffer.h"

namespace deltagi {

// One frame's surfaces, as the pipeline saw them.
struct TemporalSurfaces {
    const Camera* camera = nullptr;
    std::span<const TriangleMesh> objects;     // the virtual objects, as placed in this frame
    const GBuffer* gbuffer = nullptr;          // the objects' half of the G-buffer (object, objectIds)
    std::span<const SurfacePoint> realPoints;  // per pixel, valid where a real surface shows
};

// The values reused, per pixel (width x height), changed in place.
struct TemporalValues {
    std::span<glm::vec3> objectRadiance;  // where gbuffer.objectIds names an object
    // The real surfaces' change of direct light (the objects' shadows; see renderer.cpp) where realPoints
    // are valid. Their indirect change is left as it is: it does not flicker (README, "Stable frames").
    std::span<glm::vec3> realShadow;
};

// What one frame's reuse did: of the pixels whose neighbourhood's values differ (elsewhere a pixel keeps its
// value), how many were averaged with at least one kept frame.
struct TemporalStats {
    size_t realPixels = 0, realAveraged = 0;
    size_t objectPixels = 0, objectAveraged = 0;
};

class TemporalReuse {
  public:
    // Averages `values` over this frame and the kept ones (at most frames - 1 of them) and keeps this frame's
    // own values. frames <= 1 forgets the kept frames and changes nothing.
    TemporalStats apply(int frames, const TemporalSurfaces& surfaces, TemporalValues values);
    void clear() { history_.clear(); }
    size_t keptFrames() const { return history_.size(); }

    struct Frame;

  private:
    void keepNewest(int count);  // drops the older frames into spare_
    std::deque<Frame> history_;  // the most recent first
    std::vector<Frame> spare_;   // memory of dropped frames, reused
};

struct TemporalReuse::Frame {
    Camera camera;
    int width = 0, height = 0;
    std::vector<float> realDepth;  // per pixel: the real surface's depth, or -1 where none shows
    std::vector<glm::vec3> realShadow;
    // Per pixel, whether realShadow is 0 (or no real surface shows); per row, the columns [first, last]
    // where it is not (first > last: none). Most of an image: the objects' shadows are small.
    std::vector<uint8_t> zeroShadow;
    std::vector<glm::ivec2> columns;
    // Over the pixels the objects' G-buffer was written (rect), row by row: the object's depth at the pixel
    // centre, which object (-1: none) and its radiance.
    PixelRect rect;
    std::vector<float> objectDepth;
    std::vector<int32_t> objectIndex;
    std::vector<glm::vec3> objectRadiance;
    std::vector<std::vector<glm::vec3>> positions;  // the objects' vertices in this frame
};

}  // namespace deltagi
