// The materials of mesh files, as Assimp 5.2 gives them: glTF 2.0's metallic-roughness materials with their
// textures and samplers, and OBJ/MTL's Phong materials with their maps.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>

#include <assimp/GltfMaterial.h>
#include <assimp/material.h>
#include <assimp/scene.h>
#include <assimp/texture.h>
#include <fmt/format.h>

#include "deltagi/error.h"
#include "io/file_names.h"
#include "scene/mesh_io.h"

namespace deltagi {

namespace fs = std::filesystem;

namespace {

constexpr float kMinRoughness = 1e-3f;  // roughness is in (0, 1]; a huge Ns still gives a usable lobe
// A bump map (OBJ bump/map_Bump) whose mean texel is within this of (0.5, 0.5, 1) in x and y, with z above
// kNormalMapMinBlue, is a tangent-space normal map (exporters such as Blender's write normal maps there).
constexpr float kNormalMapMeanTolerance = 0.15f;
constexpr float kNormalMapMinBlue = 0.6f;

// glTF's sampler filters (the OpenGL enumerants glTF uses).
constexpr int kGlNearest = 9728;
constexpr int kGlNearestMipmapNearest = 9984;
constexpr int kGlNearestMipmapLinear = 9986;

// Assimp invents a material for files that have none: "DefaultMaterial" for OBJ, and an unnamed one with
// white diffuse and specular for PLY. Such a stand-in gives no values of its own.
bool isStandIn(const std::string& name, const fs::path& file) {
    return name == AI_DEFAULT_MATERIAL_NAME || (name.empty() && lowerExtension(file) == ".ply");
}

std::string describe(const FileMaterial& material, const MaterialReader& reader) {
    return fmt::format("material '{}' of '{}'", material.name, reader.file.filename().string());
}

TextureWrap wrapOf(int mode) {
    switch (mode) {
        case aiTextureMapMode_Clamp:
        case aiTextureMapMode_Decal:
            return TextureWrap::ClampToEdge;
        case aiTextureMapMode_Mirror:
            return TextureWrap::MirroredRepeat;
        default:
            return TextureWrap::Repeat;
    }
}

// glTF's sampler as Assimp keeps it with the texture: wrap modes and filters (absent: repeat, trilinear).
TextureSampler readSampler(const aiMaterial& material, aiTextureType type) {
    TextureSampler sampler;
    int value = 0;
    if (material.Get(AI_MATKEY_MAPPINGMODE_U(type, 0), value) == AI_SUCCESS) sampler.wrapS = wrapOf(value);
    if (material.Get(AI_MATKEY_MAPPINGMODE_V(type, 0), value) == AI_SUCCESS) sampler.wrapT = wrapOf(value);
    if (material.Get(AI_MATKEY_GLTF_MAPPINGFILTER_MAG(type, 0), value) == AI_SUCCESS)
        sampler.magFilter = value == kGlNearest ? TextureFilter::Nearest : TextureFilter::Linear;
    if (material.Get(AI_MATKEY_GLTF_MAPPINGFILTER_MIN(type, 0), value) == AI_SUCCESS) {
        // NEAREST, NEAREST_MIPMAP_NEAREST, NEAREST_MIPMAP_LINEAR pick the nearest texel within a level.
        sampler.minFilter =
            value == kGlNearest || value == kGlNearestMipmapNearest || value == kGlNearestMipmapLinear
                ? TextureFilter::Nearest
                : TextureFilter::Linear;
        sampler.mipmaps = value >= kGlNearestMipmapNearest;
    }
    return sampler;
}

// An embedded texture: compressed bytes (PNG, JPEG) decoded, or Assimp's raw BGRA8 texels.
std::shared_ptr<const Texture> embeddedTexture(const aiTexture& texture, TextureEncoding encoding,
                                               const std::string& where) {
    if (texture.mHeight == 0) {
        const auto* bytes = reinterpret_cast<const std::byte*>(texture.pcData);
        return Texture::decode(std::span<const std::byte>(bytes, texture.pcData ? texture.mWidth : 0),
                               texture.achFormatHint, encoding, where);
    }
    // Kept as 8 bits, as a file's texels are (the Texture decodes them).
    const size_t count = static_cast<size_t>(texture.mWidth) * texture.mHeight;
    std::vector<uint8_t> rgba(count * 4);
    for (size_t i = 0; i < count; ++i) {
        const aiTexel& t = texture.pcData[i];
        rgba[4 * i] = t.r, rgba[4 * i + 1] = t.g, rgba[4 * i + 2] = t.b, rgba[4 * i + 3] = t.a;
    }
    return std::make_shared<const Texture>(static_cast<int>(texture.mWidth),
                                           static_cast<int>(texture.mHeight), std::move(rgba), encoding,
                                           where);
}

// The texture of `type` (its first), with its sampler and texture coordinate set; an empty slot when the
// material has none. `label` names it in messages ("base colour texture").
TextureSlot readTexture(const aiMaterial& material, aiTextureType type, TextureEncoding encoding,
                        const std::string& label, const FileMaterial& result, MaterialReader& reader) {
    aiString path;
    TextureSlot slot;
    if (material.Get(AI_MATKEY_TEXTURE(type, 0), path) != AI_SUCCESS || path.length == 0) return slot;
    const std::string where = fmt::format("{}: {}, {}", reader.where, describe(result, reader), label);
    int texCoord = 0;
    if (material.Get(AI_MATKEY_UVWSRC(type, 0), texCoord) == AI_SUCCESS && texCoord != 0 && texCoord != 1) {
        reader.warnings.push_back(
            fmt::format("{}: reads texture coordinate set {}; only sets 0 and 1 are "
                        "read: the texture is ignored",
                        where, texCoord));
        return slot;
    }
    slot.texCoord = texCoord;
    slot.sampler = readSampler(material, type);
    if (const aiTexture* embedded = reader.scene.GetEmbeddedTexture(path.C_Str())) {
        slot.texture = embeddedTexture(*embedded, encoding, where);
        return slot;
    }
    if (path.C_Str()[0] == '*')
        throw InputError(where,
                         fmt::format("embedded texture '{}' does not exist in the file", path.C_Str()));
    fs::path file = fs::path(path.C_Str());
    if (file.is_relative()) file = reader.file.parent_path() / file;
    slot.texture = reader.textures.load(file.lexically_normal(), encoding, where);
    return slot;
}

// A factor of a metallic-roughness material clamped to [lo, 1], with a warning when it was outside [0, 1].
float unitFactor(float value, float lo, const char* key, const FileMaterial& result, MaterialReader& reader) {
    if (!(value >= 0.0f && value <= 1.0f))
        reader.warnings.push_back(fmt::format("{}: {}: {} is {}, outside [0, 1]: clamped", reader.where,
                                              describe(result, reader), key, value));
    return std::isfinite(value) ? std::clamp(value, lo, 1.0f) : 1.0f;
}

void readMetallicRoughness(const aiMaterial& material, FileMaterial& result, MaterialReader& reader) {
    aiColor4D base;
    if (material.Get(AI_MATKEY_BASE_COLOR, base) == AI_SUCCESS ||
        material.Get(AI_MATKEY_COLOR_DIFFUSE, base) == AI_SUCCESS) {
        glm::vec3 rgb;
        for (int c = 0; c < 3; ++c)
            rgb[c] = unitFactor(c == 0   ? base.r
                                : c == 1 ? base.g
                                         : base.b,
                                0.0f, "baseColorFactor", result, reader);
        result.albedo = rgb;
        result.opacity = unitFactor(base.a, 0.0f, "baseColorFactor's alpha", result, reader);
    }
    float value = 0.0f;
    if (material.Get(AI_MATKEY_METALLIC_FACTOR, value) == AI_SUCCESS)
        result.metallic = unitFactor(value, 0.0f, "metallicFactor", result, reader);
    // Perceptual roughness 0 (a perfect mirror) becomes kMinRoughness, as the scene format's minimum.
    if (material.Get(AI_MATKEY_ROUGHNESS_FACTOR, value) == AI_SUCCESS)
        result.roughness = unitFactor(value, kMinRoughness, "roughnessFactor", result, reader);

    aiString alphaMode;
    if (material.Get(AI_MATKEY_GLTF_ALPHAMODE, alphaMode) == AI_SUCCESS) {
        const std::string mode = alphaMode.C_Str();
        if (mode == "MASK" || mode == "BLEND") result.alphaMode = AlphaMode::Mask;
        if (mode == "MASK" && material.Get(AI_MATKEY_GLTF_ALPHACUTOFF, value) == AI_SUCCESS)
            result.alphaCutoff = unitFactor(value, 0.0f, "alphaCutoff", result, reader);
        if (mode == "BLEND" && !reader.warnedBlend) {
            reader.warnedBlend = true;
            reader.warnings.push_back(
                fmt::format("{}: {}: alphaMode BLEND is read as MASK with alphaCutoff 0.5 "
                            "(surfaces are opaque or cut out, never blended; said once "
                            "per file)",
                            reader.where, describe(result, reader)));
        }
    }
    result.baseColorTexture = readTexture(material, aiTextureType_BASE_COLOR, TextureEncoding::Srgb,
                                          "base colour texture", result, reader);
    if (!result.baseColorTexture)
        result.baseColorTexture = readTexture(material, aiTextureType_DIFFUSE, TextureEncoding::Srgb,
                                              "base colour texture", result, reader);
    // Assimp 5.2 keeps glTF's metallicRoughnessTexture as aiTextureType_UNKNOWN.
    result.metallicRoughnessTexture = readTexture(material, aiTextureType_UNKNOWN, TextureEncoding::Linear,
                                                  "metallic-roughness texture", result, reader);
    result.occlusionTexture = readTexture(material, aiTextureType_LIGHTMAP, TextureEncoding::Linear,
                                          "occlusion texture", result, reader);
    if (result.occlusionTexture &&
        material.Get(AI_MATKEY_GLTF_TEXTURE_STRENGTH(aiTextureType_LIGHTMAP, 0), value) == AI_SUCCESS)
        result.occlusionStrength = unitFactor(value, 0.0f, "occlusionTexture.strength", result, reader);
}

// OBJ's maps with no place in deltagi's Phong materials: said, not silently dropped.
void warnIgnoredMaps(const aiMaterial& material, FileMaterial& result, MaterialReader& reader) {
    struct Ignored {
        aiTextureType type;
        const char* what;
    };
    static constexpr Ignored kIgnored[] = {{aiTextureType_OPACITY, "an opacity map (map_d)"},
                                           {aiTextureType_DISPLACEMENT, "a displacement map (disp)"}};
    aiString path;
    for (const Ignored& map : kIgnored)
        if (material.Get(AI_MATKEY_TEXTURE(map.type, 0), path) == AI_SUCCESS)
            reader.warnings.push_back(
                fmt::format("{}: {}: {} ('{}') is ignored: deltagi's Phong materials have "
                            "no such texture",
                            reader.where, describe(result, reader), map.what, path.C_Str()));
}

void readPhongTextures(const aiMaterial& material, FileMaterial& result, MaterialReader& reader) {
    result.baseColorTexture = readTexture(material, aiTextureType_DIFFUSE, TextureEncoding::Srgb,
                                          "diffuse texture (map_Kd)", result, reader);
    result.specularTexture = readTexture(material, aiTextureType_SPECULAR, TextureEncoding::Srgb,
                                         "specular texture (map_Ks)", result, reader);
    result.roughnessTexture = readTexture(material, aiTextureType_DIFFUSE_ROUGHNESS, TextureEncoding::Linear,
                                          "roughness map (map_Pr)", result, reader);
    result.shininessTexture = readTexture(material, aiTextureType_SHININESS, TextureEncoding::Linear,
                                          "shininess map (map_Ns)", result, reader);
    // A bump map is a height map by the MTL spec, but exporters write normal maps there too: one whose mean
    // is the flat normal's colour is used as a normal map; a height map is not (converting it needs the
    // bump multiplier's scale in world units, which the file does not pin down).
    TextureSlot bump = readTexture(material, aiTextureType_HEIGHT, TextureEncoding::Linear, "bump map (bump)",
                                   result, reader);
    if (bump && !result.normalTexture) {
        const glm::vec4 mean = bump.texture->average();
        if (std::abs(mean.x - 0.5f) < kNormalMapMeanTolerance &&
            std::abs(mean.y - 0.5f) < kNormalMapMeanTolerance && mean.z > kNormalMapMinBlue)
            result.normalTexture = bump;
        else
            reader.warnings.push_back(
                fmt::format("{}: {}: the bump map ('{}') is a height map, which deltagi "
                            "does not read: ignored (give a tangent-space normal map as "
                            "\"norm\")",
                            reader.where, describe(result, reader), bump.texture->name()));
    }
    warnIgnoredMaps(material, result, reader);
}

}  // namespace

std::shared_ptr<const Texture> TextureCache::load(const fs::path& file, TextureEncoding encoding,
                                                  const std::string& where) {
    auto [entry, inserted] = textures_.try_emplace({file.string(), encoding});
    if (inserted) {
        try {
            entry->second = Texture::load(file, encoding, where);
        } catch (...) {
            textures_.erase(entry);
            throw;
        }
    }
    return entry->second;
}

FileMaterial readFileMaterial(const aiMaterial& material, MaterialReader& reader) {
    FileMaterial result;
    aiString name;
    if (material.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) result.name = name.C_Str();
    if (isStandIn(result.name, reader.file)) return result;
    const std::string ext = lowerExtension(reader.file);
    float metallic = 0.0f;
    if (ext == ".gltf" || ext == ".glb" || material.Get(AI_MATKEY_METALLIC_FACTOR, metallic) == AI_SUCCESS)
        result.model = MaterialModel::MetallicRoughness;

    aiColor3D colour;
    if (result.model == MaterialModel::Phong) {
        if (material.Get(AI_MATKEY_COLOR_DIFFUSE, colour) == AI_SUCCESS)
            result.albedo = glm::vec3(colour.r, colour.g, colour.b);
        if (material.Get(AI_MATKEY_COLOR_SPECULAR, colour) == AI_SUCCESS)
            result.specular = glm::vec3(colour.r, colour.g, colour.b);
    }
    // Many exporters write "Ke 0 0 0" for every material; only a positive, finite Ke makes an emitter.
    if (material.Get(AI_MATKEY_COLOR_EMISSIVE, colour) == AI_SUCCESS) {
        glm::vec3 ke(colour.r, colour.g, colour.b);
        float strength = 1.0f;  // KHR_materials_emissive_strength
        if (material.Get(AI_MATKEY_EMISSIVE_INTENSITY, strength) == AI_SUCCESS && std::isfinite(strength) &&
            strength >= 0.0f)
            ke *= strength;
        bool valid = ke != glm::vec3(0.0f);
        for (int c = 0; c < 3; ++c) valid = valid && std::isfinite(ke[c]) && ke[c] >= 0.0f;
        if (valid) result.emission = ke;
    }
    result.emissiveTexture = readTexture(material, aiTextureType_EMISSIVE, TextureEncoding::Srgb,
                                         "emissive texture", result, reader);
    result.normalTexture = readTexture(material, aiTextureType_NORMALS, TextureEncoding::Linear,
                                       "normal texture", result, reader);
    float value = 0.0f;
    if (result.normalTexture &&
        material.Get(AI_MATKEY_GLTF_TEXTURE_SCALE(aiTextureType_NORMALS, 0), value) == AI_SUCCESS &&
        std::isfinite(value))
        result.normalScale = value;

    if (result.model == MaterialModel::MetallicRoughness) {
        readMetallicRoughness(material, result, reader);
        return result;
    }
    float shininess = 0.0f;
    if (material.Get(AI_MATKEY_ROUGHNESS_FACTOR, value) == AI_SUCCESS && std::isfinite(value)) {
        // MTL's "Pr" without "Pm": perceptual roughness; its square is the Beckmann-like roughness of Phong.
        result.roughness = std::clamp(value * value, kMinRoughness, 1.0f);
    } else if (material.Get(AI_MATKEY_SHININESS, shininess) == AI_SUCCESS && std::isfinite(shininess)) {
        // The Phong exponent of the normalized lobe is n = 2/r^2 - 2 (scene.h), so r = sqrt(2 / (n + 2)).
        float roughness = shininess > 0.0f ? std::sqrt(2.0f / (shininess + 2.0f)) : 1.0f;
        result.roughness = std::clamp(roughness, kMinRoughness, 1.0f);
    }
    readPhongTextures(material, result, reader);
    return result;
}

void dropUnusableTextures(Material& material, const TriangleMesh& mesh, const std::string& where,
                          std::vector<std::string>& warnings) {
    struct Slot {
        TextureSlot* slot;
        const char* name;
    };
    const Slot slots[] = {{&material.baseColorTexture, "base colour"},
                          {&material.specularTexture, "specular"},
                          {&material.roughnessTexture, "roughness"},
                          {&material.shininessTexture, "shininess"},
                          {&material.metallicRoughnessTexture, "metallic-roughness"},
                          {&material.normalTexture, "normal"},
                          {&material.emissiveTexture, "emissive"},
                          {&material.occlusionTexture, "occlusion"}};
    for (const Slot& s : slots) {
        if (!*s.slot) continue;
        const bool hasSet = s.slot->texCoord == 0 ? !mesh.uvs.empty() : !mesh.uvs1.empty();
        if (!hasSet) {
            warnings.push_back(
                fmt::format("{}: mesh '{}' has no texture coordinates (set {}): its {} texture "
                            "('{}') is ignored",
                            where, mesh.name, s.slot->texCoord, s.name, s.slot->texture->name()));
            *s.slot = TextureSlot{};
        }
    }
    // A normal map on a mesh without tangents uses each triangle's texture-coordinate derivative instead
    // (surface_material.cpp).
}

}  // namespace deltagi
