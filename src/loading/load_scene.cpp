// loadScene(): a scene file read by scene/ (scene/scene_reader.h), then the real surfaces whose material asks
// for "albedo": "estimate" given their albedo from the photo by reference/'s path-traced estimation
// (deltagi/albedo_estimation.h). The one place where reading a scene needs the path tracer, so it sits above
// both (src/README.md).
#include <utility>

#include "deltagi/albedo_estimation.h"
#include "deltagi/scene_io.h"
#include "scene/scene_reader.h"

namespace deltagi {

namespace {

// The estimator's defaults but fewer samples, as it runs at every load.
constexpr int kLoadEstimateSamples = 16;

Scene withRequestedAlbedo(SceneRead read) {
    Scene& scene = read.scene;
    bool any = false;
    for (bool estimate : read.estimateAlbedo) any |= estimate;
    if (!any) return std::move(scene);
    AlbedoOptions options;
    options.samplesPerPixel = kLoadEstimateSamples;
    options.meshes = std::move(read.estimateAlbedo);
    const AlbedoEstimate estimate = estimateAlbedo(scene, options);
    applyAlbedo(scene, estimate);
    for (const std::string& warning : estimate.warnings) scene.warnings.push_back(warning);
    return std::move(scene);
}

}  // namespace

Scene loadScene(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
    return withRequestedAlbedo(readScene(file, overrides));
}

Scene loadScene(const nlohmann::json& document, const std::filesystem::path& file) {
    return withRequestedAlbedo(readScene(document, file));
}

}  // namespace deltagi
