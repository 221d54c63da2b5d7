// Video output (cli/video_output.h): libswscale converts sRGB RGB to YUV 4:2:0, libavcodec's libx264 encodes
// (MP4) or wraps the raw frames (Y4M), libavformat's muxer writes the temporary file that AtomicFile renames
// into place.
#include "video_output.h"

#include <algorithm>
#include <mutex>
#include <vector>

#include <fmt/format.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/imgutils.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include "deltagi/error.h"

namespace fs = std::filesystem;

namespace deltagi::cli {

namespace {

// FFmpeg's own messages would break the rule of one error line: the last error it logs is kept and added to
// deltagi's message instead.
std::mutex gLogMutex;
std::string gLastLog;

void keepLastError(void*, int level, const char* format, va_list args) {
    if (level > AV_LOG_ERROR) return;
    char line[1024];
    std::vsnprintf(line, sizeof line, format, args);
    std::string text = line;
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    const std::lock_guard lock(gLogMutex);
    gLastLog = text;
}

void quietLogs() {
    static std::once_flag once;
    std::call_once(once, [] { av_log_set_callback(keepLastError); });
}

std::string errorText(int error) {
    char text[AV_ERROR_MAX_STRING_SIZE] = {};
    av_strerror(error, text, sizeof text);
    const std::lock_guard lock(gLogMutex);
    return gLastLog.empty() ? std::string(text) : fmt::format("{} ({})", text, gLastLog);
}

// libx264, else whatever H.264 encoder this FFmpeg has (which may not take x264's options).
const AVCodec* h264Encoder() {
    if (const AVCodec* x264 = avcodec_find_encoder_by_name("libx264")) return x264;
    return avcodec_find_encoder(AV_CODEC_ID_H264);
}

std::string lowerExtension(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

}  // namespace

bool isY4m(const fs::path& path) {
    return lowerExtension(path) == ".y4m";
}

void checkVideoPath(const fs::path& path, const std::string& option) {
    const std::string ext = lowerExtension(path);
    if (ext != ".mp4" && ext != ".y4m")
        throw InputError(
            path.string(),
            fmt::format("{} writes an H.264 video in an MP4 file (.mp4) or uncompressed frames in a "
                        "YUV4MPEG2 file (.y4m): got '{}'",
                        option, path.extension().string()));
}

void checkVideoEncoder(const fs::path& path, const std::string& option) {
    quietLogs();
    if (isY4m(path)) return;  // no encoder: raw frames
    if (!h264Encoder())
        throw InputError(option, fmt::format("this FFmpeg (libavcodec {}) has no H.264 encoder: install one "
                                             "built with libx264 (Debian's libavcodec59 is)",
                                             AV_STRINGIFY(LIBAVCODEC_VERSION)));
}

struct VideoWriter::FFmpeg {
    AVFormatContext* format = nullptr;
    AVCodecContext* codec = nullptr;
    AVStream* stream = nullptr;
    SwsContext* sws = nullptr;
    AVFrame* frame = nullptr;
    AVPacket* packet = nullptr;
    int encodedWidth = 0, encodedHeight = 0;
    std::vector<uint8_t> padded;  // the frame's RGB at the encoded (even) size

    ~FFmpeg() {
        av_packet_free(&packet);
        av_frame_free(&frame);
        sws_freeContext(sws);
        avcodec_free_context(&codec);
        if (format) {
            if (format->pb) avio_closep(&format->pb);
            avformat_free_context(format);
        }
    }
};

VideoWriter::VideoWriter(const fs::path& destination, int width, int height, VideoSettings settings)
    : file_(destination), width_(width), height_(height), ff_(std::make_unique<FFmpeg>()) {
    quietLogs();
    const bool y4m = isY4m(destination);
    checkVideoEncoder(destination, "--video");
    // Y4M: the raw frames, which libavformat's muxer takes wrapped in packets.
    const AVCodec* encoder = y4m ? avcodec_find_encoder(AV_CODEC_ID_WRAPPED_AVFRAME) : h264Encoder();
    if (!encoder)
        fail("cannot start the Y4M file: this FFmpeg has no wrapped_avframe encoder", AVERROR(EINVAL));
    const bool x264 = std::string(encoder->name) == "libx264";
    const char* container = y4m ? "Y4M" : "MP4";
    const AVRational rate = av_d2q(settings.fps, 1001000);
    FFmpeg& ff = *ff_;
    // yuv420p halves the chroma in both directions: the encoded size is even.
    ff.encodedWidth = (width + 1) & ~1;
    ff.encodedHeight = (height + 1) & ~1;

    const std::string temporary = file_.temporaryPath().string();
    int error =
        avformat_alloc_output_context2(&ff.format, nullptr, y4m ? "yuv4mpegpipe" : "mp4", temporary.c_str());
    if (error < 0 || !ff.format) fail(fmt::format("cannot start the {} file", container), error);
    ff.format->flags |= AVFMT_FLAG_BITEXACT;  // no version strings or times: the same frames, the same file

    ff.codec = avcodec_alloc_context3(encoder);
    if (!ff.codec) fail(fmt::format("cannot start the {} encoder", encoder->name), AVERROR(ENOMEM));
    AVCodecContext& c = *ff.codec;
    c.width = ff.encodedWidth;
    c.height = ff.encodedHeight;
    c.time_base = av_inv_q(rate);
    c.framerate = rate;
    c.pix_fmt = AV_PIX_FMT_YUV420P;
    c.thread_count = 1;  // x264's output depends on its thread count
    c.flags |= AV_CODEC_FLAG_BITEXACT;
    if (ff.format->oformat->flags & AVFMT_GLOBALHEADER) c.flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    // Limited range; BT.709 in the MP4, which says so; BT.601 in the Y4M, which cannot, and whose readers
    // (Chromium's fake camera) take it as BT.601.
    c.color_range = AVCOL_RANGE_MPEG;
    c.colorspace = y4m ? AVCOL_SPC_SMPTE170M : AVCOL_SPC_BT709;
    c.color_primaries = y4m ? AVCOL_PRI_SMPTE170M : AVCOL_PRI_BT709;
    c.color_trc = AVCOL_TRC_IEC61966_2_1;  // the frames are sRGB-encoded
    if (y4m) {
        // nothing to set: the frames go through as they are
    } else if (x264) {
        av_opt_set(c.priv_data, "preset", "medium", 0);
        av_opt_set_double(c.priv_data, "crf", settings.crf, 0);
        // Macroblock-tree rate control off: with it, Debian 12's libx264 (0.164) reads memory it did not
        // initialise, and the file changes from run to run with whatever the heap held (MALLOC_PERTURB_
        // shows it); without it, the same frames give the same file.
        av_opt_set_int(c.priv_data, "mbtree", 0, 0);
    } else {
        // Another H.264 encoder: a bit rate of about what x264 gives at CRF 18 for rendered frames.
        c.bit_rate = static_cast<int64_t>(0.2 * c.width * c.height * settings.fps);
    }
    error = avcodec_open2(&c, encoder, nullptr);
    if (error < 0) fail(fmt::format("cannot open the H.264 encoder ({})", encoder->name), error);

    ff.stream = avformat_new_stream(ff.format, nullptr);
    if (!ff.stream) fail("cannot add the video stream", AVERROR(ENOMEM));
    error = avcodec_parameters_from_context(ff.stream->codecpar, &c);
    if (error < 0) fail("cannot set the video stream", error);
    ff.stream->time_base = c.time_base;
    ff.stream->avg_frame_rate = rate;

    error = avio_open(&ff.format->pb, temporary.c_str(), AVIO_FLAG_WRITE);
    if (error < 0) fail("cannot write file", error);
    AVDictionary* options = nullptr;
    av_dict_set(&options, "movflags", "+faststart", 0);  // the index first: players start before the end
    error = avformat_write_header(ff.format, y4m ? nullptr : &options);
    av_dict_free(&options);
    if (error < 0) fail(fmt::format("cannot write the {} header", container), error);

    ff.sws = sws_getContext(ff.encodedWidth, ff.encodedHeight, AV_PIX_FMT_RGB24, ff.encodedWidth,
                            ff.encodedHeight, AV_PIX_FMT_YUV420P,
                            SWS_BILINEAR | SWS_ACCURATE_RND | SWS_BITEXACT, nullptr, nullptr, nullptr);
    if (!ff.sws) fail("cannot convert RGB to YUV", AVERROR(EINVAL));
    const int* coefficients = sws_getCoefficients(y4m ? SWS_CS_ITU601 : SWS_CS_ITU709);
    // Source: full-range RGB; destination: limited-range ("TV") YUV, as players expect.
    sws_setColorspaceDetails(ff.sws, coefficients, 1, coefficients, 0, 0, 1 << 16, 1 << 16);

    ff.packet = av_packet_alloc();
    if (!ff.packet) fail(fmt::format("cannot start the {} encoder", encoder->name), AVERROR(ENOMEM));
    ff.padded.resize(static_cast<size_t>(ff.encodedWidth) * ff.encodedHeight * 3);
}

VideoWriter::~VideoWriter() = default;

void VideoWriter::fail(const std::string& what, int error) const {
    throw InputError(file_.destination().string(), fmt::format("{}: {}", what, errorText(error)));
}

void VideoWriter::add(const Image& linear) {
    if (linear.channels() != 3)
        throw InputError(file_.destination().string(), "expected an RGB image for a video frame");
    addSrgb8(encodeSrgb8(linear));
}

void VideoWriter::addSrgb8(std::span<const uint8_t> rgb) {
    FFmpeg& ff = *ff_;
    const size_t row = static_cast<size_t>(width_) * 3, paddedRow = static_cast<size_t>(ff.encodedWidth) * 3;
    if (rgb.size() != row * height_)
        throw InputError(file_.destination().string(),
                         fmt::format("a video frame of {} bytes, expected {}x{} RGB ({} bytes)", rgb.size(),
                                     width_, height_, row * height_));
    for (int y = 0; y < ff.encodedHeight; ++y) {
        const uint8_t* from = rgb.data() + std::min(y, height_ - 1) * row;
        uint8_t* to = ff.padded.data() + y * paddedRow;
        std::copy(from, from + row, to);
        if (ff.encodedWidth > width_) std::copy(from + row - 3, from + row, to + row);
    }
    // A new frame each time (the encoder may still hold the last one), zeroed: the planes' alignment padding
    // holds no stale heap bytes.
    av_frame_free(&ff.frame);
    ff.frame = av_frame_alloc();
    if (!ff.frame) fail("cannot encode a frame", AVERROR(ENOMEM));
    ff.frame->format = ff.codec->pix_fmt;
    ff.frame->width = ff.codec->width;
    ff.frame->height = ff.codec->height;
    ff.frame->color_range = ff.codec->color_range;
    ff.frame->colorspace = ff.codec->colorspace;
    int error = av_frame_get_buffer(ff.frame, 0);
    if (error < 0) fail("cannot encode a frame", error);
    for (AVBufferRef* buffer : ff.frame->buf)
        if (buffer) std::fill_n(buffer->data, buffer->size, uint8_t{0});
    const uint8_t* planes[1] = {ff.padded.data()};
    const int strides[1] = {static_cast<int>(paddedRow)};
    sws_scale(ff.sws, planes, strides, 0, ff.encodedHeight, ff.frame->data, ff.frame->linesize);
    ff.frame->pts = frames_;
    error = avcodec_send_frame(ff.codec, ff.frame);
    if (error < 0) fail("cannot encode a frame", error);
    ++frames_;
    writePackets();
}

// Writes the packets the encoder has ready (after a flush: all of them).
void VideoWriter::writePackets() {
    FFmpeg& ff = *ff_;
    for (;;) {
        const int error = avcodec_receive_packet(ff.codec, ff.packet);
        if (error == AVERROR(EAGAIN) || error == AVERROR_EOF) return;  // needs a frame, or flushed
        if (error < 0) fail("cannot encode a frame", error);
        av_packet_rescale_ts(ff.packet, ff.codec->time_base, ff.stream->time_base);
        ff.packet->stream_index = ff.stream->index;
        const int written = av_interleaved_write_frame(ff.format, ff.packet);  // takes the packet's data
        if (written < 0) fail("cannot write file", written);
    }
}

void VideoWriter::commit() {
    FFmpeg& ff = *ff_;
    if (frames_ == 0) throw InputError(file_.destination().string(), "a video needs at least one frame");
    int error = avcodec_send_frame(ff.codec, nullptr);
    if (error < 0) fail("cannot finish the video", error);
    writePackets();
    error = av_write_trailer(ff.format);
    if (error < 0)
        fail(fmt::format("cannot finish the {} file", isY4m(file_.destination()) ? "Y4M" : "MP4"), error);
    error = avio_closep(&ff.format->pb);
    if (error < 0) fail("cannot write file", error);
    file_.commit();
}

}  // namespace deltagi::cli
