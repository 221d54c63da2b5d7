// Writing meshes as PLY files (binary little-endian): positions, normals and 8-bit vertex colours, as scans
// come (the scene file reads them back through the mesh loader).
#pragma once

#include <span>
#include <string>

#include <glm/glm.hpp>

#include "deltagi/scene.h"

namespace deltagi {

// The bytes of a binary PLY file of `mesh`'s positions, normals and triangles, with `colors` (linear RGB in
// [0, 1], one per position) as uchar red green blue, sRGB-encoded (the convention of scans). `comment` goes
// into the header (one line, no line breaks).
std::string encodePly(const TriangleMesh& mesh, std::span<const glm::vec3> colors,
                      const std::string& comment);

}  // namespace deltagi
