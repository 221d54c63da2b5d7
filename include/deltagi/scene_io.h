// Reading scene files (JSON). The format is documented in docs/scene-format.md.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/scene.h"

namespace deltagi {

// Applies one "--set KEY=VALUE" override to a parsed scene document. KEY is a dotted path; numeric
// components index arrays ("virtual.0.material.albedo"); VALUE is parsed as JSON, and taken as a string when
// it is not valid JSON. Throws InputError naming the override when KEY walks through a non-object/array or
// an index is out of range.
void applyOverride(nlohmann::json& document, const std::string& keyEqualsValue);

// Reads, validates and loads a scene: the JSON, every mesh (Assimp), the background image. `overrides` are
// applied, in order, to the JSON before it is validated. Throws InputError (file + JSON path + what was
// expected) for any bad input: missing files, malformed JSON, wrong types, unknown keys, empty meshes, NaN
// or infinite vertices, a background of the wrong size, impossible options.
Scene loadScene(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});

// Same, from an already parsed document; `file` is used for messages and to resolve relative paths.
Scene loadScene(const nlohmann::json& document, const std::filesystem::path& file);

// The options as JSON, every key with its value (the defaults where the scene did not set one).
nlohmann::json optionsToJson(const Options& options);

}  // namespace deltagi
