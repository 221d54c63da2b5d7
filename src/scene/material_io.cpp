#include "scene/material_io.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deltagi/error.h"

namespace deltagi {

namespace {

constexpr float kEnergyTolerance = 1e-6f;            // albedo + specular <= 1 up to rounding
constexpr float kMinPhongRoughness = 1e-3f;          // as mesh files' roughness (mesh_materials.cpp)
constexpr const char* kEstimateAlbedo = "estimate";  // "albedo": "estimate"
constexpr float kEstimateStart = 0.5f;               // the grey an estimate starts from

// "base_color": [r, g, b] or [r, g, b, a] (or one number for grey), each in [0, 1].
void readBaseColor(const JsonNode& node, MaterialOverrides& result) {
    if (node.value().is_array() && node.size() == 4) {
        glm::vec3 rgb;
        for (size_t c = 0; c < 3; ++c) rgb[static_cast<int>(c)] = node.element(c).floatNumber(kUnit);
        result.albedo = rgb;
        result.opacity = node.element(3).floatNumber(kUnit);
        return;
    }
    result.albedo = node.colour(kUnit);
}

// The file's roughness in the meaning of `to`: Phong's is Beckmann-like, r = alpha; glTF's is perceptual,
// alpha = r^2 (scene.h).
std::optional<float> convertRoughness(std::optional<float> roughness, MaterialModel from, MaterialModel to) {
    if (!roughness || from == to) return roughness;
    return to == MaterialModel::MetallicRoughness ? std::sqrt(*roughness)
                                                  : std::max(*roughness * *roughness, kMinPhongRoughness);
}

}  // namespace

bool asksForEstimate(const nlohmann::json& albedo) {
    return albedo.is_string() && albedo.get<std::string>() == kEstimateAlbedo;
}

MaterialOverrides readMaterial(const JsonNode& node, const TextureReader& readTexture,
                               std::vector<std::string>& warnings) {
    node.allowKeys({"albedo", "specular", "roughness", "glossiness", "emission", "emission_scale",
                    "base_color", "metallic", "base_color_texture", "metallic_roughness_texture",
                    "normal_texture", "emissive_texture", "occlusion_texture", "alpha_mode", "alpha_cutoff"});
    MaterialOverrides result;
    // The metallic-roughness model's own keys, and Phong's.
    for (const char* key : {"base_color", "metallic", "metallic_roughness_texture"})
        if (auto n = node.find(key)) {
            if (node.has("specular"))
                n->fail(
                    "give either \"specular\" (the Phong model) or \"base_color\", \"metallic\" and "
                    "\"metallic_roughness_texture\" (glTF's metallic-roughness model), not both");
            result.model = MaterialModel::MetallicRoughness;
        }
    if (node.has("specular")) result.model = MaterialModel::Phong;
    if (auto n = node.find("base_color")) {
        if (node.has("albedo")) n->fail("give either albedo or base_color (the same colour), not both");
        readBaseColor(*n, result);
    }
    if (auto n = node.find("albedo"))
        result.albedo = asksForEstimate(n->value()) ? glm::vec3(kEstimateStart) : n->colour(kUnit);
    if (auto n = node.find("specular")) result.specular = n->colour(kUnit);
    if (auto n = node.find("metallic")) result.metallic = n->floatNumber(kUnit);
    if (auto n = node.find("emission")) result.emission = n->colour(kNonNegative);
    if (auto n = node.find("emission_scale")) result.emissionScale = n->floatNumber(kNonNegative);
    result.emissionWhere = node.childWhere("emission_scale");
    if (auto n = node.find("roughness")) result.roughness = n->floatNumber({0.0, 1.0, true, false});
    if (auto n = node.find("glossiness")) {
        if (result.roughness) n->fail("give either roughness or glossiness, not both");
        result.roughness = 1.0f - n->floatNumber({0.0, 1.0, false, true});
    }
    if (auto n = node.find("alpha_mode")) {
        const std::string mode = n->string();
        if (mode == "opaque") {
            result.alphaMode = AlphaMode::Opaque;
        } else if (mode == "mask" || mode == "blend") {
            result.alphaMode = AlphaMode::Mask;
            if (mode == "blend")
                warnings.push_back(n->where() +
                                   ": \"blend\" is read as \"mask\" with alpha_cutoff 0.5 (surfaces are "
                                   "opaque or cut out, never blended)");
        } else {
            n->fail("expected \"opaque\", \"mask\" or \"blend\", got \"" + mode + "\"");
        }
        if (mode == "blend") {
            if (auto cutoff = node.find("alpha_cutoff")) cutoff->fail("a cut-off applies to \"mask\" only");
            result.alphaCutoff = 0.5f;
        }
    }
    if (auto n = node.find("alpha_cutoff")) result.alphaCutoff = n->floatNumber(kUnit);
    if (auto n = node.find("base_color_texture"))
        result.baseColorTexture = readTexture(*n, TextureEncoding::Srgb);
    if (auto n = node.find("metallic_roughness_texture"))
        result.metallicRoughnessTexture = readTexture(*n, TextureEncoding::Linear);
    if (auto n = node.find("normal_texture")) result.normalTexture = readTexture(*n, TextureEncoding::Linear);
    if (auto n = node.find("emissive_texture"))
        result.emissiveTexture = readTexture(*n, TextureEncoding::Srgb);
    if (auto n = node.find("occlusion_texture"))
        result.occlusionTexture = readTexture(*n, TextureEncoding::Linear);
    return result;
}

Material combineMaterial(const MaterialOverrides& json, const FileMaterial& file, const std::string& meshName,
                         const std::string& where) {
    Material m;
    m.model = json.model.value_or(file.model);
    const bool phong = m.model == MaterialModel::Phong, fileModel = m.model == file.model;
    m.albedo = json.albedo.value_or(file.albedo.value_or(m.albedo));
    if (phong)
        m.specular = json.specular.value_or(fileModel ? file.specular.value_or(m.specular) : m.specular);
    m.roughness =
        json.roughness.value_or(convertRoughness(file.roughness, file.model, m.model).value_or(m.roughness));
    if (!phong)
        m.metallic = json.metallic.value_or(fileModel ? file.metallic.value_or(m.metallic) : m.metallic);
    m.opacity = json.opacity.value_or(file.opacity);
    m.alphaMode = json.alphaMode.value_or(file.alphaMode);
    m.alphaCutoff = json.alphaCutoff.value_or(file.alphaCutoff);
    m.baseColorTexture = json.baseColorTexture.value_or(file.baseColorTexture);
    if (phong && fileModel) m.specularTexture = file.specularTexture;
    if (phong && fileModel) m.shininessTexture = file.shininessTexture;
    m.roughnessTexture = file.roughnessTexture;
    if (!phong)
        m.metallicRoughnessTexture =
            json.metallicRoughnessTexture.value_or(fileModel ? file.metallicRoughnessTexture : TextureSlot{});
    m.normalTexture = json.normalTexture.value_or(file.normalTexture);
    m.normalScale = json.normalTexture ? 1.0f : file.normalScale;
    m.emissiveTexture = json.emissiveTexture.value_or(file.emissiveTexture);
    m.occlusionTexture = json.occlusionTexture.value_or(file.occlusionTexture);
    m.occlusionStrength = json.occlusionTexture ? 1.0f : file.occlusionStrength;
    // The scale applies to the file's Ke too: MTL files give emission in arbitrary units.
    m.emission = json.emission.value_or(file.emission.value_or(m.emission)) * json.emissionScale;
    if (!std::isfinite(m.emission.x) || !std::isfinite(m.emission.y) || !std::isfinite(m.emission.z))
        throw InputError(json.emissionWhere,
                         fmt::format("mesh '{}': emission times emission_scale ({}) is not a "
                                     "finite number",
                                     meshName, json.emissionScale));
    if (const float brightest = std::max({m.emission.x, m.emission.y, m.emission.z});
        brightest > static_cast<float>(kMaxRadiance))
        throw InputError(json.emissionWhere,
                         fmt::format("mesh '{}': emission times emission_scale is {:.3g}, more than {:.0e}, "
                                     "beyond which the render's 32-bit floats overflow",
                                     meshName, brightest, kMaxRadiance));
    std::string origin = (!json.albedo && file.albedo) || (!json.specular && file.specular)
                             ? fmt::format(
                                   " (values not given in \"material\" come from material '{}' of the mesh "
                                   "file)",
                                   file.name)
                             : "";
    constexpr const char* kChannel[] = {"r", "g", "b"};
    for (int c = 0; c < 3; ++c) {
        if (!(m.albedo[c] >= 0.0f && m.albedo[c] <= 1.0f) ||
            !(m.specular[c] >= 0.0f && m.specular[c] <= 1.0f))
            throw InputError(where,
                             fmt::format("mesh '{}': albedo and specular must be in [0, 1], got {} and {} in "
                                         "channel {}{}",
                                         meshName, m.albedo[c], m.specular[c], kChannel[c], origin));
        if (m.albedo[c] + m.specular[c] > 1.0f + kEnergyTolerance)
            throw InputError(
                where,
                fmt::format("mesh '{}': albedo + specular exceeds 1 in channel {} ({} + {} = {}){}", meshName,
                            kChannel[c], m.albedo[c], m.specular[c], m.albedo[c] + m.specular[c], origin));
    }
    return m;
}

}  // namespace deltagi
