// Camera frames from a video file, a capture device or numbered images: the scene camera and the light
// camera of a live or recorded session (the paper's Fig. 2 inputs). Video files and V4L2 devices (/dev/video0)
// are read through FFmpeg's libavformat and libavdevice, with one code path; numbered images through
// readImage().
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "deltagi/image.h"

namespace deltagi {

struct CameraFrame {
    Image image;             // linear RGB (8-bit sources decoded from sRGB)
    double timeSeconds = 0;  // from the stream's timestamps (a pattern's: index / frame rate), increasing
    int64_t index = 0;       // 0, 1, 2, ... in the order read
};

class FrameSource {
  public:
    virtual ~FrameSource() = default;
    // The next frame; nothing at the end of a file or pattern. Throws InputError naming the source when a
    // frame cannot be read or changes size.
    virtual std::optional<CameraFrame> next() = 0;
    // What the source is, for messages: the path as given.
    virtual const std::string& name() const = 0;
    // The size of every frame.
    virtual int width() const = 0;
    virtual int height() const = 0;
    // Frames per second the source declares (0 when it declares none).
    virtual double frameRate() const = 0;
};

// Opens `source`: a path with a run of '#' (frame_####.png: the run is the frame number, zero-padded; the
// numbers start at 0 or 1 and end before the first missing one), a device under /dev (V4L2), or any video
// file FFmpeg reads. `patternFps` times a pattern's frames. Throws InputError naming the source when it
// cannot be opened or holds no video.
std::unique_ptr<FrameSource> openFrameSource(const std::string& source, double patternFps = 30.0);

}  // namespace deltagi
