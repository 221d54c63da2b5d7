// The "material" key of a scene file's mesh entry (docs/scene-format.md#material): its values read, and
// combined with the mesh file's material into the Material a mesh gets. Part of the scene reader
// (scene_io.cpp); every check raises InputError naming the file and the key.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/scene.h"
#include "deltagi/texture.h"
#include "scene/json_reader.h"
#include "scene/mesh_io.h"

namespace deltagi {

// What the "material" key gives, each value only when the key is there.
struct MaterialOverrides {
    std::optional<glm::vec3> albedo, specular, emission;  // albedo: "albedo" or "base_color"
    std::optional<float> roughness, metallic, opacity, alphaCutoff;
    std::optional<AlphaMode> alphaMode;
    std::optional<TextureSlot> baseColorTexture, metallicRoughnessTexture, normalTexture, emissiveTexture,
        occlusionTexture;
    std::optional<MaterialModel> model;  // when a key belongs to one model only
    float emissionScale = 1.0f;
    std::string emissionWhere;  // the "emission_scale" key, for an overflowing product
};

// Whether an "albedo" value is "estimate": the real mesh's albedo comes from the photo (loadScene() in
// src/loading/load_scene.cpp), starting from grey.
bool asksForEstimate(const nlohmann::json& albedo);

// Reads a texture key's file (relative to the scene file, each read once) with the given encoding.
using TextureReader = std::function<TextureSlot(const JsonNode&, TextureEncoding)>;

// The "material" node; a warning for what is read differently from what it says ("blend" as "mask").
MaterialOverrides readMaterial(const JsonNode& node, const TextureReader& readTexture,
                               std::vector<std::string>& warnings);

// The JSON's keys win, then the mesh file's values, then the defaults of Material; the result must conserve
// energy. The model is the JSON's when one of its keys belongs to one model ("specular": Phong; "base_color",
// "metallic", "metallic_roughness_texture": metallic-roughness), else the file's. `where` names the entry (or
// its "material"), for values that came from the file.
Material combineMaterial(const MaterialOverrides& json, const FileMaterial& file, const std::string& meshName,
                         const std::string& where);

}  // namespace deltagi
