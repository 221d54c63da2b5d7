// libFuzzer target: camera frames (`deltagi live`, `deltagi track`): the input is a file that the frame
// source opens as a video (libavformat picks the demuxer from its bytes; the first byte picks the extension,
// which FFmpeg takes as a hint), whose first frames are decoded and searched for markers. Bad input must end
// in InputError or no frame; anything else (a crash, a sanitizer finding, another exception, a hang) is a
// finding. scripts/fuzz.sh seeds it with short videos that the project writes itself (`deltagi encode`).
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "deltagi/error.h"
#include "live/frame_source.h"
#include "live/marker_registration.h"

namespace {
constexpr std::array<const char*, 4> kExtensions = {".mp4", ".mkv", ".avi", ".y4m"};
constexpr int kMaxFrames = 4;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size < 1) return 0;
    static const std::filesystem::path kFolder = [] {
        std::filesystem::path folder =
            std::filesystem::temp_directory_path() / ("deltagi-fuzz-frames-" + std::to_string(::getpid()));
        std::filesystem::create_directories(folder);
        return folder;
    }();
    static const std::vector<deltagi::Marker> markers = [] {
        deltagi::Marker m;
        m.id = 3;
        m.size = 0.1f;
        return std::vector<deltagi::Marker>{m};
    }();
    static const deltagi::MarkerDetector detector(markers);
    const std::filesystem::path file =
        kFolder / (std::string("frames") + kExtensions[data[0] % kExtensions.size()]);
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
    }
    try {
        std::unique_ptr<deltagi::FrameSource> source = deltagi::openFrameSource(file.string());
        for (int i = 0; i < kMaxFrames; ++i) {
            std::optional<deltagi::CameraFrame> frame = source->next();
            if (!frame) break;
            detector.detect(frame->image);
        }
    } catch (const deltagi::InputError&) {
        // the expected outcome of bad input
    }
    return 0;
}
