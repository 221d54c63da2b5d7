// Loading mesh files with Assimp: one importer set-up for every format.
#include "mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <assimp/Importer.hpp>

#include "deltagi/error.h"

namespace deltagi {

namespace {

constexpr float kMinRoughness = 1e-3f;  // roughness is in (0, 1]; a huge Ns still gives a usable lobe

// Assimp invents a material for files that have none: "DefaultMaterial" for OBJ, and an unnamed one with
// white diffuse and specular for PLY. Such a stand-in gives no values of its own.
bool isStandIn(const std::string& name, const std::filesystem::path& file) {
    std::string ext = file.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return name == AI_DEFAULT_MATERIAL_NAME || (name.empty() && ext == ".ply");
}

FileMaterial readMaterial(const aiMaterial& material, const std::filesystem::path& file) {
    FileMaterial result;
    aiString name;
    if (material.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) result.name = name.C_Str();
    if (isStandIn(result.name, file)) return result;
    aiColor3D colour;
    if (material.Get(AI_MATKEY_COLOR_DIFFUSE, colour) == AI_SUCCESS)
        result.albedo = glm::vec3(colour.r, colour.g, colour.b);
    if (material.Get(AI_MATKEY_COLOR_SPECULAR, colour) == AI_SUCCESS)
        result.specular = glm::vec3(colour.r, colour.g, colour.b);
    // Many exporters write "Ke 0 0 0" for every material; only a positive, finite Ke makes an emitter.
    if (material.Get(AI_MATKEY_COLOR_EMISSIVE, colour) == AI_SUCCESS) {
        const glm::vec3 ke(colour.r, colour.g, colour.b);
        bool valid = ke != glm::vec3(0.0f);
        for (int c = 0; c < 3; ++c) valid = valid && std::isfinite(ke[c]) && ke[c] >= 0.0f;
        if (valid) result.emission = ke;
    }
    float shininess = 0.0f, roughnessFactor = 0.0f;
    if (material.Get(AI_MATKEY_ROUGHNESS_FACTOR, roughnessFactor) == AI_SUCCESS &&
        std::isfinite(roughnessFactor)) {
        // glTF: perceptual roughness; its square is the Beckmann roughness this renderer uses (scene.h).
        result.roughness = std::clamp(roughnessFactor * roughnessFactor, kMinRoughness, 1.0f);
    } else if (material.Get(AI_MATKEY_SHININESS, shininess) == AI_SUCCESS && std::isfinite(shininess)) {
        // The Phong exponent of the normalized lobe is n = 2/r^2 - 2 (scene.h), so r = sqrt(2 / (n + 2)).
        float roughness = shininess > 0.0f ? std::sqrt(2.0f / (shininess + 2.0f)) : 1.0f;
        result.roughness = std::clamp(roughness, kMinRoughness, 1.0f);
    }
    return result;
}

TriangleMesh readTriangles(const aiMesh& source) {
    TriangleMesh mesh;
    mesh.positions.reserve(source.mNumVertices);
    for (unsigned i = 0; i < source.mNumVertices; ++i) {
        const aiVector3D& p = source.mVertices[i];
        mesh.positions.emplace_back(p.x, p.y, p.z);
    }
    if (source.HasNormals()) {
        mesh.normals.reserve(source.mNumVertices);
        for (unsigned i = 0; i < source.mNumVertices; ++i) {
            const aiVector3D& n = source.mNormals[i];
            mesh.normals.emplace_back(n.x, n.y, n.z);
        }
    }
    mesh.triangles.reserve(source.mNumFaces);
    for (unsigned f = 0; f < source.mNumFaces; ++f) {
        const aiFace& face = source.mFaces[f];
        if (face.mNumIndices == 3)
            mesh.triangles.emplace_back(face.mIndices[0], face.mIndices[1], face.mIndices[2]);
    }
    return mesh;
}

bool hasPolygons(const aiScene& scene) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m)
        for (unsigned f = 0; f < scene.mMeshes[m]->mNumFaces; ++f)
            if (scene.mMeshes[m]->mFaces[f].mNumIndices >= 3) return true;
    return false;
}

}  // namespace

std::vector<FileMesh> loadMeshFile(const std::filesystem::path& file, const std::string& where,
                                   const std::string& baseName) {
    Assimp::Importer importer;
    importer.SetPropertyFloat(AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, kCreaseAngleDeg);
    // Bake node transforms but keep one mesh per node: joining meshes of equal material would name, say, all
    // white walls of a Cornell box after the first of them.
    importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
    constexpr unsigned kFlags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                aiProcess_GenSmoothNormals | aiProcess_PreTransformVertices |
                                aiProcess_SortByPType;
    const aiScene* scene = importer.ReadFile(file.string(), kFlags);
    // SortByPType splits meshes by primitive type; point and line meshes are skipped below.
    if (scene == nullptr) {
        // PreTransformVertices fails a file of points alone ("all meshes are orphaned"): say what is wrong.
        std::string error = importer.GetErrorString();
        Assimp::Importer plain;
        if (const aiScene* raw = plain.ReadFile(file.string(), 0); raw != nullptr && !hasPolygons(*raw))
            throw InputError(where, fmt::format("'{}' contains no triangles", file.filename().string()));
        throw InputError(where, fmt::format("cannot load '{}': {}", file.string(), error));
    }

    std::vector<FileMesh> meshes;
    std::map<std::string, int> timesSeen;
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh& source = *scene->mMeshes[m];
        if ((source.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
        FileMesh result{readTriangles(source), {}};
        if (result.mesh.triangles.empty()) continue;
        if (source.mMaterialIndex < scene->mNumMaterials)
            result.material = readMaterial(*scene->mMaterials[source.mMaterialIndex], file);
        std::string name =
            baseName + "/" + (source.mName.length > 0 ? source.mName.C_Str() : std::to_string(m));
        // A mesh placed by several nodes (glTF instancing) appears once per node: number the repeats.
        int seen = ++timesSeen[name];
        result.mesh.name = seen == 1 ? name : fmt::format("{} ({})", name, seen);
        meshes.push_back(std::move(result));
    }
    if (meshes.empty())
        throw InputError(where, fmt::format("'{}' contains no triangles", file.filename().string()));
    if (meshes.size() == 1) meshes[0].mesh.name = baseName;
    return meshes;
}

}  // namespace deltagi
