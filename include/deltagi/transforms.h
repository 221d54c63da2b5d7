// The transforms an application changes from frame to frame: the virtual objects' (worldFromObject) and the
// camera's pose (worldFromCamera). Each is checked here, in one place, for the scene reader and for code that
// sets them directly; a bad one raises InputError, as a bad scene file does.
#pragma once

#include <glm/glm.hpp>

#include "deltagi/export.h"
#include "deltagi/scene.h"

DELTAGI_API_BEGIN
namespace deltagi {

// Throws InputError("transform", ...) unless `worldFromObject` is finite, affine (last row [0, 0, 0, 1]) and
// invertible.
void checkTransform(const glm::mat4& worldFromObject);

// Throws InputError("world_from_camera", ...) unless `worldFromCamera` is finite, affine, and its 3x3 part a
// rotation (orthonormal, right-handed): the pose of a camera, without scale or shear.
void checkCameraPose(const glm::mat4& worldFromCamera);

// The pose of a camera at `position` looking at `lookAt`, `up` giving the image's up direction (the scene
// file's camera "position", "look_at", "up"). OpenGL camera frame: the camera looks down -z with +y up.
// Throws InputError("look_at" or "up", ...) when there is no view direction or `up` is parallel to it.
glm::mat4 lookAtPose(glm::vec3 position, glm::vec3 lookAt, glm::vec3 up = {0.0f, 1.0f, 0.0f});

// The camera turned by `degrees` about the vertical axis through `centre`: a camera walking round the objects
// (`deltagi bench --camera-motion`, `deltagi stability --camera-step`).
Camera turnedCamera(const Camera& camera, glm::vec3 centre, float degrees);

// Places `mesh` in the world by `worldFromObject`: its object-space mesh transformed (normals by the inverse
// transpose) and cleaned up as the scene reader does (degenerate triangles dropped, normals repaired), so
// that an object moved to the scene file's transform is the loaded one bit for bit. The object-space mesh is
// mesh.objectSpace; a mesh without one (built in code) is taken as it is, and keeps itself as its
// object-space mesh for the next call. Its name and material are kept. Throws InputError naming the mesh for
// a bad transform (checkTransform) or a mesh the reader would refuse (no triangles, non-finite vertices).
void setTransform(TriangleMesh& mesh, const glm::mat4& worldFromObject);
// setTransform's mesh, made without copying `mesh` itself when it has its object-space mesh (a 100k-triangle
// statue's arrays are megabytes): `mesh` is left as it was.
TriangleMesh placedMesh(const TriangleMesh& mesh, const glm::mat4& worldFromObject);

}  // namespace deltagi
DELTAGI_API_END
