// Mesh input: loading mesh files with Assimp (mesh_io.cpp), and the clean-up every input mesh goes through
// before it reaches the renderer: transform to world space, validation, vertex normals (mesh.cpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deltagi/scene.h"

namespace deltagi {

// The material values a mesh file gives; each is absent when the file does not give it (Assimp's default
// material, used for files without materials, gives none).
struct FileMaterial {
    std::string name;
    std::optional<glm::vec3> albedo;    // Kd
    std::optional<glm::vec3> specular;  // Ks
    std::optional<glm::vec3> emission;  // Ke (emitted radiance), where the file gives a non-zero one
    // glTF's roughness factor squared, else from the Phong exponent Ns: sqrt(2 / (Ns + 2)); within (0, 1]
    std::optional<float> roughness;
};

struct FileMesh {
    TriangleMesh mesh;  // in the file's coordinates; mesh.material is left at its defaults
    FileMaterial material;
};

// Loads the triangles of an OBJ, PLY, glTF or GLB file (anything Assimp reads), node transforms applied,
// points and lines dropped, smooth vertex normals generated where the file has none (creases sharper than
// kCreaseAngleDeg stay sharp). Meshes are named `baseName` when there is one, else "baseName/<mesh name or
// index>". Throws InputError(where, ...) when the file cannot be read or holds no triangles.
inline constexpr float kCreaseAngleDeg = 80.0f;
std::vector<FileMesh> loadMeshFile(const std::filesystem::path& file, const std::string& where,
                                   const std::string& baseName);

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
