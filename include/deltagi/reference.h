// The ground truth: a differential path tracer over the same scene (camera, materials, lights) as the DGI
// pipeline. It renders the scene with and without the virtual objects from the same random numbers, so that
// their difference has little noise, and composites like Debevec 1998: background + (with - without) on real
// pixels, the path-traced object on virtual pixels.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "deltagi/export.h"
#include "deltagi/image.h"
#include "deltagi/scene.h"

DELTAGI_API_BEGIN
namespace deltagi {

struct ReferenceOptions {
    int samplesPerPixel = 64;  // camera paths per pixel (each traced twice: with and without the objects)
    // Wall-clock budget in seconds; 0 = none. Checked after each whole pass of one sample per pixel, so the
    // image holds a whole number of samples, and the image for a given count does not depend on the budget.
    double timeLimitSeconds = 0.0;
    uint64_t seed = 0;            // the same seed gives the same image, whatever the thread count
    int rouletteStartBounce = 3;  // Russian roulette from this bounce on (bounce 0 is the camera hit)
    int maxBounces = 256;         // a safety bound only; roulette ends paths long before
    // Sample counts below samplesPerPixel at which the render also hands its image so far to the caller
    // (ReferenceSnapshot): exactly the image of a render of that many samples with the same seed, which
    // takes the same first samples. The quality suite's low-sample references come from its full one so.
    std::vector<int> snapshotSamples;
    // Seconds of rendering between checkpoints; 0 = none. After the first whole pass that ends this long
    // after the start or the last checkpoint (but not the last pass) the render hands its image so far to
    // the caller with its sums (ReferenceSnapshot, `sums` filled): a render cut short can go on from the
    // last one (`from`), so a reference of hours is not lost to an interruption. Sample counts are taken as
    // they come; the images do not depend on when the checkpoints fall.
    double checkpointSeconds = 0.0;
};

// The per-pixel sums a differential render's images are made from, over its first `samples` samples: with
// them a render goes on where an earlier one stopped (renderReference's `from`), and gives exactly the image
// of a render of all the samples at once (the same samples, added in the same order).
struct ReferenceSums {
    static constexpr int kValuesPerPixel = 13;  // with (RGB), without, object, change, virtual samples
    int width = 0, height = 0;
    int samples = 0;
    std::vector<double> values;  // kValuesPerPixel per pixel, row by row
    bool fits(const Camera& camera) const {
        return width == camera.width && height == camera.height && samples >= 0 &&
               values.size() == static_cast<size_t>(width) * height * kValuesPerPixel;
    }
};

struct ReferenceOutput {
    Image composite;          // the differential composite, linear RGB, never below 0
    Image with;               // the scene with the virtual objects, path traced
    Image without;            // the real scene alone, path traced
    Image background;         // the photo, or `without` where the scene has none
    Image objectMask;         // 1 channel: fraction of camera samples whose first hit is a virtual object
    Image delta;              // composite - background
    int samplesPerPixel = 0;  // samples actually taken (fewer than asked when the time limit stopped it)
    double totalMs = 0.0;
    ReferenceSums sums;  // what the images are made from (in the snapshots, filled for checkpoints only)
};

// Called after each pass: samples per pixel done so far, the number asked for, and the seconds spent.
using ReferenceProgress = std::function<void(int done, int total, double seconds)>;
// Called with the image of the first n samples (n = samplesPerPixel, totalMs the time spent so far) at each
// of ReferenceOptions::snapshotSamples that the render reaches, and at each checkpoint
// (ReferenceOptions::checkpointSeconds; then with its sums, sums.samples = n). Once for a pass that is both.
using ReferenceSnapshot = std::function<void(const ReferenceOutput& soFar)>;

// Lights: point and spot lights with a radius are spheres of that radius (shadow rays aim at a uniformly
// chosen point of the disk they show to the shading point, which gives the penumbra); without a radius, and
// for directional lights, shadows are hard. These lights are not visible to camera or bounce rays. Meshes
// whose material emits are area lights, seen by every ray and sampled by next-event estimation with multiple
// importance sampling. Surfaces, emitters included, are two-sided, like in the pipeline. A scene's
// environment map lights it directly: rays that leave the scene see it, and every vertex samples it in
// proportion to its radiance, combined with BRDF sampling by multiple importance sampling; the lights
// extracted from the map for the DGI pipeline are not used.
// `from`: the sums of an earlier render of the same scene with the same seed and bounces (and the same
// camera), of fewer samples than asked for: the render goes on from them, with samples from->samples on.
ReferenceOutput renderReference(const Scene& scene, const ReferenceOptions& options,
                                const ReferenceProgress& onPass = {},
                                const ReferenceSnapshot& onSnapshot = {},
                                const ReferenceSums* from = nullptr);

}  // namespace deltagi
DELTAGI_API_END
