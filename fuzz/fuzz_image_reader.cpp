// libFuzzer target: image files as the scene's photo, environment maps, textures' neighbours and `compare`
// read them (readImage, imageFileSize; io/image_io.cpp). The first byte picks the extension (0 .png, 1 .jpg,
// 2 .exr, 3 .hdr), the rest is the file. Every input must be read or refused with InputError; a crash,
// another exception or a sanitizer finding is a finding. Headers that declare more than 4,096 x 4,096 pixels
// are checked by imageFileSize alone: readImage would decode up to half the machine's memory, more than the
// fuzzer's 4 GB (the guard itself is tested by tests/bad-inputs/env-header-100000).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "deltagi/error.h"
#include "deltagi/image.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static const char* kExtensions[] = {".png", ".jpg", ".exr", ".hdr"};
    const std::filesystem::path file =
        std::filesystem::temp_directory_path() /
        ("deltagi-fuzz-image-" + std::to_string(::getpid()) + kExtensions[data[0] % 4]);
    std::ofstream(file, std::ios::binary)
        .write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    const auto declared = deltagi::imageFileSize(file);
    if (!declared || static_cast<double>(declared->first) * declared->second <= 4096.0 * 4096.0) {
        try {
            (void)deltagi::readImage(file);
        } catch (const deltagi::InputError&) {
        }
    }
    std::filesystem::remove(file);
    return 0;
}
