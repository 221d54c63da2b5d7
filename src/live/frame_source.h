// Camera frames from a video file, a capture device or numbered images: the scene camera and the light
// camera of a live or recorded session (the paper's Fig. 2 inputs). Video files and V4L2 devices
// (/dev/video0) are read through FFmpeg's libavformat and libavdevice (loaded at the first device), with one
// code path; numbered images through readImage().
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

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

// Frames as a live system receives them, read on a thread of their own. A device gives frames at its own
// pace; with `realtime`, a file's or pattern's frames come at the pace of their timestamps as well (a
// recorded camera replayed live), otherwise each waits until it is taken (every frame is used, none dropped).
// take() gives the newest frame that arrived; the frames that arrived and were never taken are counted as
// dropped.
class FrameFeed {
  public:
    using Clock = std::chrono::steady_clock;
    FrameFeed(std::unique_ptr<FrameSource> source, bool realtime);
    ~FrameFeed();  // stops the reading thread
    FrameFeed(const FrameFeed&) = delete;
    FrameFeed& operator=(const FrameFeed&) = delete;

    struct Arrival {
        CameraFrame frame;
        Clock::time_point arrived;  // when it was read from the source (not in real time: when taken)
        int dropped = 0;            // frames that arrived since the last take() and were not taken
    };
    // Waits for a frame; nothing once the source has ended and every frame is taken. Rethrows the source's
    // error (InputError naming it) once its frames before the error are taken.
    std::optional<Arrival> take();
    // The newest frame if one arrived since the last take(), without waiting; nothing otherwise.
    std::optional<Arrival> poll();
    // As take(), waiting at most until `deadline`: nothing when no frame came by then or the source has
    // ended (ended() tells which).
    std::optional<Arrival> takeUntil(Clock::time_point deadline);
    // The source has ended (or failed, which take() rethrows) and every frame was taken.
    bool ended() const;
    const FrameSource& source() const { return *source_; }
    int droppedTotal() const;

  private:
    void read();
    std::optional<Arrival> takeLocked(std::unique_lock<std::mutex>& lock);

    std::unique_ptr<FrameSource> source_;
    bool realtime_;  // frames come at their own pace, the newest wins (else each waits to be taken)
    bool paced_;     // ... at their timestamps' pace, read from a file (a device paces itself)
    mutable std::mutex mutex_;
    std::condition_variable changed_;
    std::optional<Arrival> newest_;
    int droppedSinceTake_ = 0, droppedTotal_ = 0;
    bool ended_ = false, stopping_ = false;
    std::exception_ptr error_;
    std::thread reader_;
};

}  // namespace deltagi
