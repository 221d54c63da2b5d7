// A scene file read into a Scene, all but the one step that needs the path tracer: the real surfaces whose
// material asks for "albedo": "estimate" are listed, and estimated by the public loadScene()
// (src/loading/load_scene.cpp), which runs reference/'s albedo estimation over the scene read here.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/scene.h"

namespace deltagi {

struct SceneRead {
    Scene scene;
    // Per real mesh (scene.real), whether its entry asked for "albedo": "estimate"; its material holds a
    // grey start value until it is estimated. Only true with a photo (scene.background): checked here.
    std::vector<bool> estimateAlbedo;
};

// The document (with `overrides` applied in order, each as applyOverride) read, validated and loaded; throws
// InputError as loadScene() documents (include/deltagi/scene_io.h).
SceneRead readScene(const std::filesystem::path& file, const std::vector<std::string>& overrides);
SceneRead readScene(const nlohmann::json& document, const std::filesystem::path& file);

}  // namespace deltagi
