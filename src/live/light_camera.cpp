#include "live/light_camera.h"

#include <cmath>
#include <fstream>
#include <iterator>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "scene/environment_io.h"
#include "scene/json_reader.h"

namespace deltagi {

LightCamera::LightCamera(const std::filesystem::path& sceneFile, const std::vector<std::string>& overrides,
                         double timeConstantSeconds)
    : file_(sceneFile.string()), timeConstant_(timeConstantSeconds) {
    std::ifstream in(sceneFile, std::ios::binary);
    if (!in) throw InputError(file_, "cannot open scene file");
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    document_ = parseJson(text, file_);
    for (const std::string& o : overrides) applyOverride(document_, o);
    if (!document_.is_object() || !document_.contains("environment"))
        throw InputError(file_ + ": environment",
                         "missing: the light camera's frames become the environment, whose \"projection\" "
                         "(\"fisheye\" and its circle, or \"mirror_ball\"), \"rotate_deg\" and \"intensity\" "
                         "(the exposure) say how the camera sees the light");
}

Environment LightCamera::environment(Image frame, double timeSeconds, const std::string& frameName) {
    const JsonNode node(document_["environment"], file_, "environment");
    size_t clipped = 0;
    for (size_t p = 0; p < frame.pixelCount(); ++p) {
        float* rgb = &frame.data()[p * frame.channels()];
        bool white = false;
        for (int c = 0; c < frame.channels(); ++c) {
            if (!(rgb[c] >= 0.0f) || !std::isfinite(rgb[c])) rgb[c] = 0.0f;
            white = white || rgb[c] >= 1.0f;
        }
        clipped += white;
    }
    clippedShare_ =
        frame.pixelCount() ? static_cast<double>(clipped) / static_cast<double>(frame.pixelCount()) : 0.0;
    Environment e = environmentFromImage(node, std::move(frame), frameName, &conversion_);
    const Image& map = e.radiance;
    if (smoothed_.empty() || smoothed_.width() != map.width() || smoothed_.height() != map.height() ||
        !(timeSeconds > lastTime_)) {
        smoothed_ = map;
    } else {
        // An exponential average over time: the weight of the past falls by e every time constant.
        const float keep = static_cast<float>(std::exp(-(timeSeconds - lastTime_) / timeConstant_));
        std::span<float> s = smoothed_.data();
        std::span<const float> m = map.data();
        for (size_t i = 0; i < s.size(); ++i) s[i] = keep * s[i] + (1.0f - keep) * m[i];
    }
    lastTime_ = timeSeconds;
    e.radiance = smoothed_;
    e.file = frameName;
    return e;
}

}  // namespace deltagi
