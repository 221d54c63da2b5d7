#include "evaluation/benchmark.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#include <fmt/core.h>
#include <tbb/global_control.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/environment.h"
#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "deltagi/transforms.h"

namespace deltagi {

const std::vector<BenchRow>& benchRows() {
    static const std::vector<BenchRow> rows = {
        {"voxelize_ms", {"voxelize"}, 5.0},
        {"rsm_ms", {"rsm"}, 0.2},
        {"inject_ms", {"inject"}, 3.0},
        {"mipmap_ms", {"mipmap"}, 8.0},
        {"diffuse_ms", {"diffuse"}, 6.0},
        {"specular_ms", {"specular"}, 64.0},
        {"shadow_ms", {"shadow"}, 4.0},
        {"sky_ms", {"sky"}, -1.0},
        {"environment_ms", {"environment"}, -1.0},
        {"bounce_ms", {"bounce"}, -1.0},
        {"bvh_ms", {"bvh"}, -1.0},
        {"gbuffer_ms", {"gbuffer"}, -1.0},
        {"shading_ms", {"shading"}, -1.0},
        {"background_ms", {"background"}, -1.0},
        {"temporal_ms", {"temporal"}, -1.0},
        {"composite_ms", {"composite"}, -1.0},
        {"total_ms", {}, 90.2},
    };
    return rows;
}

namespace {

BenchStatistics statistics(std::vector<double> values) {
    BenchStatistics s;
    if (values.empty()) return s;
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    s.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    s.max = values.back();
    return s;
}

// The frames repeat after this many: the objects' circle, the camera's swing and the live light's motion.
constexpr int kPeriod = 16;

float turnOf(int frame) {
    return 2.0f * std::numbers::pi_v<float> * static_cast<float>(frame % kPeriod) /
           static_cast<float>(kPeriod);
}

glm::mat3 aboutVertical(float radians) {
    return glm::mat3(glm::rotate(glm::mat4(1.0f), radians, glm::vec3(0.0f, 1.0f, 0.0f)));
}

// The real light as loaded, which a live benchmark (BenchOptions::live) changes frame by frame.
struct RealLight {
    std::vector<Light> lights;  // the environment's extracted lights included
    std::optional<Environment> environment;
    float radius = 0.0f;  // of the point and spot lights' circle (world units)
};

// Frame `frame`'s real light on `scene` (BenchOptions::live); returns the milliseconds setEnvironment took,
// 0 without an environment map.
double setLiveLight(Scene& scene, const RealLight& original, int frame) {
    const float turn = turnOf(frame);
    scene.lights.clear();
    for (Light light : original.lights) {
        if (light.fromEnvironment) continue;
        if (light.type == Light::Type::Directional)
            light.direction =
                aboutVertical(glm::radians(kLiveLightDegrees) * std::sin(turn)) * light.direction;
        else
            light.position += original.radius * glm::vec3(std::cos(turn) - 1.0f, 0.0f, std::sin(turn));
        scene.lights.push_back(light);
    }
    if (!original.environment) return 0.0;
    Environment environment = *original.environment;
    environment.worldFromEnvironment = aboutVertical(turn) * environment.worldFromEnvironment;
    const auto start = std::chrono::steady_clock::now();
    setEnvironment(scene, std::move(environment));
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

struct CameraPose {
    Camera camera;
    Image photo;
};

// The camera's poses for BenchOptions::cameraDegrees (at most a period, and `frames`), each with the real
// scene rendered alone from there as its photo, lit as frame k is (`live`: the live light of frame k).
std::vector<CameraPose> cameraPoses(const Scene& scene, float degrees, int frames, const RealLight* live) {
    Bounds3f objects;
    for (const TriangleMesh& m : scene.virtuals) objects.extend(m.bounds());
    const glm::vec3 centre = objects.center();
    Scene real;
    real.file = scene.file;
    real.camera = scene.camera;
    real.real = scene.real;
    real.lights = scene.lights;
    real.environment = scene.environment;
    real.options = scene.options;
    std::vector<CameraPose> poses;
    for (int k = 0; k < std::min(frames, kPeriod); ++k) {
        const float angle = degrees * std::sin(turnOf(k));
        real.camera = turnedCamera(scene.camera, centre, angle);
        if (live) setLiveLight(real, *live, k);
        poses.push_back({real.camera, render(real).background});
    }
    return poses;
}

size_t triangleCount(const std::vector<TriangleMesh>& meshes) {
    size_t n = 0;
    for (const TriangleMesh& m : meshes) n += m.triangleCount();
    return n;
}

}  // namespace

BenchStatistics BenchResult::row(const BenchRow& row) const {
    if (row.stages.empty()) return statistics(totals);
    std::vector<double> values;
    for (const std::vector<StageTiming>& frame : frames) {
        double ms = 0.0;
        for (const StageTiming& t : frame)
            if (std::find(row.stages.begin(), row.stages.end(), t.name) != row.stages.end()) ms += t.ms;
        values.push_back(ms);
    }
    return statistics(std::move(values));
}

BenchResult runBenchmark(Scene& scene, const BenchOptions& options,
                         const std::function<void(int, double)>& onFrame) {
    BenchResult result;
    result.options = options;
    result.threads =
        static_cast<int>(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    result.width = scene.camera.width;
    result.height = scene.camera.height;
    const VolumeRegion region = volumeRegion(scene);
    result.volumeResolution = region.resolution;
    result.realTriangles = triangleCount(scene.real);
    result.virtualTriangles = triangleCount(scene.virtuals);

    // The objects' own vertices are moved (and restored at the end): every frame starts from the originals,
    // so the path does not drift.
    std::vector<std::vector<glm::vec3>> original;
    for (const TriangleMesh& m : scene.virtuals) original.push_back(m.positions);
    const float radius = options.motionVoxels * region.voxelSize();
    auto placeObjects = [&](int frame) {
        const float angle = turnOf(frame);
        const glm::vec3 offset = radius * glm::vec3(std::cos(angle) - 1.0f, 0.0f, std::sin(angle));
        for (size_t m = 0; m < scene.virtuals.size(); ++m) {
            std::vector<glm::vec3>& p = scene.virtuals[m].positions;
            for (size_t v = 0; v < p.size(); ++v) p[v] = original[m][v] + offset;
        }
    };

    const int total = options.warmup + options.frames;
    const ShownFrame shown = shownFrame(scene);
    // A tracked sequence: its frames in order, each with its camera, photo and keyframed objects.
    const std::vector<SequenceFrame>& sequence = scene.sequence;
    if (!sequence.empty()) {
        if (options.live || options.cameraDegrees > 0.0f)
            throw InputError(options.live ? "--live" : "--camera-motion",
                             "not with a \"sequence\": its frames move the camera and the keyframed objects "
                             "as the transforms file and the keyframes say");
        result.sequence = sequenceRangeText(scene);
        result.sequenceFrames = static_cast<int>(sequence.size());
    }
    const std::optional<glm::vec3> viewpoint = scene.options.volume.viewpoint;
    const RealLight light{scene.lights, scene.environment, kLiveLightVoxels * region.voxelSize()};
    const float cameraDegrees =
        options.live && options.cameraDegrees == 0.0f ? kLiveCameraDegrees : options.cameraDegrees;
    std::vector<CameraPose> poses;
    result.cameraDegrees = cameraDegrees;
    if (cameraDegrees > 0.0f) {
        // As a sequence does: the volumes light the real surfaces' side that the first camera sees.
        if (!viewpoint) scene.options.volume.viewpoint = shown.camera.position();
        poses = cameraPoses(scene, cameraDegrees, total, options.live ? &light : nullptr);
    }

    FrameRenderer renderer;
    for (int f = 0; f < total; ++f) {
        if (!sequence.empty()) {  // the photo is read before the frame, as a camera's frame arrives
            showFrame(scene, sequence[static_cast<size_t>(f) % sequence.size()]);
        } else {
            placeObjects(f);
        }
        const double environmentMs = options.live ? setLiveLight(scene, light, f) : 0.0;
        if (!poses.empty()) {
            const CameraPose& pose = poses[static_cast<size_t>(f) % poses.size()];
            scene.camera = pose.camera;
            scene.background = pose.photo;
        }
        if (options.cold) renderer.clear();
        RenderOutput out = renderer.render(scene);
        if (light.environment && options.live) {
            out.timings.insert(out.timings.begin(), {"environment", environmentMs});
            out.totalMs += environmentMs;
        }
        if (f < options.warmup) continue;
        const FrameRenderer::KeptWork kept = renderer.lastFrameKept();
        if (kept.world) ++result.worldKeptFrames;
        if (kept.light) ++result.lightKeptFrames;
        result.frames.push_back(std::move(out.timings));
        result.totals.push_back(out.totalMs);
        if (onFrame) onFrame(f - options.warmup, out.totalMs);
    }
    result.volumeBytes = renderer.volumeBytes();
    if (sequence.empty()) placeObjects(0);
    scene.lights = light.lights;
    scene.environment = light.environment;
    restoreShownFrame(scene, shown);
    scene.options.volume.viewpoint = viewpoint;
    return result;
}

nlohmann::ordered_json benchToJson(const BenchResult& r) {
    nlohmann::ordered_json json;
    json["frames"] = r.options.frames;
    json["warmup"] = r.options.warmup;
    json["cold"] = r.options.cold;
    json["live"] = r.options.live;
    json["camera_motion_deg"] = r.cameraDegrees;
    json["sequence"] = r.sequence.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(r.sequence);
    json["world_kept_frames"] = r.worldKeptFrames;
    json["light_kept_frames"] = r.lightKeptFrames;
    json["volume_bytes"] = r.volumeBytes;
    json["threads"] = r.threads;
    json["width"] = r.width;
    json["height"] = r.height;
    json["volume_resolution"] = r.volumeResolution;
    json["triangles"] = {{"real", r.realTriangles}, {"virtual", r.virtualTriangles}};
    for (const BenchRow& row : benchRows()) {
        const BenchStatistics s = r.row(row);
        nlohmann::ordered_json entry = {{"median", s.median}, {"max", s.max}};
        entry["paper"] = row.paperMs >= 0.0 ? nlohmann::ordered_json(row.paperMs) : nlohmann::ordered_json();
        json[row.key] = std::move(entry);
    }
    return json;
}

std::string benchTable(const BenchResult& r) {
    std::string out = fmt::format(
        "{}x{}, volumes {}^3, {} real + {} virtual triangles, {} threads, {} frames ({}{}{} warm-up)\n",
        r.width, r.height, r.volumeResolution, r.realTriangles, r.virtualTriangles, r.threads,
        r.options.frames, r.options.cold ? "cold, " : "", r.options.live ? "live, " : "", r.options.warmup);
    out += fmt::format("volumes with their mip chains: {:.1f} MiB\n",
                       static_cast<double>(r.volumeBytes) / (1024.0 * 1024.0));
    if (r.options.live)
        out += fmt::format(
            "the real light changing every frame; its shadow maps and injection kept in {} of {} frames\n",
            r.lightKeptFrames, r.options.frames);
    if (!r.sequence.empty())
        out += fmt::format(
            "the tracked sequence's {} in order: each frame's camera, photo and keyframed "
            "objects{}; the BVH and voxels kept in {} of {} frames\n",
            r.sequence,
            r.options.warmup + r.options.frames > r.sequenceFrames
                ? ", from its first frame again after its last"
                : "",
            r.worldKeptFrames, r.options.frames);
    if (r.cameraDegrees > 0.0f)
        out += fmt::format("camera swinging +-{} deg; the BVH and voxels kept in {} of {} frames\n",
                           r.cameraDegrees, r.worldKeptFrames, r.options.frames);
    out += fmt::format("{:<15} {:>10} {:>10} {:>12}\n", "stage", "median ms", "max ms", "paper ms");
    for (const BenchRow& row : benchRows()) {
        const BenchStatistics s = r.row(row);
        const std::string paper = row.paperMs >= 0.0 ? fmt::format("{:.1f}", row.paperMs) : "-";
        out += fmt::format("{:<15} {:>10.1f} {:>10.1f} {:>12}\n", row.key, s.median, s.max, paper);
    }
    return out;
}

}  // namespace deltagi
