#include "evaluation/temporal.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/core.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/error.h"
#include "deltagi/keyframes.h"
#include "deltagi/scene_io.h"
#include "deltagi/transforms.h"

namespace deltagi {

MotionFrames renderMotion(Scene& scene, const MotionOptions& options) {
    if (options.frames < 3) throw InputError("--frames", "at least 3 frames are needed");
    const float length = glm::length(options.objectDirection);
    if (!(length > 0.0f) || !std::isfinite(length))
        throw InputError("--direction", "expected a non-zero, finite direction");
    const glm::vec3 step =
        options.objectStepVoxels * volumeRegion(scene).voxelSize() * options.objectDirection / length;
    Bounds3f objects;
    for (const TriangleMesh& m : scene.virtuals) objects.extend(m.bounds());
    const glm::vec3 centre = objects.empty() ? glm::vec3(0.0f) : objects.center();
    const Camera camera = scene.camera;
    std::vector<std::vector<glm::vec3>> original;
    for (const TriangleMesh& m : scene.virtuals) original.push_back(m.positions);
    auto place = [&](int frame) {
        const glm::vec3 offset = static_cast<float>(frame) * step;
        for (size_t m = 0; m < scene.virtuals.size(); ++m)
            for (size_t v = 0; v < original[m].size(); ++v)
                scene.virtuals[m].positions[v] = original[m][v] + offset;
        scene.camera = turnedCamera(camera, centre, static_cast<float>(frame) * options.cameraStepDeg);
    };
    // The depth layer, for following the surfaces under a turning camera (the other layers come with it).
    const bool layers = scene.options.render.layers;
    if (options.cameraStepDeg != 0.0f) scene.options.render.layers = true;
    FrameRenderer renderer;
    MotionFrames out;
    const int warmUp =
        options.warmUpFrames >= 0 ? options.warmUpFrames : scene.options.render.temporalFrames - 1;
    for (int f = -warmUp; f < options.frames; ++f) {
        place(f);
        RenderOutput frame = renderer.render(scene);
        if (f < 0) continue;
        out.frames.push_back(std::move(frame));
        out.cameras.push_back(scene.camera);
        if (out.objectGroups.empty()) out.objectGroups.emplace_back();
        out.objectGroups[0].poses.push_back(glm::translate(glm::mat4(1.0f), static_cast<float>(f) * step));
    }
    place(0);
    scene.camera = camera;
    scene.options.render.layers = layers;
    return out;
}

namespace {

// The groups of virtual objects that move as one over a sequence: each animation's meshes, and the meshes
// without keyframes.
std::vector<std::vector<size_t>> objectGroupMeshes(const Scene& scene) {
    std::vector<std::vector<size_t>> groups;
    std::vector<bool> animated(scene.virtuals.size(), false);
    for (const ObjectAnimation& animation : scene.animations) {
        groups.emplace_back();
        for (size_t m = animation.firstMesh; m < animation.firstMesh + animation.meshCount; ++m) {
            groups.back().push_back(m);
            animated.at(m) = true;
        }
    }
    std::vector<size_t> still;
    for (size_t m = 0; m < scene.virtuals.size(); ++m)
        if (!animated[m]) still.push_back(m);
    if (!still.empty()) groups.push_back(std::move(still));
    return groups;
}

}  // namespace

MotionFrames renderSequence(Scene& scene, int frames) {
    if (scene.sequence.empty()) throw InputError(scene.file.string(), "the scene has no \"sequence\"");
    const std::vector<SequenceFrame> sequence = scene.sequence;
    const size_t count =
        frames > 0 ? std::min<size_t>(static_cast<size_t>(frames), sequence.size()) : sequence.size();
    if (count < 3)
        throw InputError(scene.sequenceFile.string(),
                         fmt::format("at least 3 frames are needed, the sequence has {}", count));
    const ShownFrame shown = shownFrame(scene);
    const bool layers = scene.options.render.layers;
    scene.options.render.layers = true;  // the depth, to follow the surfaces under a moving camera
    const int first = sequence.front().index;
    std::vector<SequenceFrame> order = framesBeforeSequence(scene);
    order.insert(order.end(), sequence.begin(), sequence.begin() + static_cast<std::ptrdiff_t>(count));
    const std::vector<std::vector<size_t>> groups = objectGroupMeshes(scene);
    auto poseAt = [&](size_t group, int frame) {
        return group < scene.animations.size() ? worldFromObjectAt(scene.animations[group], frame)
                                               : glm::mat4(1.0f);
    };
    FrameRenderer renderer;
    MotionFrames out;
    out.objectGroups.resize(groups.size());
    for (const SequenceFrame& frame : order) {
        showFrame(scene, frame);
        RenderOutput output = renderer.render(scene);
        if (frame.index < first) continue;
        out.frames.push_back(std::move(output));
        out.cameras.push_back(frame.camera);
        out.indices.push_back(frame.index);
        for (size_t g = 0; g < groups.size(); ++g) {
            MotionFrames::ObjectGroup& group = out.objectGroups[g];
            group.poses.push_back(poseAt(g, frame.index) * glm::inverse(poseAt(g, first)));
            if (groups.size() < 2) continue;
            Bounds3f bounds;
            for (size_t m : groups[g]) bounds.extend(scene.virtuals[m].bounds());
            group.bounds.push_back(bounds);
        }
    }
    restoreShownFrame(scene, shown);
    scene.options.render.layers = layers;
    return out;
}

namespace {

void checkFrames(std::span<const RenderOutput> frames) {
    if (frames.size() < 3) throw InputError("frames", "at least 3 frames are needed");
    const int width = frames[0].composite.width(), height = frames[0].composite.height();
    for (const RenderOutput& f : frames)
        if (f.composite.width() != width || f.composite.height() != height || f.delta.width() != width ||
            f.delta.height() != height || f.objectMask.width() != width || f.objectMask.height() != height)
            throw InputError("frames", "the frames are not all of one size");
}

using Rgb = std::array<float, 3>;

Rgb rgbAt(const Image& image, int x, int y) {
    return {image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2)};
}

// Adds one triple's second and first differences, per channel.
void accumulate(const Rgb& a, const Rgb& b, const Rgb& c, double& second, double& first) {
    for (int ch = 0; ch < 3; ++ch) {
        const double pa = a[ch], pb = b[ch], pc = c[ch];
        second += (pc - 2.0 * pb + pa) * (pc - 2.0 * pb + pa);
        first += 0.25 * (pc - pa) * (pc - pa);
    }
}

double ratio(double second, double first) {
    return first > 0.0 ? std::sqrt(second / first) : (second > 0.0 ? INFINITY : 0.0);
}

// A frame's pixel shows the same surface as a reprojected point when its depth is within this fraction.
constexpr float kDepthTolerance = 0.02f;
// ... and the surface is flat over the pixels a lookup reads: the second difference of their inverse depths
// (linear across a plane's image) along rows and columns stays under this fraction of the inverse depth, on
// real surfaces (a room's walls meeting in a corner make one of 1e-2 and more: 1e-2 there raised the
// noise-free figure of the Cornell box's turning camera from 0.32 to 0.39) and on the objects, which are
// curved (the test scene's ball at 96 x 72 makes about 2e-3 in its middle).
constexpr float kRealInverseDepthKink = 2e-3f;
constexpr float kObjectInverseDepthKink = 1e-2f;

// Catmull-Rom's cubic weights of the four pixels around a point `t` in [0, 1] past the second one: exact for
// quadratics, so that a smooth change (a soft shadow's edge) is looked up between pixels with an error far
// below bilinear interpolation's, which counted as flicker under a moving camera.
std::array<float, 4> cubicWeights(float t) {
    const float t2 = t * t, t3 = t2 * t;
    return {0.5f * (-t3 + 2.0f * t2 - t), 0.5f * (3.0f * t3 - 5.0f * t2 + 2.0f),
            0.5f * (-3.0f * t3 + 4.0f * t2 + t), 0.5f * (t3 - t2)};
}

// What the measure follows: an object's pixels in the composite, the real ones' in the delta.
const Image& measured(const RenderOutput& frame, bool object) {
    return object ? frame.composite : frame.delta;
}

// The measured value (3 channels) at world point `p` seen by `frame` from `camera`: a cubic lookup over the
// 4 x 4 pixels around its projection, each of which must show the same kind of surface (`object`: an
// object's pixel covered fully; otherwise a real one) of one flat surface (no crease between them) at p's
// depth. False where any does not, or p's pixels leave the image.
bool valueAt(const RenderOutput& frame, const Camera& camera, const glm::mat4& cameraFromWorld, glm::vec3 p,
             bool object, Rgb& out) {
    const Image& image = measured(frame, object);
    const glm::vec3 q = glm::vec3(cameraFromWorld * glm::vec4(p, 1.0f));
    if (!(q.z < -1e-6f)) return false;
    const float depth = -q.z;
    const glm::vec2 pixel = camera.imagePoint(q) - glm::vec2(0.5f);  // pixel (i, j)'s centre at (i, j)
    if (!(pixel.x >= 1.0f && pixel.y >= 1.0f && pixel.x < static_cast<float>(camera.width - 2) &&
          pixel.y < static_cast<float>(camera.height - 2)))
        return false;
    const int x0 = static_cast<int>(pixel.x), y0 = static_cast<int>(pixel.y);
    const std::array<float, 4> wx = cubicWeights(pixel.x - static_cast<float>(x0)),
                               wy = cubicWeights(pixel.y - static_cast<float>(y0));
    std::array<std::array<float, 4>, 4> d;  // the pixels' inverse depths, [row][column]
    float inverseDepth = 0.0f;              // looked up like the values: exact across a plane
    out = {0.0f, 0.0f, 0.0f};
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            const int x = x0 - 1 + i, y = y0 - 1 + j;
            const float mask = frame.objectMask.at(x, y, 0);
            if (object ? mask < 1.0f : mask != 0.0f) return false;
            d[j][i] = 1.0f / frame.depth.at(x, y, 0);
            const float w = wx[i] * wy[j];
            inverseDepth += w * d[j][i];
            for (int ch = 0; ch < 3; ++ch) out[ch] += w * image.at(x, y, ch);
        }
    if (!(std::abs(inverseDepth * depth - 1.0f) <= kDepthTolerance)) return false;
    const float kink = (object ? kObjectInverseDepthKink : kRealInverseDepthKink) / depth;
    for (int a = 0; a < 4; ++a)
        for (int b = 1; b < 3; ++b)
            if (!(std::abs(d[a][b - 1] - 2.0f * d[a][b] + d[a][b + 1]) <= kink) ||
                !(std::abs(d[b - 1][a] - 2.0f * d[b][a] + d[b + 1][a]) <= kink))
                return false;
    return true;
}

// The mean delta per frame over the pixels that are real in every frame.
std::vector<double> meanDeltas(std::span<const RenderOutput> frames) {
    const int width = frames[0].composite.width(), height = frames[0].composite.height();
    std::vector<double> means;
    std::vector<uint8_t> real(static_cast<size_t>(width) * height, 1);
    for (const RenderOutput& f : frames)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                if (f.objectMask.at(x, y, 0) != 0.0f) real[static_cast<size_t>(y) * width + x] = 0;
    for (const RenderOutput& f : frames) {
        double sum = 0.0;
        size_t count = 0;
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                if (!real[static_cast<size_t>(y) * width + x]) continue;
                sum += (f.delta.at(x, y, 0) + f.delta.at(x, y, 1) + f.delta.at(x, y, 2)) / 3.0;
                ++count;
            }
        means.push_back(count ? sum / static_cast<double>(count) : 0.0);
    }
    return means;
}

}  // namespace

TemporalFigures temporalInstability(std::span<const RenderOutput> frames) {
    checkFrames(frames);
    const int width = frames[0].composite.width(), height = frames[0].composite.height();
    TemporalFigures out;
    double realSecond = 0.0, realFirst = 0.0, objectSecond = 0.0, objectFirst = 0.0;
    for (size_t t = 1; t + 1 < frames.size(); ++t) {
        const RenderOutput &a = frames[t - 1], &b = frames[t], &c = frames[t + 1];
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const float ma = a.objectMask.at(x, y, 0), mb = b.objectMask.at(x, y, 0),
                            mc = c.objectMask.at(x, y, 0);
                if (ma == 0.0f && mb == 0.0f && mc == 0.0f) {
                    accumulate(rgbAt(a.delta, x, y), rgbAt(b.delta, x, y), rgbAt(c.delta, x, y), realSecond,
                               realFirst);
                    ++out.realSamples;
                } else if (ma >= 1.0f && mb >= 1.0f && mc >= 1.0f) {
                    accumulate(rgbAt(a.composite, x, y), rgbAt(b.composite, x, y), rgbAt(c.composite, x, y),
                               objectSecond, objectFirst);
                    ++out.objectSamples;
                }
            }
    }
    out.realInstability = ratio(realSecond, realFirst);
    out.objectInstability = ratio(objectSecond, objectFirst);
    out.meanDelta = meanDeltas(frames);
    return out;
}

TemporalFigures temporalInstability(const MotionFrames& motion) {
    const std::span<const RenderOutput> frames = motion.frames;
    checkFrames(frames);
    if (motion.cameras.size() != frames.size()) throw InputError("cameras", "expected one camera per frame");
    bool still = true;
    for (const Camera& c : motion.cameras) still = still && c == motion.cameras[0];
    if (still) return temporalInstability(frames);
    const int width = frames[0].composite.width(), height = frames[0].composite.height();
    for (const RenderOutput& f : frames)
        if (f.depth.width() != width || f.depth.height() != height)
            throw InputError("frames",
                             "following the surfaces under a moving camera needs each frame's depth");
    TemporalFigures out;
    out.followsSurfaces = true;
    std::vector<glm::mat4> cameraFromWorld;
    for (const Camera& c : motion.cameras) cameraFromWorld.push_back(glm::inverse(c.worldFromCamera));
    const std::vector<MotionFrames::ObjectGroup>& groups = motion.objectGroups;
    for (const MotionFrames::ObjectGroup& group : groups)
        if (group.poses.size() != frames.size() ||
            (groups.size() > 1 && group.bounds.size() != frames.size()))
            throw InputError("objectGroups", "expected a pose (and with several groups, bounds) per frame");
    // The index of the group whose object shows at point p: the only one whose bounds in this frame (a
    // little larger: `grown`) hold it; -1 when it is not one.
    auto groupAt = [&](std::span<const Bounds3f> grown, glm::vec3 p) -> int {
        if (groups.size() == 1) return 0;
        int found = -1;
        for (size_t g = 0; g < grown.size(); ++g) {
            if (!grown[g].contains(p)) continue;
            if (found >= 0) return -1;
            found = static_cast<int>(g);
        }
        return found;
    };
    double realSecond = 0.0, realFirst = 0.0, objectSecond = 0.0, objectFirst = 0.0;
    for (size_t t = 1; t + 1 < frames.size(); ++t) {
        const RenderOutput &a = frames[t - 1], &b = frames[t], &c = frames[t + 1];
        const Camera& camera = motion.cameras[t];
        // Each group's points now, where they were in the frame before and will be in the frame after.
        std::vector<std::pair<glm::mat4, glm::mat4>> toBeforeAfter;
        std::vector<Bounds3f> grown;
        for (const MotionFrames::ObjectGroup& group : groups) {
            const glm::mat4 fromNow = glm::inverse(group.poses[t]);
            toBeforeAfter.emplace_back(group.poses[t - 1] * fromNow, group.poses[t + 1] * fromNow);
            if (group.bounds.empty()) continue;
            Bounds3f b = group.bounds[t];
            const glm::vec3 margin(0.01f * glm::length(b.diagonal()) + 1e-6f);
            b.min -= margin;
            b.max += margin;
            grown.push_back(b);
        }
        const glm::vec3 eye = camera.position();
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const float mask = b.objectMask.at(x, y, 0), depth = b.depth.at(x, y, 0);
                const bool object = mask >= 1.0f;
                if ((mask != 0.0f && !object) || !std::isfinite(depth)) continue;
                // rayDirection is 1 long along the camera's axis: the z depth takes it to the point.
                const glm::vec3 p = eye + depth * camera.rayDirection(static_cast<float>(x) + 0.5f,
                                                                      static_cast<float>(y) + 0.5f);
                glm::vec3 pBefore = p, pAfter = p;
                if (object) {
                    const int group = groupAt(grown, p);
                    if (group < 0) continue;
                    const auto& [toBefore, toAfter] = toBeforeAfter[static_cast<size_t>(group)];
                    pBefore = glm::vec3(toBefore * glm::vec4(p, 1.0f));
                    pAfter = glm::vec3(toAfter * glm::vec4(p, 1.0f));
                }
                Rgb before, after;
                if (!valueAt(a, motion.cameras[t - 1], cameraFromWorld[t - 1], pBefore, object, before) ||
                    !valueAt(c, motion.cameras[t + 1], cameraFromWorld[t + 1], pAfter, object, after))
                    continue;
                const Rgb now = rgbAt(measured(b, object), x, y);
                if (object) {
                    accumulate(before, now, after, objectSecond, objectFirst);
                    ++out.objectSamples;
                } else {
                    accumulate(before, now, after, realSecond, realFirst);
                    ++out.realSamples;
                }
            }
    }
    out.realInstability = ratio(realSecond, realFirst);
    out.objectInstability = ratio(objectSecond, objectFirst);
    out.meanDelta = meanDeltas(frames);
    return out;
}

nlohmann::ordered_json temporalToJson(const TemporalFigures& f) {
    nlohmann::ordered_json json;
    json["frames"] = f.meanDelta.size();
    json["real_instability"] = f.realInstability;
    json["object_instability"] = f.objectInstability;
    json["follows_surfaces"] = f.followsSurfaces;
    json["real_samples"] = f.realSamples;
    json["object_samples"] = f.objectSamples;
    json["mean_delta"] = f.meanDelta;
    return json;
}

}  // namespace deltagi
