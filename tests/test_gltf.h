// Small glTF 2.0 files written by tests: one unit quad in the z = 0 plane facing +z, with two texture
// coordinate sets and vertex colours, and whatever materials, textures, images and samplers the test gives.
#pragma once

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace deltagi::test {

// The quad's corners (x, y) = (0, 0), (1, 0), (1, 1), (0, 1) and their glTF texture coordinates: the image's
// top-left corner (uv (0, 0)) at the quad's top-left corner (0, 1, 0), u along +x, v along -y.
inline const glm::vec3 kQuadPositions[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
inline const glm::vec2 kQuadUvs[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
inline const glm::vec2 kQuadUvs1[4] = {{0, 2}, {2, 2}, {2, 0}, {0, 0}};
inline const glm::vec3 kQuadColour{0.5f, 0.25f, 1.0f};  // COLOR_0 of every vertex (linear)

// Writes `name`.gltf and `name`.bin into `folder`. `document` holds the keys to add (materials, textures,
// images, samplers); the primitive uses material 0 when there are materials.
inline std::filesystem::path writeQuadGltf(const std::filesystem::path& folder, const std::string& name,
                                           nlohmann::json document = nlohmann::json::object()) {
    std::vector<char> bin;
    auto append = [&](const void* data, size_t bytes) {
        const size_t at = bin.size();
        bin.resize(at + bytes);
        std::memcpy(bin.data() + at, data, bytes);
        return at;
    };
    const size_t positions = append(kQuadPositions, sizeof(kQuadPositions));
    const size_t uvs = append(kQuadUvs, sizeof(kQuadUvs));
    const size_t uvs1 = append(kQuadUvs1, sizeof(kQuadUvs1));
    const glm::vec3 colours[4] = {kQuadColour, kQuadColour, kQuadColour, kQuadColour};
    const size_t colourAt = append(colours, sizeof(colours));
    const uint16_t indices[6] = {0, 1, 2, 0, 2, 3};
    const size_t indexAt = append(indices, sizeof(indices));
    bin.resize((bin.size() + 3) / 4 * 4);

    using nlohmann::json;
    auto view = [](size_t offset, size_t bytes) {
        return json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
    };
    document["asset"] = {{"version", "2.0"}};
    document["scene"] = 0;
    document["scenes"] = json::array({{{"nodes", {0}}}});
    document["nodes"] = json::array({{{"mesh", 0}}});
    json primitive = {{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}, {"TEXCOORD_1", 2}, {"COLOR_0", 3}}},
                      {"indices", 4}};
    if (document.contains("materials")) primitive["material"] = 0;
    document["meshes"] = json::array({{{"primitives", {primitive}}}});
    document["buffers"] = json::array({{{"uri", name + ".bin"}, {"byteLength", bin.size()}}});
    document["bufferViews"] = {view(positions, sizeof(kQuadPositions)), view(uvs, sizeof(kQuadUvs)),
                               view(uvs1, sizeof(kQuadUvs1)), view(colourAt, sizeof(colours)),
                               view(indexAt, sizeof(indices))};
    document["accessors"] = {{{"bufferView", 0},
                              {"componentType", 5126},
                              {"count", 4},
                              {"type", "VEC3"},
                              {"min", {0, 0, 0}},
                              {"max", {1, 1, 0}}},
                             {{"bufferView", 1}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
                             {{"bufferView", 2}, {"componentType", 5126}, {"count", 4}, {"type", "VEC2"}},
                             {{"bufferView", 3}, {"componentType", 5126}, {"count", 4}, {"type", "VEC3"}},
                             {{"bufferView", 4}, {"componentType", 5123}, {"count", 6}, {"type", "SCALAR"}}};
    std::ofstream(folder / (name + ".bin"), std::ios::binary)
        .write(bin.data(), static_cast<std::streamsize>(bin.size()));
    const std::filesystem::path file = folder / (name + ".gltf");
    std::ofstream(file) << document.dump(2);
    return file;
}

}  // namespace deltagi::test
