// Reading the scene file's "environment" object (docs/scene-format.md): the light probe image in any of the
// supported projections, its rotation and intensity.
#pragma once

#include <filesystem>

#include "deltagi/scene.h"
#include "scene/json_reader.h"

namespace deltagi {

// Reads the map (converted to equirectangular, bad pixels repaired, times the intensity) and calls
// setEnvironment(). Warnings (an LDR image, repaired pixels) are added to scene.warnings; errors name the
// file and the key. scene.options must already be read.
void readEnvironment(const JsonNode& node, const std::filesystem::path& sceneFolder, Scene& scene);

}  // namespace deltagi
