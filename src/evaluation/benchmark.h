// `deltagi bench`: the per-stage timings of the paper's Table 1, measured over a sequence of frames in which
// the virtual objects move a little every frame (as in a mixed reality session), so that their voxels, the
// RSMs with them, the light and delta volumes and all cones are redone each frame. The live frame
// (BenchOptions::live) changes the real light and the camera every frame too, as the paper's light camera and
// tracked scene camera do.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/renderer.h"
#include "deltagi/scene.h"

namespace deltagi {

struct BenchOptions {
    int frames = 10;    // measured frames
    int warmup = 2;     // frames rendered first and not measured (caches, page faults, the kept static work)
    bool cold = false;  // rebuild everything every frame, the static reconstruction's share too
    // The virtual objects move on a horizontal circle of this radius (in level-0 voxels of the volume
    // region), one sixteenth of a turn per frame.
    float motionVoxels = 1.0f;
    // The camera moves too (as in a real session) when > 0: it swings about the vertical axis through the
    // objects' centre, up to this many degrees either way, one sixteenth of a period per frame. Each pose has
    // its photo (the real scene rendered alone from there, before the measured frames), so the frames do not
    // render the background; they redo the camera-space work and keep the world-space work.
    float cameraDegrees = 0.0f;
    // The live frame: every frame the real light changes as well, over a photo. Point and spot lights move on
    // a horizontal circle of kLiveLightVoxels level-0 voxels; the scene file's directional lights swing
    // +-kLiveLightDegrees about the vertical; an environment map turns 1/16 of a turn per frame about the
    // vertical, its lights extracted again each frame (setEnvironment, timed as "environment"). The camera
    // swings as cameraDegrees says, kLiveCameraDegrees when that is 0. Each frame's photo is the real scene
    // rendered alone with that frame's light and camera (before the measured frames).
    bool live = false;
};
inline constexpr float kLiveLightVoxels = 8.0f;
inline constexpr float kLiveLightDegrees = 10.0f;
inline constexpr float kLiveCameraDegrees = 5.0f;

// The rows of the report, in order: Table 1's stages first, then the others, then the total.
struct BenchRow {
    std::string key;                  // JSON key, e.g. "voxelize_ms"
    std::vector<std::string> stages;  // pipeline stages (StageTiming names) summed into the row
    double paperMs = -1.0;            // Table 1 of the paper (GTX 660); < 0: not reported there
};
const std::vector<BenchRow>& benchRows();

struct BenchStatistics {
    double median = 0.0, max = 0.0;
};

struct BenchResult {
    BenchOptions options;
    float cameraDegrees = 0.0f;  // the camera's swing as run (options.cameraDegrees, or the live default)
    std::vector<std::vector<StageTiming>> frames;  // the measured frames' stage timings
    std::vector<double> totals;                    // their total_ms
    int threads = 0;
    int width = 0, height = 0, volumeResolution = 0;
    size_t realTriangles = 0, virtualTriangles = 0;
    int worldKeptFrames = 0;  // measured frames that kept the real scene's BVH and voxels
    int lightKeptFrames = 0;  // measured frames that kept the real scene's light (its RSMs and injection)
    size_t volumeBytes = 0;   // of the volumes with their mip chains, at the last frame (FrameRenderer)
    std::string sequence;     // a tracked sequence's frames, "frames 0:8 of FILE" (empty: none)
    int sequenceFrames = 0;

    BenchStatistics row(const BenchRow& row) const;  // over the measured frames
};

// Renders options.warmup + options.frames frames of `scene`, moving its virtual objects (their vertices are
// changed in place and put back at the end), with options.cameraDegrees its camera and with options.live its
// lights or environment (all put back too). A scene with a "sequence" renders its frames in order instead,
// from its first again after its last, each with its camera, photo (read before the frame, untimed) and
// keyframed objects; options.motionVoxels does not apply to it, and cameraDegrees or live are an InputError.
// `onFrame(index, total_ms)` is called after each measured frame.
BenchResult runBenchmark(Scene& scene, const BenchOptions& options,
                         const std::function<void(int, double)>& onFrame = {});

// {"frames", "warmup", "cold", "live", "camera_motion_deg", "sequence" (null or "frames A:B of FILE"),
// "world_kept_frames", "light_kept_frames", "volume_bytes" (FrameRenderer::volumeBytes at the last frame),
// "threads", "width", "height",
// "volume_resolution", "triangles": {"real", "virtual"}, then one object {"median", "max", "paper"} per row
// key ("voxelize_ms" ... "total_ms")}.
nlohmann::ordered_json benchToJson(const BenchResult& result);

// The table printed by `deltagi bench`.
std::string benchTable(const BenchResult& result);

}  // namespace deltagi
