// TriangleMesh helpers shared by the mesh loaders and the procedural shapes (declared in mesh_io.h).
#include <cmath>
#include <cstdint>
#include <vector>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/scene.h"
#include "mesh_io.h"

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

// Removes the vertices no triangle refers to, keeping the order of the others.
void removeUnreferencedVertices(TriangleMesh& mesh) {
    constexpr uint32_t kUnused = UINT32_MAX;
    std::vector<uint32_t> newIndex(mesh.positions.size(), kUnused);
    for (glm::uvec3 t : mesh.triangles) newIndex[t.x] = newIndex[t.y] = newIndex[t.z] = 0;
    uint32_t next = 0;
    bool hasNormals = mesh.normals.size() == mesh.positions.size();
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        if (newIndex[i] == kUnused) continue;
        newIndex[i] = next;
        mesh.positions[next] = mesh.positions[i];
        if (hasNormals) mesh.normals[next] = mesh.normals[i];
        ++next;
    }
    mesh.positions.resize(next);
    if (hasNormals) mesh.normals.resize(next);
    for (glm::uvec3& t : mesh.triangles) t = {newIndex[t.x], newIndex[t.y], newIndex[t.z]};
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
    for (glm::vec3& p : mesh.positions) p = glm::vec3(worldFromObject * glm::vec4(p, 1.0f));
    for (glm::vec3& n : mesh.normals) {
        // A normal that cannot be transformed is zeroed here and recomputed from the faces by cleanMesh().
        glm::vec3 m = normalMatrix * n;
        float length = glm::length(m);
        n = std::isfinite(length) && length > 0.0f ? m / length : glm::vec3(0.0f);
    }
    if (glm::determinant(linear) < 0.0f)
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
    return dropped;
}

}  // namespace deltagi
