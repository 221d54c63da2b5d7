#include "io/image_input.h"

#include <algorithm>
#include <cstring>
#include <fstream>

#include <fmt/format.h>

#include "io/file_names.h"

namespace deltagi {

namespace {

constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

uint32_t bigEndian32(const std::byte* p) {
    return (static_cast<uint32_t>(p[0]) << 24) | (static_cast<uint32_t>(p[1]) << 16) |
           (static_cast<uint32_t>(p[2]) << 8) | static_cast<uint32_t>(p[3]);
}

// Walks a PNG's chunk headers (the signature checked by the caller), `size` the file's bytes: each chunk's
// length and type from readHeader(at, header) (false: no more to read), its data and CRC skipped.
template <typename ReadHeader>
std::optional<std::string> walkPngChunks(uint64_t size, ReadHeader readHeader) {
    uint64_t at = 8;
    std::byte chunk[8];
    while (at + 8 <= size && readHeader(at, chunk)) {
        const uint64_t length = bigEndian32(chunk);
        const std::string type(reinterpret_cast<const char*>(chunk + 4), 4);
        const uint64_t left = size - at - 8;
        if (length + 4 > left)
            return fmt::format(
                "it is truncated or corrupt: its '{}' chunk claims {} bytes, but {} are left in the "
                "file",
                type, length, left >= 4 ? left - 4 : 0);
        if (type == "IEND") break;
        at += 8 + length + 4;
    }
    return std::nullopt;
}

std::optional<std::string> pngFileChunkError(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) return std::nullopt;  // OpenImageIO says why
    const uint64_t size = static_cast<uint64_t>(in.tellg());
    std::byte signature[8];
    in.seekg(0);
    if (!in.read(reinterpret_cast<char*>(signature), 8) || std::memcmp(signature, kPngSignature, 8) != 0)
        return std::nullopt;
    return walkPngChunks(size, [&](uint64_t at, std::byte* header) {
        in.seekg(static_cast<std::streamoff>(at));
        return static_cast<bool>(in.read(reinterpret_cast<char*>(header), 8));
    });
}

}  // namespace

std::optional<std::string> pngChunkError(std::span<const std::byte> bytes, uint64_t fileSize) {
    if (bytes.size() < 8 || std::memcmp(bytes.data(), kPngSignature, 8) != 0) return std::nullopt;
    return walkPngChunks(fileSize, [&](uint64_t at, std::byte* header) {
        if (at + 8 > bytes.size()) return false;
        std::memcpy(header, bytes.data() + at, 8);
        return true;
    });
}

std::unique_ptr<OIIO::ImageInput> openImageInput(const std::string& path, const OIIO::ImageSpec* config,
                                                 std::string& error) {
    if (lowerExtension(path) == ".png")
        if (std::optional<std::string> chunks = pngFileChunkError(path)) {
            error = *chunks;
            return nullptr;
        }
    auto input = OIIO::ImageInput::create(path, /*do_open=*/false);
    if (!input) {  // no reader for the extension: every reader tries
        OIIO::geterror();
        input = OIIO::ImageInput::open(path, config);
        if (!input) error = OIIO::geterror();
        return input;
    }
    OIIO::ImageSpec spec;
    const bool opened = config ? input->open(path, spec, *config) : input->open(path, spec);
    if (!opened) {
        error = input->geterror();
        if (error.empty()) error = OIIO::geterror();
        return nullptr;
    }
    return input;
}

}  // namespace deltagi
