#include "deltagi/temporal.h"

#include <cmath>

#include "deltagi/error.h"
#include "deltagi/transforms.h"

namespace deltagi {

std::vector<RenderOutput> renderMotion(Scene& scene, const MotionOptions& options) {
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
    FrameRenderer renderer;
    std::vector<RenderOutput> frames;
    const int warmUp =
        options.warmUpFrames >= 0 ? options.warmUpFrames : scene.options.render.temporalFrames - 1;
    for (int f = -warmUp; f < options.frames; ++f) {
        place(f);
        RenderOutput frame = renderer.render(scene);
        if (f >= 0) frames.push_back(std::move(frame));
    }
    place(0);
    scene.camera = camera;
    return frames;
}

TemporalFigures temporalInstability(std::span<const RenderOutput> frames) {
    if (frames.size() < 3) throw InputError("frames", "at least 3 frames are needed");
    const int width = frames[0].composite.width(), height = frames[0].composite.height();
    for (const RenderOutput& f : frames)
        if (f.composite.width() != width || f.composite.height() != height || f.delta.width() != width ||
            f.delta.height() != height || f.objectMask.width() != width || f.objectMask.height() != height)
            throw InputError("frames", "the frames are not all of one size");
    TemporalFigures out;
    double realSecond = 0.0, realFirst = 0.0, objectSecond = 0.0, objectFirst = 0.0;
    auto accumulate = [](const Image& a, const Image& b, const Image& c, int x, int y, double& second,
                         double& first) {
        for (int ch = 0; ch < 3; ++ch) {
            const double pa = a.at(x, y, ch), pb = b.at(x, y, ch), pc = c.at(x, y, ch);
            second += (pc - 2.0 * pb + pa) * (pc - 2.0 * pb + pa);
            first += 0.25 * (pc - pa) * (pc - pa);
        }
    };
    for (size_t t = 1; t + 1 < frames.size(); ++t) {
        const RenderOutput &a = frames[t - 1], &b = frames[t], &c = frames[t + 1];
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const float ma = a.objectMask.at(x, y, 0), mb = b.objectMask.at(x, y, 0),
                            mc = c.objectMask.at(x, y, 0);
                if (ma == 0.0f && mb == 0.0f && mc == 0.0f) {
                    accumulate(a.delta, b.delta, c.delta, x, y, realSecond, realFirst);
                    ++out.realSamples;
                } else if (ma >= 1.0f && mb >= 1.0f && mc >= 1.0f) {
                    accumulate(a.composite, b.composite, c.composite, x, y, objectSecond, objectFirst);
                    ++out.objectSamples;
                }
            }
    }
    auto ratio = [](double second, double first) {
        return first > 0.0 ? std::sqrt(second / first) : (second > 0.0 ? INFINITY : 0.0);
    };
    out.realInstability = ratio(realSecond, realFirst);
    out.objectInstability = ratio(objectSecond, objectFirst);
    // The mean delta over the pixels that are real in every frame.
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
        out.meanDelta.push_back(count ? sum / static_cast<double>(count) : 0.0);
    }
    return out;
}

nlohmann::ordered_json temporalToJson(const TemporalFigures& f) {
    nlohmann::ordered_json json;
    json["frames"] = f.meanDelta.size();
    json["real_instability"] = f.realInstability;
    json["object_instability"] = f.objectInstability;
    json["real_samples"] = f.realSamples;
    json["object_samples"] = f.objectSamples;
    json["mean_delta"] = f.meanDelta;
    return json;
}

}  // namespace deltagi
