// Mesh input: loading mesh files with Assimp (mesh_io.cpp), and the clean-up every input mesh goes through
// before it reaches the renderer: transform to world space, validation, vertex normals (mesh.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/scene.h"
#include "deltagi/texture.h"

struct aiMaterial;
struct aiScene;

namespace deltagi {

// Textures read once per path and encoding (the materials of a mesh file, or of a scene file, share them).
class TextureCache {
  public:
    // Texture::load(file, encoding, where): throws InputError(where, ...) naming the file when it is missing,
    // unreadable, empty or not an image.
    std::shared_ptr<const Texture> load(const std::filesystem::path& file, TextureEncoding encoding,
                                        const std::string& where);

  private:
    std::map<std::pair<std::string, TextureEncoding>, std::shared_ptr<const Texture>> textures_;
};

// The material values a mesh file gives; each value is absent when the file does not give it (Assimp's
// default material, used for files without materials, gives none), each texture null.
struct FileMaterial {
    std::string name;
    // MetallicRoughness for glTF files' materials (and any material that gives a metallic factor, as MTL's
    // PBR extension "Pm" does), else Phong.
    MaterialModel model = MaterialModel::Phong;
    std::optional<glm::vec3> albedo;    // Kd; glTF: the base colour factor's rgb
    std::optional<glm::vec3> specular;  // Ks (Phong)
    std::optional<glm::vec3> emission;  // Ke (emitted radiance), where the file gives a non-zero one; glTF:
                                        // the emissive factor times KHR_materials_emissive_strength
    // Phong: from the Phong exponent Ns, sqrt(2 / (Ns + 2)); MetallicRoughness: glTF's (perceptual) roughness
    // factor. Within (0, 1].
    std::optional<float> roughness;
    std::optional<float> metallic;  // glTF's metallic factor, in [0, 1]
    float opacity = 1.0f;           // glTF: the base colour factor's alpha
    AlphaMode alphaMode = AlphaMode::Opaque;
    float alphaCutoff = 0.5f;
    TextureSlot baseColorTexture;  // glTF baseColorTexture; OBJ map_Kd
    TextureSlot specularTexture;   // OBJ map_Ks
    TextureSlot roughnessTexture;  // OBJ map_Pr
    TextureSlot shininessTexture;  // OBJ map_Ns
    TextureSlot metallicRoughnessTexture;
    TextureSlot normalTexture;  // glTF normalTexture; OBJ norm, or bump/map_Bump holding a normal map
    float normalScale = 1.0f;
    TextureSlot emissiveTexture;  // glTF emissiveTexture; OBJ map_Ke
    TextureSlot occlusionTexture;
    float occlusionStrength = 1.0f;
};

// What reading the materials of one mesh file shares: the file, its textures and its warnings.
struct MaterialReader {
    const aiScene& scene;
    std::filesystem::path file;
    std::string where;
    TextureCache textures;
    std::vector<std::string> warnings;  // each prefixed with `where`
    bool warnedBlend = false;           // glTF's BLEND is said once per file
};

// Reads a material of a mesh file (mesh_materials.cpp). Texture files are relative to the mesh file's folder;
// embedded ones ("*0", GLB's) are decoded from memory. A texture that is missing or not an image throws
// InputError(where, ...) naming the mesh file, the material and the texture. What is read but not as the
// file means it (glTF's BLEND read as MASK, factors clamped to [0, 1], OBJ maps without a place in deltagi's
// materials) goes to reader.warnings.
FileMaterial readFileMaterial(const aiMaterial& material, MaterialReader& reader);

// Drops, with a warning prefixed with `where`, the textures of `material` that `mesh` cannot use: those
// reading a texture coordinate set the mesh does not have, and a normal map on a mesh without tangents.
void dropUnusableTextures(Material& material, const TriangleMesh& mesh, const std::string& where,
                          std::vector<std::string>& warnings);

struct FileMesh {
    TriangleMesh mesh;  // in the file's coordinates; mesh.material is left at its defaults
    FileMaterial material;
};

// Loads the triangles of an OBJ, PLY, glTF or GLB file (anything Assimp reads), node transforms applied,
// points and lines dropped, smooth vertex normals generated where the file has none (creases sharper than
// kCreaseAngleDeg stay sharp), per-vertex attributes read (texture coordinates, colours, tangents: see
// readAttributes in mesh_io.cpp) and each mesh's material with its textures (readFileMaterial). Meshes are
// named `baseName` when there is one, else "baseName/<mesh name or index>". Throws InputError(where, ...)
// when the file cannot be read or holds no triangles, a non-finite position or texture coordinate, or a
// texture that cannot be read. Warnings go to `warnings` when given.
inline constexpr float kCreaseAngleDeg = 80.0f;
std::vector<FileMesh> loadMeshFile(const std::filesystem::path& file, const std::string& where,
                                   const std::string& baseName, std::vector<std::string>* warnings = nullptr);

// Nesting bounded before a file reaches Assimp, whose readers recurse (a glTF with 20,000 nested nodes or
// 200,000 '[', a Collada file of 20,000 nested <node>, overflowed the stack): JSON or XML nesting and glTF
// node chains deeper than kMaxFileNesting, node cycles, and buffers or images of a glTF that are not regular
// files, each an InputError naming `where` and the file.
inline constexpr size_t kMaxFileNesting = 1000;
// Returns a glTF's JSON document (for what Assimp does not read), nothing for other files.
std::optional<nlohmann::json> checkMeshFileStructure(const std::filesystem::path& file,
                                                     const std::string& where);

// Run by loadMeshFile before Assimp reads anything: checks the element counts a PLY or OFF header claims
// against the file's size (a truncated file, or a header claiming 3.5e11 vertices in 300 bytes), and the
// memory loading the file needs (from those counts, else in proportion to the file's size) against
// `physicalMemoryBytes` (a parameter so that tests can lower it). Throws InputError(where, ...).
void checkMeshFileClaims(const std::filesystem::path& file, const std::string& where,
                         uint64_t physicalMemoryBytes);

// Area-weighted average of the face normals around each vertex, unit length; (0, 1, 0) where it vanishes.
void computeVertexNormals(TriangleMesh& mesh);

// Positions by `worldFromObject`, normals by its inverse transpose (renormalized), tangents by its linear
// part (renormalized; their handedness w flips under a mirroring transform); a mirroring transform also flips
// the winding, so that outward faces stay outward.
void transformMesh(TriangleMesh& mesh, const glm::mat4& worldFromObject);

// Validates a mesh read from input and makes it ready to render. Throws InputError(where, ...) for a
// non-finite position or texture coordinate (naming the vertex), a vertex colour outside [0, 1], a
// per-vertex attribute whose count is not the vertices', an index out of range, and a mesh without
// triangles or with only degenerate ones. Texture coordinates outside [0, 1] are fine (textures wrap).
// Triangles with area < kDegenerateAreaFactor * (bounding box diagonal)^2 are dropped, unreferenced vertices
// removed (with their attributes), missing or broken normals recomputed and all normals normalized, tangents
// made unit length and perpendicular to the normals (any perpendicular where a tangent is broken), w = +-1.
// Returns the number of degenerate triangles dropped.
inline constexpr double kDegenerateAreaFactor = 1e-12;
size_t cleanMesh(TriangleMesh& mesh, const std::string& where);

}  // namespace deltagi
