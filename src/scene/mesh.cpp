// TriangleMesh helpers shared by the mesh loaders and the procedural shapes (declared in mesh_io.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/scene.h"
#include "scene/mesh_io.h"

namespace deltagi {

Bounds3f TriangleMesh::bounds() const {
    Bounds3f b;
    for (glm::vec3 p : positions) b.extend(p);
    return b;
}

namespace {

constexpr float kMinNormalLength = 1e-6f;  // shorter than this, a normal carries no direction
const glm::vec3 kFallbackNormal{0.0f, 1.0f, 0.0f};

bool isFinite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Twice the triangle's area along its normal, in double so that tiny triangles of a large mesh are judged
// correctly.
glm::dvec3 areaVector(const TriangleMesh& mesh, glm::uvec3 t) {
    glm::dvec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
    return glm::cross(b - a, c - a);
}

std::vector<glm::dvec3> areaWeightedNormalSums(const TriangleMesh& mesh) {
    std::vector<glm::dvec3> sums(mesh.positions.size(), glm::dvec3(0.0));
    for (glm::uvec3 t : mesh.triangles) {
        glm::dvec3 n = areaVector(mesh, t);
        sums[t.x] += n;
        sums[t.y] += n;
        sums[t.z] += n;
    }
    return sums;
}

glm::vec3 unitOrFallback(glm::dvec3 n) {
    double length = glm::length(n);
    return length > 0.0 && std::isfinite(length) ? glm::vec3(n / length) : kFallbackNormal;
}

// Keeps element i of `attribute` (empty, or one per vertex) at newIndex[i], for the vertices kept.
template <typename T>
void compact(std::vector<T>& attribute, const std::vector<uint32_t>& newIndex, uint32_t kept,
             uint32_t unused) {
    if (attribute.size() != newIndex.size()) return;
    for (size_t i = 0; i < newIndex.size(); ++i)
        if (newIndex[i] != unused) attribute[newIndex[i]] = attribute[i];
    attribute.resize(kept);
}

// Removes the vertices no triangle refers to, keeping the order of the others, and their attributes with
// them.
void removeUnreferencedVertices(TriangleMesh& mesh) {
    constexpr uint32_t kUnused = UINT32_MAX;
    std::vector<uint32_t> newIndex(mesh.positions.size(), kUnused);
    for (glm::uvec3 t : mesh.triangles) newIndex[t.x] = newIndex[t.y] = newIndex[t.z] = 0;
    uint32_t next = 0;
    for (uint32_t& index : newIndex)
        if (index != kUnused) index = next++;
    compact(mesh.positions, newIndex, next, kUnused);
    compact(mesh.normals, newIndex, next, kUnused);
    compact(mesh.uvs, newIndex, next, kUnused);
    compact(mesh.uvs1, newIndex, next, kUnused);
    compact(mesh.tangents, newIndex, next, kUnused);
    compact(mesh.colors, newIndex, next, kUnused);
    for (glm::uvec3& t : mesh.triangles) t = {newIndex[t.x], newIndex[t.y], newIndex[t.z]};
}

// Every per-vertex attribute is empty or has one value per position; texture coordinates and colours are
// finite (coordinates outside [0, 1] are fine: textures wrap), colours within [0, 1].
void checkAttributes(const TriangleMesh& mesh, const std::string& where) {
    const size_t count = mesh.positions.size();
    auto checkSize = [&](size_t size, const char* what) {
        if (size != 0 && size != count)
            throw InputError(where, fmt::format("mesh '{}' has {} {} for {} vertices (expected none or one "
                                                "per vertex)",
                                                mesh.name, size, what, count));
    };
    checkSize(mesh.normals.size(), "normals");
    checkSize(mesh.uvs.size(), "texture coordinates (set 0)");
    checkSize(mesh.uvs1.size(), "texture coordinates (set 1)");
    checkSize(mesh.tangents.size(), "tangents");
    checkSize(mesh.colors.size(), "vertex colours");
    for (int set = 0; set < 2; ++set) {
        const std::vector<glm::vec2>& uvs = set == 0 ? mesh.uvs : mesh.uvs1;
        for (size_t i = 0; i < uvs.size(); ++i)
            if (!std::isfinite(uvs[i].x) || !std::isfinite(uvs[i].y))
                throw InputError(where,
                                 fmt::format("texture coordinate (set {}) of vertex {} of mesh '{}' is "
                                             "not finite: ({}, {})",
                                             set, i, mesh.name, uvs[i].x, uvs[i].y));
    }
    for (size_t i = 0; i < mesh.colors.size(); ++i) {
        const glm::vec3 c = mesh.colors[i];
        if (!(c.x >= 0.0f && c.x <= 1.0f && c.y >= 0.0f && c.y <= 1.0f && c.z >= 0.0f && c.z <= 1.0f))
            throw InputError(where, fmt::format("vertex colour of vertex {} of mesh '{}' is ({}, {}, {}), "
                                                "expected linear RGB in [0, 1]",
                                                i, mesh.name, c.x, c.y, c.z));
    }
}

// A unit vector perpendicular to the unit vector `n`.
glm::vec3 anyPerpendicular(glm::vec3 n) {
    const glm::vec3 axis = std::abs(n.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
    return glm::normalize(glm::cross(n, axis));
}

// Tangents made perpendicular to the (final) normals and unit length (Gram-Schmidt), w = +-1; a tangent
// along the normal or not finite (a triangle whose texture coordinates are degenerate) becomes any
// perpendicular direction.
void orthonormalizeTangents(TriangleMesh& mesh) {
    for (size_t i = 0; i < mesh.tangents.size(); ++i) {
        const glm::vec3 n = mesh.normals[i];
        glm::vec4& t = mesh.tangents[i];
        glm::vec3 xyz = glm::vec3(t) - n * glm::dot(n, glm::vec3(t));
        const float length = glm::length(xyz);
        xyz = std::isfinite(length) && length > kMinNormalLength ? xyz / length : anyPerpendicular(n);
        t = glm::vec4(xyz, t.w < 0.0f ? -1.0f : 1.0f);
    }
}

}  // namespace

void computeVertexNormals(TriangleMesh& mesh) {
    std::vector<glm::dvec3> sums = areaWeightedNormalSums(mesh);
    mesh.normals.resize(mesh.positions.size());
    for (size_t i = 0; i < sums.size(); ++i) mesh.normals[i] = unitOrFallback(sums[i]);
}

void transformMesh(TriangleMesh& mesh, const glm::mat4& worldFromObject) {
    glm::mat3 linear(worldFromObject);
    glm::mat3 normalMatrix = glm::transpose(glm::inverse(linear));
    const bool mirrors = glm::determinant(linear) < 0.0f;
    for (glm::vec3& p : mesh.positions) p = glm::vec3(worldFromObject * glm::vec4(p, 1.0f));
    for (glm::vec3& n : mesh.normals) {
        // A normal that cannot be transformed is zeroed here and recomputed from the faces by cleanMesh().
        glm::vec3 m = normalMatrix * n;
        float length = glm::length(m);
        n = std::isfinite(length) && length > 0.0f ? m / length : glm::vec3(0.0f);
    }
    // Tangents lie in the surface: they transform like positions' differences. A mirror turns cross(n, t)
    // against the transformed bitangent, so the handedness flips. cleanMesh() makes them perpendicular to the
    // normals again (a non-uniform scale shears them).
    for (glm::vec4& t : mesh.tangents) {
        glm::vec3 m = linear * glm::vec3(t);
        float length = glm::length(m);
        t = glm::vec4(std::isfinite(length) && length > 0.0f ? m / length : glm::vec3(0.0f),
                      mirrors ? -t.w : t.w);
    }
    if (mirrors)
        for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
}

size_t cleanMesh(TriangleMesh& mesh, const std::string& where) {
    if (mesh.triangles.empty())
        throw InputError(where, fmt::format("mesh '{}' contains no triangles", mesh.name));
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        glm::vec3 p = mesh.positions[i];
        if (!isFinite(p))
            throw InputError(where, fmt::format("vertex {} of mesh '{}' is not finite: ({}, {}, {})", i,
                                                mesh.name, p.x, p.y, p.z));
    }
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
        glm::uvec3 tri = mesh.triangles[t];
        for (int k = 0; k < 3; ++k)
            if (tri[k] >= mesh.positions.size())
                throw InputError(where,
                                 fmt::format("triangle {} of mesh '{}' refers to vertex {}, but the mesh has "
                                             "{} vertices",
                                             t, mesh.name, tri[k], mesh.positions.size()));
    }
    checkAttributes(mesh, where);

    glm::dvec3 diagonal = glm::dvec3(mesh.bounds().diagonal());
    double minDoubleArea = 2.0 * kDegenerateAreaFactor * glm::dot(diagonal, diagonal);
    size_t total = mesh.triangles.size();
    std::erase_if(mesh.triangles, [&](glm::uvec3 t) {
        double doubleArea = glm::length(areaVector(mesh, t));
        return !(doubleArea > 0.0 && doubleArea >= minDoubleArea);
    });
    size_t dropped = total - mesh.triangles.size();
    if (mesh.triangles.empty())
        throw InputError(
            where, fmt::format("all {} triangles of mesh '{}' are degenerate (zero area)", total, mesh.name));
    removeUnreferencedVertices(mesh);

    if (mesh.normals.size() != mesh.positions.size()) {
        computeVertexNormals(mesh);
        orthonormalizeTangents(mesh);
        return dropped;
    }
    std::vector<glm::dvec3> sums;  // computed only when some normal needs replacing
    for (size_t i = 0; i < mesh.normals.size(); ++i) {
        glm::vec3 n = mesh.normals[i];
        float length = glm::length(n);
        if (std::isfinite(length) && length > kMinNormalLength) {
            mesh.normals[i] = n / length;
            continue;
        }
        if (sums.empty()) sums = areaWeightedNormalSums(mesh);
        mesh.normals[i] = unitOrFallback(sums[i]);
    }
    orthonormalizeTangents(mesh);
    return dropped;
}

}  // namespace deltagi
