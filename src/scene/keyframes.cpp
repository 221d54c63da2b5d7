// Keyframed virtual objects: reading "keyframes", evaluating a pose at a frame, placing the objects, and the
// volume region a moving object needs (deltagi/keyframes.h, src/scene/keyframes_io.h).
#include "deltagi/keyframes.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/transforms.h"
#include "scene/keyframes_io.h"

namespace deltagi {

namespace {

// Frames (and times times the frame rate) a keyframe may name: whole sequences of hours at 240 frames/s.
constexpr double kMaxKeyFrame = 1e7;
// fixVolumeRegionOverAnimation samples every whole frame of the keyframes' span; beyond this many it samples
// this many evenly (a span of a million frames is no sequence anyone renders, but must not hang).
constexpr double kMaxSweepSamples = 100000.0;

// The rotation of the scene file's "rotate_deg" [x, y, z]: Rz * Ry * Rx, as in readTransform (scene_io.cpp).
glm::quat eulerDegrees(glm::vec3 degrees) {
    glm::mat4 m(1.0f);
    m = glm::rotate(m, glm::radians(degrees.z), glm::vec3(0, 0, 1));
    m = glm::rotate(m, glm::radians(degrees.y), glm::vec3(0, 1, 0));
    m = glm::rotate(m, glm::radians(degrees.x), glm::vec3(1, 0, 0));
    return glm::normalize(glm::quat_cast(glm::mat3(m)));
}

// The value of a channel at `frame`: held outside its keys, interpolated by `mix` between them.
template <typename T, typename Mix>
T sample(const std::vector<std::pair<double, T>>& keys, double frame, T identity, Mix mix) {
    if (keys.empty()) return identity;
    if (frame <= keys.front().first) return keys.front().second;
    if (frame >= keys.back().first) return keys.back().second;
    const auto next =
        std::upper_bound(keys.begin(), keys.end(), frame,
                         [](double f, const std::pair<double, T>& key) { return f < key.first; });
    const auto& [f1, v1] = *next;
    const auto& [f0, v0] = *(next - 1);
    return mix(v0, v1, static_cast<float>((frame - f0) / (f1 - f0)));
}

std::pair<double, double> keySpan(const ObjectAnimation& a) {
    double first = std::numeric_limits<double>::infinity(), last = -first;
    for (double f : {a.translate.empty() ? first : a.translate.front().first,
                     a.rotation.empty() ? first : a.rotation.front().first,
                     a.scale.empty() ? first : a.scale.front().first})
        first = std::min(first, f);
    for (double f :
         {a.translate.empty() ? last : a.translate.back().first,
          a.rotation.empty() ? last : a.rotation.back().first, a.scale.empty() ? last : a.scale.back().first})
        last = std::max(last, f);
    return {first, last};
}

}  // namespace

ObjectAnimation readKeyframes(const JsonNode& node, double frameRate) {
    node.requireArray();
    if (node.size() == 0) node.fail("expected at least one keyframe, got an empty list");
    ObjectAnimation animation;
    animation.where = node.where();
    std::optional<std::string> kind;  // "frame" or "time", the same for every key
    double previous = -1.0;
    std::string previousWhere;
    for (size_t i = 0; i < node.size(); ++i) {
        const JsonNode key = node.element(i);
        key.requireObject();
        key.allowKeys({"frame", "time", "translate", "rotate_deg", "scale"});
        const bool hasFrame = key.has("frame"), hasTime = key.has("time");
        if (hasFrame && hasTime) key.child("time").fail("give either \"frame\" or \"time\", not both");
        if (!hasFrame && !hasTime)
            key.fail("missing \"frame\" (a frame of the transforms file) or \"time\" (seconds)");
        const std::string thisKind = hasFrame ? "frame" : "time";
        if (kind && *kind != thisKind)
            key.child(thisKind).fail(
                fmt::format("the first keyframe gives a \"{}\": give every keyframe of an object a \"{}\"",
                            *kind, *kind));
        kind = thisKind;
        const JsonNode at = key.child(thisKind);
        const double frame = hasFrame ? at.number({0.0, kMaxKeyFrame})
                                      : at.number({0.0, kMaxKeyFrame / frameRate}) * frameRate;
        if (i > 0 && !(frame > previous))
            at.fail(fmt::format(
                "keyframes out of order: {} {} does not come after {} ({}); give them in "
                "increasing order",
                thisKind, at.number(), hasFrame ? previous : previous / frameRate, previousWhere));
        previous = frame;
        previousWhere = at.path();
        if (!key.has("translate") && !key.has("rotate_deg") && !key.has("scale"))
            key.fail("expected at least one of \"translate\", \"rotate_deg\" and \"scale\"");
        if (auto n = key.find("translate")) animation.translate.emplace_back(frame, n->vec3());
        if (auto n = key.find("rotate_deg")) animation.rotation.emplace_back(frame, eulerDegrees(n->vec3()));
        if (auto n = key.find("scale")) {
            const glm::vec3 scale = n->value().is_number() ? glm::vec3(n->floatNumber()) : n->vec3();
            if (scale.x == 0.0f || scale.y == 0.0f || scale.z == 0.0f)
                n->fail("expected non-zero scale factors (a zero scale flattens the mesh)");
            if (!animation.scale.empty()) {
                const glm::vec3 before = animation.scale.back().second;
                for (int a = 0; a < 3; ++a)
                    if ((before[a] < 0.0f) != (scale[a] < 0.0f))
                        n->fail(fmt::format(
                            "the scale's {} factor changes sign from the keyframe before ({} to {}): between "
                            "them it would pass through 0 and flatten the mesh",
                            "xyz"[a], before[a], scale[a]));
            }
            animation.scale.emplace_back(frame, scale);
        }
        try {
            checkTransform(worldFromObjectAt(animation, frame));
        } catch (const InputError& e) {
            key.fail(e.message());
        }
    }
    return animation;
}

glm::mat4 worldFromObjectAt(const ObjectAnimation& animation, double frame) {
    auto lerp = [](glm::vec3 a, glm::vec3 b, float t) { return a + t * (b - a); };
    auto slerp = [](glm::quat a, glm::quat b, float t) { return glm::normalize(glm::slerp(a, b, t)); };
    const glm::vec3 translate = sample(animation.translate, frame, glm::vec3(0.0f), lerp);
    const glm::quat rotation = sample(animation.rotation, frame, glm::quat(1.0f, 0.0f, 0.0f, 0.0f), slerp);
    const glm::vec3 scale = sample(animation.scale, frame, glm::vec3(1.0f), lerp);
    return glm::scale(glm::translate(glm::mat4(1.0f), translate) * glm::mat4_cast(rotation), scale);
}

void poseObjects(Scene& scene, double frame) {
    for (const ObjectAnimation& animation : scene.animations) {
        const glm::mat4 pose = worldFromObjectAt(animation, frame);
        for (size_t m = animation.firstMesh; m < animation.firstMesh + animation.meshCount; ++m) {
            try {
                setTransform(scene.virtuals.at(m), pose);
            } catch (const InputError& e) {
                throw InputError(animation.where, fmt::format("at frame {}: {}", frame, e.what()));
            }
        }
    }
}

void fixVolumeRegionOverAnimation(Scene& scene) {
    VolumeOptions& volume = scene.options.volume;
    if (scene.animations.empty() || (volume.center && volume.size)) return;
    std::vector<bool> animated(scene.virtuals.size(), false);
    Bounds3f swept;
    for (const ObjectAnimation& animation : scene.animations) {
        const auto [first, last] = keySpan(animation);
        const double step = std::max(1.0, std::ceil((last - first) / kMaxSweepSamples));
        std::vector<double> frames{first, last};
        for (double f = std::floor(first); f <= last; f += step) frames.push_back(f);
        for (size_t m = animation.firstMesh; m < animation.firstMesh + animation.meshCount; ++m) {
            animated.at(m) = true;
            const TriangleMesh& mesh = scene.virtuals[m];
            const Bounds3f box = mesh.objectSpace ? mesh.objectSpace->bounds() : mesh.bounds();
            for (double f : frames) {
                const glm::mat4 pose = worldFromObjectAt(animation, f);
                for (int corner = 0; corner < 8; ++corner) {
                    const glm::vec3 p((corner & 1) ? box.max.x : box.min.x,
                                      (corner & 2) ? box.max.y : box.min.y,
                                      (corner & 4) ? box.max.z : box.min.z);
                    swept.extend(glm::vec3(pose * glm::vec4(p, 1.0f)));
                }
            }
        }
    }
    for (size_t m = 0; m < scene.virtuals.size(); ++m)
        if (!animated[m]) swept.extend(scene.virtuals[m].bounds());
    // volumeRegion() over stand-ins: a mesh of two points spanning the swept box, one spanning the real
    // scene.
    Scene standIn;
    standIn.options = scene.options;
    standIn.virtuals.resize(1);
    standIn.virtuals[0].positions = {swept.min, swept.max};
    Bounds3f real;
    for (const TriangleMesh& mesh : scene.real) real.extend(mesh.bounds());
    if (!real.empty()) {
        standIn.real.resize(1);
        standIn.real[0].positions = {real.min, real.max};
    }
    const VolumeRegion region = volumeRegion(standIn);
    volume.center = region.origin + glm::vec3(0.5f * region.size);
    volume.size = region.size;
}

}  // namespace deltagi
