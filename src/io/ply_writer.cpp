#include "io/ply_writer.h"

#include <bit>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include <fmt/core.h>

#include "deltagi/image.h"

namespace deltagi {

namespace {

static_assert(std::endian::native == std::endian::little,
              "the PLY writer writes the machine's floats as they are");

template <typename T>
void append(std::string& out, T value) {
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out.append(bytes, sizeof(T));
}

}  // namespace

std::string encodePly(const TriangleMesh& mesh, std::span<const glm::vec3> colors,
                      const std::string& comment) {
    if (colors.size() != mesh.positions.size() || mesh.normals.size() != mesh.positions.size())
        throw std::invalid_argument("encodePly: one colour and one normal per position expected");
    // The sRGB encoding of the image writer, so that a PNG and a PLY of the same colour agree.
    Image pixels(static_cast<int>(colors.size()), 1, 3);
    for (size_t v = 0; v < colors.size(); ++v) pixels.setRgb(static_cast<int>(v), 0, colors[v]);
    const std::vector<uint8_t> srgb = colors.empty() ? std::vector<uint8_t>{} : encodeSrgb8(pixels);

    std::string out = fmt::format(
        "ply\nformat binary_little_endian 1.0\ncomment {}\nelement vertex {}\nproperty float x\n"
        "property float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face {}\n"
        "property list uchar uint vertex_indices\nend_header\n",
        comment, mesh.positions.size(), mesh.triangles.size());
    out.reserve(out.size() + mesh.positions.size() * 27 + mesh.triangles.size() * 13);
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        for (int c = 0; c < 3; ++c) append(out, mesh.positions[v][c]);
        for (int c = 0; c < 3; ++c) append(out, mesh.normals[v][c]);
        for (int c = 0; c < 3; ++c) append(out, srgb[3 * v + c]);
    }
    for (const glm::uvec3& t : mesh.triangles) {
        append(out, uint8_t{3});
        for (int k = 0; k < 3; ++k) append(out, static_cast<uint32_t>(t[k]));
    }
    return out;
}

}  // namespace deltagi
