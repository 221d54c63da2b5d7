// Reading the scene file's "environment" object (docs/scene-format.md): the light probe image in any of the
// supported projections, its rotation and intensity.
#pragma once

#include <filesystem>
#include <optional>

#include "core/environment.h"
#include "deltagi/scene.h"
#include "scene/json_reader.h"

namespace deltagi {

// The environment an image of the light gives through the scene file's "environment" `node` (its
// projection and that projection's parameters for the image's size, rotation and intensity): what
// readEnvironment() does with the file's image, and `deltagi live` with each light-camera frame. The image
// must be finite and >= 0. Throws InputError naming the key, or `imageName` for an image of the wrong shape.
// `conversion`: where a caller that converts many images through the same `node` (a light camera's frames)
// keeps the projection's conversion (EquirectConversion) for the next image of the same size.
Environment environmentFromImage(const JsonNode& node, Image image, const std::string& imageName,
                                 std::optional<EquirectConversion>* conversion = nullptr);

// Reads the map (converted to equirectangular, bad pixels repaired, times the intensity) and calls
// setEnvironment(). Warnings (an LDR image, repaired pixels) are added to scene.warnings; errors name the
// file and the key. scene.options must already be read.
void readEnvironment(const JsonNode& node, const std::filesystem::path& sceneFolder, Scene& scene);

}  // namespace deltagi
