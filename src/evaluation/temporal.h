// Temporal stability: flicker measured without a reference. A mixed reality session shows one frame after the
// other while the objects and the camera move a little each time; DGI's change to the photo must follow the
// motion smoothly, not pop or boil. `deltagi stability` renders such frames and reports
// `temporal_instability`: the RMS of the second temporal difference of the frames, D[t+1] - 2 D[t] +
// D[t-1], relative to the RMS of their first (central) difference, (D[t+1] - D[t-1]) / 2. It is near 0 when
// each frame's change lies on the line between its neighbours (a steady motion) and of order 1 or more when
// frames jump back and forth.
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/renderer.h"
#include "deltagi/scene.h"

namespace deltagi {

struct MotionOptions {
    int frames = 8;
    // The virtual objects move this far each frame, in level-0 voxels of the volume region (its voxel size
    // at the first frame), along `objectDirection` (normalized).
    float objectStepVoxels = 0.25f;
    glm::vec3 objectDirection{1.0f, 0.0f, 0.0f};
    // The camera turns this many degrees each frame about the vertical axis through the objects' centre (0:
    // still).
    float cameraStepDeg = 0.0f;
    // Frames rendered first and not returned, the motion continued backwards: -1 renders
    // options.render.temporal_frames - 1 of them, so that every returned frame averages as many frames
    // before it as in a session that has been running (temporal reuse); 0 starts with the first frame.
    int warmUpFrames = -1;
};

// Frames rendered in order, with the cameras they were rendered from and the objects' motion between them.
struct MotionFrames {
    std::vector<RenderOutput> frames;
    std::vector<Camera> cameras;  // one per frame
    // The virtual objects' motion: one entry per group of objects that moves as one (a keyframed object;
    // the objects that stay), each with one pose per frame (world from where the group is in the first frame)
    // and, where there are several groups, its bounds in each frame, which tell the groups' pixels apart.
    struct ObjectGroup {
        std::vector<glm::mat4> poses;
        std::vector<Bounds3f> bounds;  // empty with a single group
    };
    std::vector<ObjectGroup> objectGroups;
    std::vector<int> indices;  // a sequence's frames: their indices in the transforms file (else empty)
};

// Renders options.frames frames of `scene` with one FrameRenderer, as a session would, moving its objects and
// camera as `options` says (its meshes and camera are put back at the end). With a turning camera the frames
// carry their depth layer (the measure below follows the surfaces with it).
MotionFrames renderMotion(Scene& scene, const MotionOptions& options);

// The frames of the scene's "sequence" (its first `frames`; all when 0), each with its camera, photo and
// keyframed objects, rendered as `deltagi render` renders them: after the temporal_frames - 1 frames of the
// transforms file before the first, unmeasured. The scene's camera, photo and objects are put back at the
// end. InputError when the scene has no sequence or fewer than 3 frames are asked for.
MotionFrames renderSequence(Scene& scene, int frames = 0);

struct TemporalFigures {
    // Over the real pixels (no object in any of the three frames of a triple), of the delta.
    // followsSurfaces: measured along surface points (a moving camera), not pixel by pixel.
    bool followsSurfaces = false;
    double realInstability = 0.0;
    // Over the objects' pixels (covered fully in all three frames), of the composite.
    double objectInstability = 0.0;
    size_t realSamples = 0, objectSamples = 0;  // pixel-triples counted
    // Per frame, the mean of the delta over the real pixels of every frame (channels averaged): a value that
    // alternates from frame to frame is flicker of the whole image.
    std::vector<double> meanDelta;
};

// The figures of frames rendered in order (at least 3, all of one size; InputError otherwise), pixel by
// pixel: for a still camera.
TemporalFigures temporalInstability(std::span<const RenderOutput> frames);

// The same for frames of renderMotion. With a still camera, pixel by pixel as above. With a moving camera a
// fixed pixel sees the scene slide under it, and every edge that crosses it (a room's corner, a silhouette)
// would count as flicker; so the measure follows surface points instead: each pixel of the middle frame of a
// triple is taken back to its world point (by its depth), moved by the objects' step where it shows an
// object, and looked up in the frames before and after it (projected into their cameras; Catmull-Rom over
// the 4 x 4 pixels around it), where those pixels all show the same kind of surface (real, or fully covered
// by an object), flat (no corner between them) and at the point's depth (within 2 %). Points that are
// hidden, leave the image or lie on an edge or a crease in either frame are not counted, nor an object's
// point that lies in the bounds of two groups of objects that move differently (or of none).
TemporalFigures temporalInstability(const MotionFrames& motion);

// {"frames", "real_instability", "object_instability", "follows_surfaces", "real_samples", "object_samples",
// "mean_delta": [...]}.
nlohmann::ordered_json temporalToJson(const TemporalFigures& figures);

}  // namespace deltagi
