// The Delta Global Illumination pipeline (Thöner & Kuijper, §3): one call renders the augmented image.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "deltagi/export.h"
#include "deltagi/image.h"
#include "deltagi/math.h"
#include "deltagi/scene.h"

DELTAGI_API_BEGIN
namespace deltagi {

struct StageTiming {
    std::string
        name;  // voxelize, rsm, inject, mipmap, gbuffer, diffuse, specular, shadow, shading, composite...
    double ms = 0.0;
};

struct RenderOutput {
    Image composite;   // the augmented image, linear RGB
    Image background;  // the camera image used (given or rendered), linear RGB
    Image objectMask;  // 1 channel: coverage of virtual objects per pixel, in [0,1]
    Image delta;       // composite - background, linear RGB (negative where light was removed)
    // The layers a compositor grades over the plate (with options.render.layers; empty otherwise):
    //   composite = object.rgb + (1 - object.a) * max(background + shadow + indirect, 0)
    // (every pixel, to float rounding; max per channel). Of the real surfaces' change, `shadow` is the
    // change of their direct light — the objects' shadows, and the light of virtual emitters — and
    // `indirect` that of their indirect light — colour bleeding, reflections, the bounce light the objects
    // block; both are 0 where no real surface shows (coverage 1).
    Image object;    // RGBA, premultiplied: the objects' radiance times their coverage, alpha = coverage
    Image shadow;    // linear RGB, mostly <= 0
    Image indirect;  // linear RGB
    // 1 channel: the distance along the camera's axis (z depth, world units) of the surface at the pixel's
    // centre, the object's where it covers the pixel; infinity where no surface is seen.
    Image depth;
    std::vector<StageTiming> timings;  // in pipeline order
    double totalMs = 0.0;
};

// The compositing layers of a render, in the order of a multi-layer EXR (writeLayers, `render --layers`):
// composite, background, object (RGBA), shadow, indirect, delta (RGB each) and depth (Z). They point into
// `output`, which must outlive them.
std::vector<ImageLayer> compositingLayers(const RenderOutput& output);

// Called after each stage, for progress output: the stage's name and its time.
using StageCallback = std::function<void(const StageTiming&)>;

// Checks what an application may set in code between frames: the camera's size, intrinsics and pose
// (checkCameraPose) and the photo (camera-sized, 3 channels, finite). Throws InputError naming the field
// ("camera.world_from_camera", "background"). render() and FrameRenderer::render() call it first; the
// scene's meshes are checked where they are made (loadScene, setTransform).
void checkFrame(const Scene& scene);

// Renders one frame from scratch: a still, whose "auto" options spend more time than a session's frames do
// (options.render.refine_budget, options.diffuse.object_gather_rays; docs/scene-format.md).
RenderOutput render(const Scene& scene, const StageCallback& onStage = {});

// Renders a sequence of frames of one scene whose virtual objects and camera change from frame to frame, as
// in a mixed reality session. What depends only on the real side is kept from the previous frame, each part
// while what it is made from is unchanged (compared by identity and content at every call;
// src/pipeline/frame_cache.h): the reconstruction's ray-casting BVH while the scene object, its real meshes
// and the options are; its voxels while the volume region is too; its reflective shadow maps and injected and
// bounced light while the lights and the environment map are too and the camera stays on the same side of
// every real surface (the RSMs and the bounces keep a surface's camera side); its camera-space work (the real
// half of the G-buffer, the edge-aware filter's weights over the real surfaces) while the camera is
// unchanged, and with it and the lights the rendered background and the real scene's share of the real
// surfaces' shadow cones. The virtual
// objects' voxels, the full and delta light volumes and their mipmaps are kept too and redone only where the
// objects change them (their voxels, and the voxels lit differently because of them); so are the objects'
// half of the G-buffer (redone where they were and are) and their BVH (refit when only their vertices moved).
// The RSM texels the objects can change and the cones are redone every frame. A frame resolves the options'
// "auto" for a session's frame, render() for a still (options.render.refine_budget,
// options.diffuse.object_gather_rays): with those set, and options.render.temporal_frames = 1, the images
// are the same as render()'s, bit for bit, but for one case: a refit BVH may find the other of two triangles
// that a ray meets on their shared edge, at the same point to rounding (tests/core/ray_scene_test.cpp);
// renderStill() gives render()'s image with any options. With more temporal frames (the default, 4) each
// frame's lighting is the mean of its own and that of the temporal_frames - 1 frames before it, reprojected
// (pipeline/temporal_reuse.h): the first frame, and every frame once the scene has stood still for
// temporal_frames frames, is the frame without reuse.
class FrameRenderer {
  public:
    FrameRenderer();
    ~FrameRenderer();
    FrameRenderer(const FrameRenderer&) = delete;
    FrameRenderer& operator=(const FrameRenderer&) = delete;

    // `scene` must stay alive and in place between calls for the kept work to be reused.
    RenderOutput render(const Scene& scene, const StageCallback& onStage = {});
    // render()'s image (a still: the options' "auto" resolved as a single render does) with the kept work's
    // speed: forgets the frames temporal reuse averages over first (clearHistory), and the frames after it
    // average it in. For a session's idle frame.
    RenderOutput renderStill(const Scene& scene, const StageCallback& onStage = {});
    // Forgets everything kept: the next frame is a cold one.
    void clear();
    // Forgets the frames that temporal reuse averages over (options.render.temporal_frames) and keeps the
    // rest: the next frame is render()'s image, with the kept work's speed. For a frame that does not follow
    // the ones before it in time.
    void clearHistory();
    // What the last frame kept from the frames before (with virtual objects in the scene): the real scene's
    // geometry (its BVH and its voxels over the volume region), its light (its RSMs and injected and bounced
    // light, which a new light, environment or region redoes, and a camera that crosses a real surface's
    // plane) and its camera-space work (its G-buffer, the filter's weights).
    struct KeptWork {
        bool world = false, light = false, camera = false;
        // The virtual objects were the frame before's, bit for bit: their BVH was not refit and their voxels
        // not redone (a still object in a live frame whose camera or light changed).
        bool objects = false;
        // Where the light was not kept: how many of the new lights' reflective shadow maps were the frame
        // before's, for the lights that did not change (a lamp beside a light camera's new environment).
        int lightMapsKept = 0;
    };
    KeptWork lastFrameKept() const;
    // Bytes of the voxel volumes with their mip chains that the last frame's cones read: the real scene's
    // visibility, and the objects' visibility, the full, delta and objects' light volumes (the objects' own
    // two over the objects' box only). 0 before the first frame.
    size_t volumeBytes() const;

  private:
    // A frame (or a still) with what the frames before kept.
    RenderOutput renderKept(const Scene& scene, const StageCallback& onStage, bool still);
    struct State;
    std::unique_ptr<State> state_;
};

// Tells the C library's allocator (glibc's) to keep the memory the process frees for its next allocations
// instead of giving it back to the system, so that the per-pixel arrays a frame allocates and frees (a few
// MiB each, dozens a frame) are not faulted in afresh every frame: a 1280x960 frame took 2-2.5 times as long
// without it on the project's machine (docs/performance.md). Process-wide, and the memory is never returned:
// the command line and the Python module call it once at start; call it before rendering frames in a process
// of your own. No effect with another C library or under a sanitizer's allocator.
void retainFreedMemory();

// The cubic region covered by the volumes: the explicit options.volume region, or extent_scale times the
// virtual objects' bounding box (§3.4) grown up to reach_scale times it to take in the real scene around
// them; the real scene's bounds when there are no virtual objects.
struct VolumeRegion {
    glm::vec3 origin{0.0f};  // world-space corner with the smallest coordinates
    float size = 1.0f;       // edge length, world units
    int resolution = 1;      // voxels per edge (level 0)
    float voxelSize() const { return size / static_cast<float>(resolution); }
    Bounds3f bounds() const { return {origin, origin + glm::vec3(size)}; }
};
VolumeRegion volumeRegion(const Scene& scene);

}  // namespace deltagi
DELTAGI_API_END
