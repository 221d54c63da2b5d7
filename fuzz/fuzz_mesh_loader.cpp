// libFuzzer target: mesh loading (loadMeshFile, then cleanMesh as the scene reader does). The first byte
// picks the file's format (its extension: Assimp chooses the importer by it); the rest is the file. Bad input
// must end in InputError; anything else (a crash, a sanitizer finding, another exception) is a finding.
// scripts/fuzz.sh seeds it with mesh files prefixed by their format's byte.
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "deltagi/error.h"
#include "scene/mesh_io.h"

namespace {
// Index = the first byte modulo the size; scripts/fuzz.sh uses the same order.
constexpr std::array<const char*, 6> kExtensions = {".obj", ".ply", ".off", ".gltf", ".glb", ".stl"};
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static const std::filesystem::path kFolder = [] {
        std::filesystem::path folder =
            std::filesystem::temp_directory_path() / ("deltagi-fuzz-mesh-" + std::to_string(::getpid()));
        std::filesystem::create_directories(folder);
        return folder;
    }();
    const std::filesystem::path file =
        kFolder / (std::string("mesh") + kExtensions[data[0] % kExtensions.size()]);
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    }
    try {
        for (deltagi::FileMesh& mesh : deltagi::loadMeshFile(file, "fuzz", "mesh"))
            deltagi::cleanMesh(mesh.mesh, "fuzz");
    } catch (const deltagi::InputError&) {
        // the expected outcome of bad input
    }
    return 0;
}
