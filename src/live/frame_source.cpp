#include "live/frame_source.h"

#include <filesystem>
#include <mutex>

#include <dlfcn.h>

#include <fmt/format.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavdevice/version.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/log.h>
#include <libswscale/swscale.h>
}

#include "deltagi/error.h"
#include "io/image_encode.h"

namespace fs = std::filesystem;

namespace deltagi {

namespace {

// Frames up to 8K (7680 x 4320) and a little more; larger ones are refused before a pixel is decoded (each
// frame is held as linear floats: 12 bytes a pixel).
constexpr int kMaxFrameSide = 8192;
constexpr int64_t kMaxFramePixels = 8192LL * 4608;

// A capture device (V4L2): it gives frames at its own pace.
bool isDevice(const std::string& source) {
    return source.starts_with("/dev/");
}

std::string avError(int error) {
    char text[AV_ERROR_MAX_STRING_SIZE] = {};
    av_strerror(error, text, sizeof text);
    return text;
}

// ---- numbered images ------------------------------------------------------------------------------------

class PatternSource final : public FrameSource {
  public:
    PatternSource(std::string pattern, double fps) : pattern_(std::move(pattern)), fps_(fps) {
        if (!(fps_ > 0.0)) throw InputError(pattern_, "the frame rate must be > 0");
        const size_t first = pattern_.find('#');
        size_t last = first;
        while (last < pattern_.size() && pattern_[last] == '#') ++last;
        prefix_ = pattern_.substr(0, first);
        suffix_ = pattern_.substr(last);
        digits_ = static_cast<int>(last - first);
        if (suffix_.find('#') != std::string::npos)
            throw InputError(pattern_, "expected one run of '#' (the frame number), got several");
        next_ = fs::exists(path(0)) ? 0 : 1;
        if (!fs::exists(path(next_)))
            throw InputError(pattern_, fmt::format("no frame: neither '{}' nor '{}' exists", path(0).string(),
                                                   path(1).string()));
        const std::optional<std::pair<int, int>> size = imageFileSize(path(next_));
        if (!size) {
            (void)readImage(path(next_));  // says why
            throw InputError(path(next_).string(), "cannot read the image's size");
        }
        width_ = size->first;
        height_ = size->second;
        if (width_ > kMaxFrameSide || height_ > kMaxFrameSide ||
            static_cast<int64_t>(width_) * height_ > kMaxFramePixels)
            throw InputError(path(next_).string(),
                             fmt::format("a frame of {}x{}: expected at most {} pixels a side and {} in all",
                                         width_, height_, kMaxFrameSide, kMaxFramePixels));
    }

    std::optional<CameraFrame> next() override {
        const fs::path file = path(next_);
        if (!fs::exists(file)) return std::nullopt;
        CameraFrame frame;
        frame.image = readImage(file);
        if (frame.image.width() != width_ || frame.image.height() != height_)
            throw InputError(file.string(),
                             fmt::format("the frames changed size: {}x{}, the first was {}x{}",
                                         frame.image.width(), frame.image.height(), width_, height_));
        frame.index = read_++;
        frame.timeSeconds = static_cast<double>(frame.index) / fps_;
        ++next_;
        return frame;
    }
    const std::string& name() const override { return pattern_; }
    int width() const override { return width_; }
    int height() const override { return height_; }
    double frameRate() const override { return fps_; }

  private:
    fs::path path(int64_t index) const { return prefix_ + fmt::format("{:0{}d}", index, digits_) + suffix_; }
    std::string pattern_, prefix_, suffix_;
    int digits_ = 0;
    double fps_;
    int64_t next_ = 0, read_ = 0;
    int width_ = 0, height_ = 0;
};

// ---- FFmpeg ---------------------------------------------------------------------------------------------

// libavdevice, FFmpeg's cameras (V4L2), is loaded when a device is first opened, not linked: with its own
// dependencies (SDL, PulseAudio, X11, ...) it would add some 80 shared libraries to every deltagi process's
// start, about 80 ms. Registering its inputs makes av_find_input_format() find them.
std::string devicesLibrary() {
    return fmt::format("libavdevice.so.{}", LIBAVDEVICE_VERSION_MAJOR);
}

void registerDevices() {
    static std::once_flag once;
    std::call_once(once, [] {
        void* library = dlopen(devicesLibrary().c_str(), RTLD_NOW | RTLD_GLOBAL);
        if (!library) return;  // av_find_input_format() finds no V4L2 input, and the caller says so
        if (auto registerAll = reinterpret_cast<void (*)()>(dlsym(library, "avdevice_register_all")))
            registerAll();
    });
}

class VideoSource final : public FrameSource {
  public:
    explicit VideoSource(std::string source) : name_(std::move(source)) {
        static std::once_flag once;
        std::call_once(once, [] {
            av_log_set_level(AV_LOG_QUIET);  // its errors come back as codes, which the messages name
        });
        const bool device = isDevice(name_);
        if (device) registerDevices();
        const AVInputFormat* format = device ? av_find_input_format("video4linux2") : nullptr;
        if (device && !format) fail("this FFmpeg has no V4L2 input (" + devicesLibrary() + ")");
        if (!device) {
            std::error_code ec;
            if (!fs::exists(name_, ec)) fail("file not found");
            if (!fs::is_regular_file(name_, ec)) fail("expected a video file");
        }
        if (int e = avformat_open_input(&input_, name_.c_str(), format, nullptr); e < 0)
            fail("cannot open: " + avError(e));
        if (int e = avformat_find_stream_info(input_, nullptr); e < 0) fail("cannot read: " + avError(e));
        const AVCodec* codec = nullptr;
        stream_ = av_find_best_stream(input_, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
        if (stream_ < 0 || !codec) fail("holds no video stream this FFmpeg decodes");
        const AVStream* stream = input_->streams[stream_];
        decoder_ = avcodec_alloc_context3(codec);
        if (!decoder_) fail("out of memory");
        if (avcodec_parameters_to_context(decoder_, stream->codecpar) < 0)
            fail("cannot read its video stream");
        decoder_->thread_count = 1;
        if (int e = avcodec_open2(decoder_, codec, nullptr); e < 0) fail("cannot decode: " + avError(e));
        width_ = decoder_->width;
        height_ = decoder_->height;
        if (width_ < 1 || height_ < 1 || width_ > kMaxFrameSide || height_ > kMaxFrameSide ||
            static_cast<int64_t>(width_) * height_ > kMaxFramePixels)
            fail(fmt::format("frames of {}x{}: expected 1 to {} pixels a side and at most {} in all", width_,
                             height_, kMaxFrameSide, kMaxFramePixels));
        timeBase_ = av_q2d(stream->time_base);
        const AVRational rate =
            stream->avg_frame_rate.num > 0 ? stream->avg_frame_rate : stream->r_frame_rate;
        fps_ = rate.num > 0 && rate.den > 0 ? av_q2d(rate) : 0.0;
        packet_ = av_packet_alloc();
        frame_ = av_frame_alloc();
        if (!packet_ || !frame_) fail("out of memory");
    }
    ~VideoSource() override {
        sws_freeContext(scaler_);
        av_frame_free(&frame_);
        av_packet_free(&packet_);
        avcodec_free_context(&decoder_);
        avformat_close_input(&input_);
    }

    std::optional<CameraFrame> next() override {
        while (true) {
            const int got = avcodec_receive_frame(decoder_, frame_);
            if (got == 0) return convert();
            if (got == AVERROR_EOF) return std::nullopt;
            if (got != AVERROR(EAGAIN)) fail(fmt::format("frame {}: cannot decode: {}", read_, avError(got)));
            if (flushed_) return std::nullopt;
            const int e = av_read_frame(input_, packet_);
            if (e == AVERROR_EOF) {
                avcodec_send_packet(decoder_, nullptr);  // the decoder gives the frames it holds, then EOF
                flushed_ = true;
                continue;
            }
            if (e < 0) fail(fmt::format("frame {}: cannot read: {}", read_, avError(e)));
            if (packet_->stream_index == stream_) {
                const int sent = avcodec_send_packet(decoder_, packet_);
                if (sent < 0 && sent != AVERROR(EAGAIN))
                    fail(fmt::format("frame {}: cannot decode: {}", read_, avError(sent)));
            }
            av_packet_unref(packet_);
        }
    }
    const std::string& name() const override { return name_; }
    int width() const override { return width_; }
    int height() const override { return height_; }
    double frameRate() const override { return fps_; }

  private:
    [[noreturn]] void fail(const std::string& what) const { throw InputError(name_, what); }

    CameraFrame convert() {
        if (frame_->width != width_ || frame_->height != height_)
            fail(fmt::format("the frames changed size at frame {}: {}x{}, the first were {}x{}", read_,
                             frame_->width, frame_->height, width_, height_));
        scaler_ = sws_getCachedContext(scaler_, width_, height_, static_cast<AVPixelFormat>(frame_->format),
                                       width_, height_, AV_PIX_FMT_RGB24, SWS_BICUBIC | SWS_ACCURATE_RND,
                                       nullptr, nullptr, nullptr);
        if (!scaler_) fail(fmt::format("frame {}: cannot convert its pixel format to RGB", read_));
        std::vector<uint8_t> rgb(static_cast<size_t>(width_) * height_ * 3);
        uint8_t* planes[4] = {rgb.data(), nullptr, nullptr, nullptr};
        int strides[4] = {3 * width_, 0, 0, 0};
        sws_scale(scaler_, frame_->data, frame_->linesize, 0, height_, planes, strides);
        CameraFrame out;
        out.image = Image(width_, height_, 3);
        const std::array<float, 256>& linear = srgb8ToLinearValues();
        std::span<float> pixels = out.image.data();
        for (size_t i = 0; i < rgb.size(); ++i) pixels[i] = linear[rgb[i]];
        out.index = read_++;
        const int64_t stamp = frame_->best_effort_timestamp;
        double time = stamp != AV_NOPTS_VALUE ? static_cast<double>(stamp) * timeBase_
                                              : static_cast<double>(out.index) / (fps_ > 0.0 ? fps_ : 30.0);
        if (!(time > lastTime_)) time = lastTime_ + 1.0 / (fps_ > 0.0 ? fps_ : 30.0);  // increasing
        out.timeSeconds = lastTime_ = time;
        av_frame_unref(frame_);
        return out;
    }

    std::string name_;
    AVFormatContext* input_ = nullptr;
    AVCodecContext* decoder_ = nullptr;
    AVPacket* packet_ = nullptr;
    AVFrame* frame_ = nullptr;
    SwsContext* scaler_ = nullptr;
    int stream_ = -1;
    int width_ = 0, height_ = 0;
    double timeBase_ = 0.0, fps_ = 0.0, lastTime_ = -INFINITY;
    int64_t read_ = 0;
    bool flushed_ = false;
};

}  // namespace

FrameFeed::FrameFeed(std::unique_ptr<FrameSource> source, bool realtime)
    : source_(std::move(source)),
      realtime_(realtime || isDevice(source_->name())),
      paced_(realtime && !isDevice(source_->name())) {
    reader_ = std::thread([this] { read(); });
}

FrameFeed::~FrameFeed() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    changed_.notify_all();
    reader_.join();
}

void FrameFeed::read() {
    const Clock::time_point start = Clock::now();
    std::optional<double> firstTime;
    while (true) {
        std::optional<CameraFrame> frame;
        try {
            frame = source_->next();
        } catch (...) {
            std::lock_guard lock(mutex_);
            error_ = std::current_exception();
            ended_ = true;
            changed_.notify_all();
            return;
        }
        std::unique_lock lock(mutex_);
        if (!frame || stopping_) {
            ended_ = true;
            changed_.notify_all();
            return;
        }
        if (paced_) {
            // A recorded camera replayed live: the frame arrives when its timestamp says.
            if (!firstTime) firstTime = frame->timeSeconds;
            const auto due = start + std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double>(frame->timeSeconds - *firstTime));
            if (changed_.wait_until(lock, due, [&] { return stopping_; })) return;
        } else if (!realtime_) {
            // Every frame is used: wait until the one before is taken.
            changed_.wait(lock, [&] { return !newest_ || stopping_; });
            if (stopping_) return;
        }
        if (newest_) ++droppedSinceTake_, ++droppedTotal_;
        newest_ = Arrival{std::move(*frame), Clock::now(), 0};
        changed_.notify_all();
    }
}

std::optional<FrameFeed::Arrival> FrameFeed::takeLocked(std::unique_lock<std::mutex>& lock) {
    std::optional<Arrival> out = std::move(newest_);
    newest_.reset();
    // Every frame is used: it arrives when it is wanted (the one read ahead waited for the one before).
    if (!realtime_) out->arrived = Clock::now();
    out->dropped = droppedSinceTake_;
    droppedSinceTake_ = 0;
    changed_.notify_all();
    return out;
}

std::optional<FrameFeed::Arrival> FrameFeed::take() {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return newest_.has_value() || ended_; });
    if (newest_) return takeLocked(lock);
    if (error_) std::rethrow_exception(error_);
    return std::nullopt;
}

std::optional<FrameFeed::Arrival> FrameFeed::poll() {
    std::unique_lock lock(mutex_);
    if (newest_) return takeLocked(lock);
    if (ended_ && error_) std::rethrow_exception(error_);
    return std::nullopt;
}

std::optional<FrameFeed::Arrival> FrameFeed::takeUntil(Clock::time_point deadline) {
    std::unique_lock lock(mutex_);
    changed_.wait_until(lock, deadline, [&] { return newest_.has_value() || ended_; });
    if (newest_) return takeLocked(lock);
    if (ended_ && error_) std::rethrow_exception(error_);
    return std::nullopt;
}

bool FrameFeed::ended() const {
    std::lock_guard lock(mutex_);
    return ended_ && !newest_;
}

int FrameFeed::droppedTotal() const {
    std::lock_guard lock(mutex_);
    return droppedTotal_;
}

std::unique_ptr<FrameSource> openFrameSource(const std::string& source, double patternFps) {
    if (source.empty())
        throw InputError("", "expected a camera source (a video file, /dev/videoN or frame_####.png)");
    if (source.find('#') != std::string::npos) return std::make_unique<PatternSource>(source, patternFps);
    return std::make_unique<VideoSource>(source);
}

}  // namespace deltagi
