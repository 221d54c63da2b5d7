// Procedural meshes, in object space, counter-clockwise (outward) winding, with unit vertex normals and
// texture coordinates (each face of a box and a quad span [0, 1]^2; spheres and tori wrap once around): the
// scene file's "shape" entries, and the parts of a scene built in code (place them with setTransform(),
// deltagi/transforms.h). The scene reader checks their parameters; these functions expect valid ones
// (positive sizes, enough segments, indices in range).
#pragma once

#include <span>

#include <glm/glm.hpp>

#include "deltagi/export.h"
#include "deltagi/scene.h"

DELTAGI_API_BEGIN
namespace deltagi {

// An axis-aligned box of edge lengths `size`, centred at the origin: 24 vertices (flat face normals), 12
// triangles.
TriangleMesh makeBox(glm::vec3 size);

// A UV sphere of `radius` at the origin: `segments` slices around +y and segments/2 (at least 2) stacks.
// Normals are the exact sphere normals.
TriangleMesh makeSphere(float radius, int segments);

// A rectangle in the XZ plane, centred at the origin, `size.x` along x and `size.y` along z, normal +y.
TriangleMesh makeQuad(glm::vec2 size);

// A torus around the y axis: the tube's centre line is the circle of `majorRadius` in the XZ plane;
// `segments` slices around y, segments/2 (at least 3) around the tube.
TriangleMesh makeTorus(float majorRadius, float minorRadius, int segments);

// A triangle soup from explicit positions and indices (in range). Flat: each triangle gets its own three
// vertices with its face normal. Smooth: vertices are shared, normals are area-weighted averages.
TriangleMesh makeTriangles(std::span<const glm::vec3> positions, std::span<const glm::uvec3> triangles,
                           bool smooth);

}  // namespace deltagi
DELTAGI_API_END
