// Video output through the FFmpeg libraries: H.264 in an MP4 (libavcodec with libx264, libavformat,
// libswscale), or uncompressed 4:2:0 frames in a YUV4MPEG2 file (.y4m: what Chromium's fake camera,
// --use-file-for-fake-video-capture, and most video tools read). Written atomically as every output is
// (io/atomic_file.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "deltagi/image.h"
#include "io/atomic_file.h"

namespace deltagi::cli {

struct VideoSettings {
    double fps = 30.0;  // frames per second, (0, 1000]
    int crf = 18;       // x264's constant rate factor, 0 (lossless) to 51; 18: visually lossless for most
};
inline constexpr int kMaxCrf = 51;

// Whether `path` names a Y4M (.y4m, any case) rather than an MP4.
bool isY4m(const std::filesystem::path& path);

// Throws InputError naming `option` when `path` is not a .mp4 or .y4m file name.
void checkVideoPath(const std::filesystem::path& path, const std::string& option);

// Throws InputError naming `option` when `path` is an MP4 and this FFmpeg has no H.264 encoder (libx264, or
// another H.264 encoder when libx264 is missing).
void checkVideoEncoder(const std::filesystem::path& path, const std::string& option);

// Frames go in one by one as 8-bit sRGB (the pixels a PNG of the frame holds; a linear image is encoded as
// the PNG writer does: clamped to [0, 1], sRGB transfer function); they are converted to YUV 4:2:0 (limited
// range, BT.709 for an MP4, BT.601 for a Y4M; an odd width or height is padded by repeating the last column
// or row) and, for an MP4, encoded with libx264 at `settings.crf` (preset medium, no macroblock-tree rate
// control, one thread, bit-exact: the same frames give the same file, byte for byte). The file is written to
// a temporary beside `destination` and renamed into place by commit(); a failure or an interruption before
// then leaves the previous file, if any, as it was.
class VideoWriter {
  public:
    VideoWriter(const std::filesystem::path& destination, int width, int height, VideoSettings settings);
    ~VideoWriter();
    VideoWriter(const VideoWriter&) = delete;
    VideoWriter& operator=(const VideoWriter&) = delete;

    // A linear RGB image of the video's size (encoded to sRGB 8-bit as PNGs are).
    void add(const Image& linear);
    // 8-bit sRGB RGB pixels, rows top first, width * height * 3 bytes.
    void addSrgb8(std::span<const uint8_t> rgb);
    // Flushes the encoder, finishes the file and renames it into place. Throws InputError.
    void commit();

    int frames() const { return frames_; }

  private:
    struct FFmpeg;
    void writePackets();
    [[noreturn]] void fail(const std::string& what, int error) const;

    AtomicFile file_;
    int width_, height_;
    std::unique_ptr<FFmpeg> ff_;
    int frames_ = 0;
};

}  // namespace deltagi::cli
