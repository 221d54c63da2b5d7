#include "scene/shapes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "scene/mesh_io.h"

namespace deltagi {

namespace {

// Appends the rectangle centre + (±1)*halfU*u + (±1)*halfV*v with normal cross(u, v), wound counter-clockwise
// seen from the side the normal points to. Texture coordinates span [0, 1]^2 over it: texture u along v,
// texture v along u (a quad's image lies unmirrored seen from above, its top towards -z).
void addRectangle(TriangleMesh& mesh, glm::vec3 centre, glm::vec3 u, glm::vec3 v) {
    auto base = static_cast<unsigned>(mesh.positions.size());
    glm::vec3 normal = glm::normalize(glm::cross(u, v));
    for (glm::vec2 corner : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
        mesh.positions.push_back(centre + corner.x * u + corner.y * v);
        mesh.normals.push_back(normal);
        mesh.uvs.emplace_back(0.5f * (corner.y + 1.0f), 0.5f * (corner.x + 1.0f));
    }
    mesh.triangles.emplace_back(base, base + 1, base + 2);
    mesh.triangles.emplace_back(base, base + 2, base + 3);
}

// Triangles of a (rows+1) x (columns+1) vertex grid, row-major; cross(down a row, along a column) is outward.
// A collapsed first or last row has all its vertices at one point (a sphere's poles): its quads become one
// triangle instead of two, so that no degenerate triangle is made.
void addGridTriangles(TriangleMesh& mesh, int rows, int columns, bool collapsedFirstRow,
                      bool collapsedLastRow) {
    auto index = [columns](int row, int column) {
        return static_cast<unsigned>(row * (columns + 1) + column);
    };
    for (int row = 0; row < rows; ++row) {
        for (int column = 0; column < columns; ++column) {
            unsigned v00 = index(row, column), v01 = index(row, column + 1);
            unsigned v10 = index(row + 1, column), v11 = index(row + 1, column + 1);
            // In a collapsed first row v00 == v01; in a collapsed last row v10 == v11.
            if (!(row == rows - 1 && collapsedLastRow)) mesh.triangles.emplace_back(v00, v10, v11);
            if (!(row == 0 && collapsedFirstRow)) mesh.triangles.emplace_back(v00, v11, v01);
        }
    }
}

}  // namespace

TriangleMesh makeBox(glm::vec3 size) {
    TriangleMesh mesh;
    mesh.name = "box";
    glm::vec3 half = 0.5f * size;
    glm::vec3 x(half.x, 0, 0), y(0, half.y, 0), z(0, 0, half.z);
    // Each face: centre, then u and v with cross(u, v) pointing out of the box.
    addRectangle(mesh, x, y, z);
    addRectangle(mesh, -x, z, y);
    addRectangle(mesh, y, z, x);
    addRectangle(mesh, -y, x, z);
    addRectangle(mesh, z, x, y);
    addRectangle(mesh, -z, y, x);
    return mesh;
}

TriangleMesh makeSphere(float radius, int segments) {
    TriangleMesh mesh;
    mesh.name = "sphere";
    int stacks = std::max(2, segments / 2);
    // Rows go from the north pole (theta = 0) to the south pole; columns around +y (the last repeats the
    // first so that the seam has its own vertices).
    for (int row = 0; row <= stacks; ++row) {
        float theta = std::numbers::pi_v<float> * static_cast<float>(row) / static_cast<float>(stacks);
        for (int column = 0; column <= segments; ++column) {
            float phi =
                2.0f * std::numbers::pi_v<float> * static_cast<float>(column) / static_cast<float>(segments);
            glm::vec3 normal(std::sin(theta) * std::sin(phi), std::cos(theta),
                             std::sin(theta) * std::cos(phi));
            mesh.positions.push_back(radius * normal);
            mesh.normals.push_back(normal);
            // Longitude along u, the north pole at the image's top.
            mesh.uvs.emplace_back(static_cast<float>(column) / static_cast<float>(segments),
                                  static_cast<float>(row) / static_cast<float>(stacks));
        }
    }
    addGridTriangles(mesh, stacks, segments, true, true);
    return mesh;
}

TriangleMesh makeQuad(glm::vec2 size) {
    TriangleMesh mesh;
    mesh.name = "quad";
    addRectangle(mesh, glm::vec3(0.0f), glm::vec3(0, 0, 0.5f * size.y), glm::vec3(0.5f * size.x, 0, 0));
    return mesh;
}

TriangleMesh makeTorus(float majorRadius, float minorRadius, int segments) {
    TriangleMesh mesh;
    mesh.name = "torus";
    int tubeSegments = std::max(3, segments / 2);
    // Rows go around the tube (theta), columns around +y (phi); both wrap with a repeated seam.
    for (int row = 0; row <= tubeSegments; ++row) {
        float theta =
            2.0f * std::numbers::pi_v<float> * static_cast<float>(row) / static_cast<float>(tubeSegments);
        for (int column = 0; column <= segments; ++column) {
            float phi =
                2.0f * std::numbers::pi_v<float> * static_cast<float>(column) / static_cast<float>(segments);
            glm::vec3 radial(std::sin(phi), 0.0f, std::cos(phi));
            // theta turns from outside over the bottom, so that rows x columns wind outward.
            glm::vec3 normal = std::cos(theta) * radial - glm::vec3(0.0f, std::sin(theta), 0.0f);
            mesh.positions.push_back(majorRadius * radial + minorRadius * normal);
            mesh.normals.push_back(normal);
            mesh.uvs.emplace_back(static_cast<float>(column) / static_cast<float>(segments),
                                  static_cast<float>(row) / static_cast<float>(tubeSegments));
        }
    }
    addGridTriangles(mesh, tubeSegments, segments, false, false);
    return mesh;
}

TriangleMesh makeTriangles(std::span<const glm::vec3> positions, std::span<const glm::uvec3> triangles,
                           bool smooth) {
    TriangleMesh mesh;
    mesh.name = "triangles";
    if (smooth) {
        mesh.positions.assign(positions.begin(), positions.end());
        mesh.triangles.assign(triangles.begin(), triangles.end());
        computeVertexNormals(mesh);
        return mesh;
    }
    for (glm::uvec3 t : triangles) {
        glm::vec3 a = positions[t.x], b = positions[t.y], c = positions[t.z];
        glm::vec3 n = glm::cross(b - a, c - a);
        float length = glm::length(n);
        // A degenerate triangle gets a zero normal here; cleanMesh() drops it.
        n = std::isfinite(length) && length > 0.0f ? n / length : glm::vec3(0.0f);
        auto base = static_cast<unsigned>(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), {a, b, c});
        mesh.normals.insert(mesh.normals.end(), {n, n, n});
        mesh.triangles.emplace_back(base, base + 1, base + 2);
    }
    return mesh;
}

}  // namespace deltagi
