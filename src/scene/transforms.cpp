#include "deltagi/transforms.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/error.h"
#include "scene/mesh_io.h"

namespace deltagi {

namespace {

constexpr float kAffineTolerance = 1e-6f;       // last row of 4x4 matrices: [0, 0, 0, 1]
constexpr float kOrthonormalTolerance = 1e-3f;  // world_from_camera rotation: max |R^T R - I|
constexpr float kParallelTolerance = 1e-6f;     // camera up vs view direction: |cross| of unit vectors

void checkFiniteAffine(const glm::mat4& m, const char* where) {
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r]))
                throw InputError(where, fmt::format("expected finite numbers, got {} in row {}, column {}",
                                                    m[c][r], r, c));
    glm::vec4 lastRow(m[0][3], m[1][3], m[2][3], m[3][3]);
    if (glm::length(lastRow - glm::vec4(0, 0, 0, 1)) > kAffineTolerance)
        throw InputError(where, fmt::format("expected the last row to be [0, 0, 0, 1], got [{}, {}, {}, {}]",
                                            lastRow.x, lastRow.y, lastRow.z, lastRow.w));
}

}  // namespace

void checkTransform(const glm::mat4& worldFromObject) {
    checkFiniteAffine(worldFromObject, "transform");
    float det = glm::determinant(glm::mat3(worldFromObject));
    if (det == 0.0f || !std::isfinite(det))
        throw InputError("transform", "expected an invertible matrix, got a singular one");
}

void checkCameraPose(const glm::mat4& worldFromCamera) {
    checkFiniteAffine(worldFromCamera, "world_from_camera");
    glm::mat3 rotation(worldFromCamera);
    glm::mat3 error = glm::transpose(rotation) * rotation - glm::mat3(1.0f);
    float maxError = 0.0f;
    for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) maxError = std::max(maxError, std::abs(error[c][r]));
    if (maxError > kOrthonormalTolerance)
        throw InputError("world_from_camera",
                         fmt::format("expected an orthonormal rotation part (no scale or shear), but "
                                     "|R^T R - I| reaches {:.3g}",
                                     maxError));
    if (glm::determinant(rotation) < 0.0f)
        throw InputError(
            "world_from_camera",
            "expected a rotation, got a reflection (determinant -1): the camera frame must be right-handed");
}

glm::mat4 lookAtPose(glm::vec3 position, glm::vec3 lookAt, glm::vec3 up) {
    glm::vec3 forward = lookAt - position;
    if (!(glm::length(forward) > kParallelTolerance * std::max(1.0f, glm::length(position))))
        throw InputError(
            "look_at", "expected a point different from camera.position (the camera needs a view direction)");
    forward = glm::normalize(forward);
    if (!(glm::length(up) > 0.0f)) throw InputError("up", "expected a non-zero vector");
    glm::vec3 right = glm::cross(forward, glm::normalize(up));
    if (!(glm::length(right) >= kParallelTolerance))
        throw InputError("up",
                         "expected a direction not parallel to the view direction (look_at - position)");
    right = glm::normalize(right);
    glm::vec3 trueUp = glm::cross(right, forward);
    glm::mat4 worldFromCamera(1.0f);
    worldFromCamera[0] = glm::vec4(right, 0.0f);
    worldFromCamera[1] = glm::vec4(trueUp, 0.0f);
    worldFromCamera[2] = glm::vec4(-forward, 0.0f);
    worldFromCamera[3] = glm::vec4(position, 1.0f);
    return worldFromCamera;
}

void setTransform(TriangleMesh& mesh, const glm::mat4& worldFromObject) {
    mesh = placedMesh(mesh, worldFromObject);
}

TriangleMesh placedMesh(const TriangleMesh& mesh, const glm::mat4& worldFromObject) {
    const std::string where = "mesh '" + mesh.name + "'";
    try {
        checkTransform(worldFromObject);
    } catch (const InputError& e) {
        throw InputError(where + ": " + e.where(), e.message());
    }
    std::shared_ptr<const TriangleMesh> objectSpace = mesh.objectSpace;
    if (!objectSpace) {
        TriangleMesh asGiven = mesh;
        asGiven.worldFromObject = glm::mat4(1.0f);
        objectSpace = std::make_shared<const TriangleMesh>(std::move(asGiven));
    }
    TriangleMesh placed;
    placed.positions = objectSpace->positions;
    placed.normals = objectSpace->normals;
    placed.triangles = objectSpace->triangles;
    placed.uvs = objectSpace->uvs;
    placed.uvs1 = objectSpace->uvs1;
    placed.tangents = objectSpace->tangents;
    placed.colors = objectSpace->colors;
    placed.name = mesh.name;
    placed.material = mesh.material;
    // The scene reader's order: transform, then clean up (scene_io.cpp, readMeshEntry).
    transformMesh(placed, worldFromObject);
    cleanMesh(placed, where);
    placed.objectSpace = std::move(objectSpace);
    placed.worldFromObject = worldFromObject;
    return placed;
}

Camera turnedCamera(const Camera& camera, glm::vec3 centre, float degrees) {
    const glm::mat4 turn = glm::translate(glm::mat4(1.0f), centre) *
                           glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::vec3(0.0f, 1.0f, 0.0f)) *
                           glm::translate(glm::mat4(1.0f), -centre);
    Camera turned = camera;
    turned.worldFromCamera = turn * camera.worldFromCamera;
    return turned;
}

}  // namespace deltagi
