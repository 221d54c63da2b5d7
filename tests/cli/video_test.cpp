// `deltagi render --video` and `deltagi encode`: the MP4 (and the Y4M) decoded back with
// libavformat/libavcodec has the frames, their size and their colours; the same frames give the same file;
// outputs are atomic.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
}

#include "deltagi/image.h"
#include "test_errors.h"
#include "test_files.h"
#include "test_scene_json.h"
#include "test_sequence.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::SequenceTest;

// A video as decoded: the stream's codec, size and frame rate, and each frame's mean R, G, B (8-bit sRGB
// scale, converted back from BT.709 limited-range YUV 4:2:0, or BT.601 for a Y4M).
struct Decoded {
    std::string codec;
    int width = 0, height = 0;
    AVPixelFormat format = AV_PIX_FMT_NONE;
    double fps = 0.0;
    std::vector<std::array<double, 3>> means;
};

Decoded decode(const fs::path& file, bool bt601 = false) {
    Decoded out;
    AVFormatContext* format = nullptr;
    if (avformat_open_input(&format, file.c_str(), nullptr, nullptr) < 0) {
        ADD_FAILURE() << "cannot open " << file;
        return out;
    }
    EXPECT_GE(avformat_find_stream_info(format, nullptr), 0);
    const int index = av_find_best_stream(format, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
    EXPECT_GE(index, 0);
    if (index < 0) {
        avformat_close_input(&format);
        return out;
    }
    const AVStream* stream = format->streams[index];
    const AVCodec* decoder = avcodec_find_decoder(stream->codecpar->codec_id);
    AVCodecContext* codec = avcodec_alloc_context3(decoder);
    avcodec_parameters_to_context(codec, stream->codecpar);
    EXPECT_GE(avcodec_open2(codec, decoder, nullptr), 0);
    out.codec = decoder->name;
    out.width = codec->width;
    out.height = codec->height;
    out.format = codec->pix_fmt;
    out.fps = av_q2d(stream->avg_frame_rate);
    AVPacket* packet = av_packet_alloc();
    AVFrame* frame = av_frame_alloc();
    // BT.709 limited range back to R'G'B' (Rec. ITU-R BT.709-6, 3.2-3.3; BT.601-7, 2.5 for a Y4M), in double:
    // the test's own inverse, not the writer's library run backwards.
    const double kr = bt601 ? 0.299 : 0.2126, kb = bt601 ? 0.114 : 0.0722, kg = 1.0 - kr - kb;
    auto take = [&] {
        while (avcodec_receive_frame(codec, frame) >= 0) {
            EXPECT_EQ(frame->format, AV_PIX_FMT_YUV420P);
            std::array<double, 3> mean{};
            for (int y = 0; y < frame->height; ++y)
                for (int x = 0; x < frame->width; ++x) {
                    const double luma = (frame->data[0][y * frame->linesize[0] + x] - 16.0) / 219.0;
                    const double pb = (frame->data[1][(y / 2) * frame->linesize[1] + x / 2] - 128.0) / 224.0;
                    const double pr = (frame->data[2][(y / 2) * frame->linesize[2] + x / 2] - 128.0) / 224.0;
                    const double rgb[3] = {
                        luma + 2.0 * (1.0 - kr) * pr,
                        luma - 2.0 * kb * (1.0 - kb) / kg * pb - 2.0 * kr * (1.0 - kr) / kg * pr,
                        luma + 2.0 * (1.0 - kb) * pb};
                    for (int c = 0; c < 3; ++c) mean[c] += std::clamp(rgb[c], 0.0, 1.0) * 255.0;
                }
            for (double& m : mean) m /= static_cast<double>(frame->width) * frame->height;
            out.means.push_back(mean);
        }
    };
    while (av_read_frame(format, packet) >= 0) {
        if (packet->stream_index == index) {
            EXPECT_GE(avcodec_send_packet(codec, packet), 0);
            take();
        }
        av_packet_unref(packet);
    }
    avcodec_send_packet(codec, nullptr);
    take();
    av_frame_free(&frame);
    av_packet_free(&packet);
    avcodec_free_context(&codec);
    avformat_close_input(&format);
    return out;
}

// The mean R, G, B of an image's 8-bit sRGB pixels (what its PNG holds).
std::array<double, 3> srgbMean(const Image& image) {
    const std::vector<uint8_t> bytes = encodeSrgb8(image);
    std::array<double, 3> mean{};
    for (size_t i = 0; i < bytes.size(); ++i) mean[i % 3] += bytes[i];
    for (double& m : mean) m /= static_cast<double>(image.pixelCount());
    return mean;
}

std::string text(const fs::path& path) {
    return test::readText(path);
}

using VideoTest = SequenceTest;

// The video holds every frame of the sequence, of its size, in H.264 yuv420p at the frame rate asked for,
// and each frame's mean colour is the PNG frame's within the rounding of YUV 4:2:0.
TEST_F(VideoTest, RenderWritesTheFramesAsH264) {
    write(transforms(4, 48, 32));
    const fs::path scene = writeSequenceScene(test::tinySceneJson(48, 32, {0.9, 0.3, 0.1}));
    ASSERT_EQ(runCli("render " + scene.string() + " -q -o " + (dir_ / "f_####.png").string() + " --video " +
                     (dir_ / "out/v.mp4").string() + " --fps 24"),
              0)
        << errors();
    const Decoded video = decode(dir_ / "out/v.mp4");
    EXPECT_EQ(video.codec, "h264");
    EXPECT_EQ(video.width, 48);
    EXPECT_EQ(video.height, 32);
    EXPECT_EQ(video.format, AV_PIX_FMT_YUV420P);
    EXPECT_NEAR(video.fps, 24.0, 1e-9);
    ASSERT_EQ(video.means.size(), 4u);
    for (int i = 0; i < 4; ++i) {
        const std::array<double, 3> png = srgbMean(readImage(dir_ / ("f_000" + std::to_string(i) + ".png")));
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(video.means[i][c], png[c], 1.0) << "frame " << i << " " << c;
    }
    // The photos differ from frame to frame (grey 0.2, 0.3, ...): so do the frames, in order.
    EXPECT_GT(video.means[3][1], video.means[0][1] + 20.0);

    // Without -o, the video alone; the frame rate is the sequence's (sequence.fps), a range of frames.
    json withFps = json::parse(text(scene));
    withFps["sequence"]["fps"] = 12.5;
    const fs::path scene2 = write(withFps, "scene2.json");
    ASSERT_EQ(
        runCli("render " + scene2.string() + " -q --frames 1:3 --video " + (dir_ / "part.mp4").string()), 0)
        << errors();
    const Decoded part = decode(dir_ / "part.mp4");
    EXPECT_NEAR(part.fps, 12.5, 1e-9);
    ASSERT_EQ(part.means.size(), 2u);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(part.means[0][c], video.means[1][c], 1.0);
    EXPECT_FALSE(fs::exists(dir_ / "f_0004.png"));
}

// The same frames give the same file, byte for byte: whatever the thread count, whatever the heap held
// (libx264's macroblock-tree rate control read memory it had not initialised), and from the PNG frames by
// `deltagi encode` as from the render.
TEST_F(VideoTest, TheSameFramesGiveTheSameFile) {
    write(transforms(5));
    const fs::path scene = writeSequenceScene(test::tinySceneJson(32, 24, {0.2, 0.8, 0.3}));
    const std::string render = "render " + scene.string() + " -q --video ";
    ASSERT_EQ(runCli(render + (dir_ / "a.mp4").string() + " -o " + (dir_ / "f_##.png").string()), 0)
        << errors();
    ASSERT_EQ(runCli(render + (dir_ / "b.mp4").string() + " --threads 1", "MALLOC_PERTURB_=85"), 0);
    ASSERT_EQ(runCli(render + (dir_ / "c.mp4").string() + " --threads 2", "MALLOC_PERTURB_=200"), 0);
    ASSERT_EQ(runCli("encode " + (dir_ / "f_##.png").string() + " -q -o " + (dir_ / "d.mp4").string()), 0)
        << errors();
    const std::string a = text(dir_ / "a.mp4");
    EXPECT_GT(a.size(), 100u);
    for (const char* other : {"b.mp4", "c.mp4", "d.mp4"}) EXPECT_TRUE(text(dir_ / other) == a) << other;
    // A lower quality makes a smaller file.
    ASSERT_EQ(runCli(render + (dir_ / "e.mp4").string() + " --crf 40"), 0) << errors();
    EXPECT_LT(fs::file_size(dir_ / "e.mp4"), a.size());
}

// An odd size is padded to an even one (yuv420p halves the chroma both ways).
TEST_F(VideoTest, AnOddSizeIsPadded) {
    write(transforms(2, 33, 25));
    const fs::path scene = writeSequenceScene(test::tinySceneJson(33, 25, {0.5, 0.5, 0.5}));
    ASSERT_EQ(runCli("render " + scene.string() + " -q --video " + (dir_ / "odd.mp4").string()), 0)
        << errors();
    const Decoded video = decode(dir_ / "odd.mp4");
    EXPECT_EQ(video.width, 34);
    EXPECT_EQ(video.height, 26);
    EXPECT_EQ(video.means.size(), 2u);
}

// An interrupted run leaves the previous video as it was and no temporary file; bad outputs fail before the
// render with one line naming them.
TEST_F(VideoTest, OutputsAreAtomicAndChecked) {
    write(transforms(2));
    const fs::path scene = writeSequenceScene(test::tinySceneJson(32, 24, {0.5, 0.5, 0.5}));
    test::writeText(dir_ / "v.mp4", "the previous video");
    EXPECT_EQ(runCli("render " + scene.string() + " -q --video " + (dir_ / "v.mp4").string(),
                     "DELTAGI_TEST_SIGNAL_BEFORE_RENAME=2"),
              130);
    EXPECT_EQ(text(dir_ / "v.mp4"), "the previous video");
    for (const auto& entry : fs::directory_iterator(dir_))
        EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();

    EXPECT_EQ(runCli("render " + scene.string() + " --video " + (dir_ / "v.mov").string()), 1);
    test::expectContains(errors(), {"v.mov", ".mp4", ".y4m"});
    // The scene file itself, by another name, is an input.
    fs::copy_file(scene, dir_ / "scene.mp4");
    EXPECT_EQ(runCli("render " + (dir_ / "scene.mp4").string() + " --video " + (dir_ / "scene.mp4").string()),
              1);
    test::expectContains(errors(), {"scene.mp4", "is an input of this run"});
    EXPECT_EQ(runCli("render " + scene.string()), 2);
    test::expectContains(errors(), {"-o OUTPUT", "--video"});
    EXPECT_EQ(runCli("render " + scene.string() + " -o " + (dir_ / "f.png").string() + " --crf 18"), 2);
    test::expectContains(errors(), "--crf requires --video");
    // A scene without a sequence has no frames for a video.
    const fs::path still = write(test::tinySceneJson(32, 24, {0.5, 0.5, 0.5}), "still.json");
    EXPECT_EQ(runCli("render " + still.string() + " --video " + (dir_ / "s.mp4").string()), 1);
    test::expectContains(errors(), {"--video", "sequence"});
    // Frames of two sizes make no video: refused before any frame is rendered.
    json doc = transforms(3);
    doc["frames"][2]["w"] = 16;
    doc["frames"][2]["h"] = 12;
    writeImage(Image(16, 12, 3, 0.5f), dir_ / "images/frame_2.png");
    write(doc);
    EXPECT_EQ(runCli("render " + scene.string() + " -o " + (dir_ / "g_#.png").string() + " --video " +
                     (dir_ / "g.mp4").string()),
              1);
    test::expectContains(errors(), {"transforms.json: frames[2]", "16x12", "one size"});
    EXPECT_FALSE(fs::exists(dir_ / "g_0.png"));
}

// `deltagi encode` takes consecutive frames and names the first one missing, or one of another size.
TEST_F(VideoTest, EncodeChecksItsFrames) {
    for (int i : {3, 4, 5, 7})
        writeImage(Image(8, 6, 3, 0.1f * i), dir_ / ("f_" + std::to_string(i) + ".png"));
    const std::string encode = "encode " + (dir_ / "f_#.png").string() + " -o " + (dir_ / "v.mp4").string();
    EXPECT_EQ(runCli(encode), 1);
    test::expectContains(errors(), {"f_6.png", "frame 6 of 3:8 is missing"});
    ASSERT_EQ(runCli(encode + " -q --frames 3:6"), 0) << errors();
    EXPECT_EQ(decode(dir_ / "v.mp4").means.size(), 3u);
    writeImage(Image(6, 6, 3, 0.5f), dir_ / "f_6.png");
    EXPECT_EQ(runCli(encode), 1);
    test::expectContains(errors(), {"f_6.png", "6x6", "8x6"});
    EXPECT_EQ(runCli("encode " + (dir_ / "none_#.png").string() + " -o " + (dir_ / "n.mp4").string()), 1);
    test::expectContains(errors(), "no frames found");
    EXPECT_EQ(runCli("encode " + (dir_ / "f_3.png").string() + " -o " + (dir_ / "n.mp4").string()), 1);
    test::expectContains(errors(), "frame_####.png");
}

// `encode -o X.y4m`: uncompressed YUV4MPEG2 (the file Chromium's fake camera reads), its header the frames'
// size and rate, each frame's colour the PNG's within 4:2:0's rounding (BT.601, limited range); the same
// frames give the same file.
TEST_F(VideoTest, EncodeWritesY4m) {
    const std::array<std::array<float, 3>, 3> colours = {
        {{0.8f, 0.1f, 0.05f}, {0.1f, 0.6f, 0.2f}, {0.2f, 0.3f, 0.9f}}};
    for (int i = 0; i < 3; ++i) {
        Image image(10, 6, 3);
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 10; ++x)
                for (int c = 0; c < 3; ++c) image.at(x, y, c) = colours[i][c];
        writeImage(image, dir_ / ("f_" + std::to_string(i) + ".png"));
    }
    const std::string encode =
        "encode " + (dir_ / "f_#.png").string() + " --fps 15 -q -o " + (dir_ / "camera.y4m").string();
    ASSERT_EQ(runCli(encode), 0) << errors();
    const std::string bytes = text(dir_ / "camera.y4m");
    EXPECT_TRUE(bytes.starts_with("YUV4MPEG2 W10 H6 F15:1")) << bytes.substr(0, 60);
    EXPECT_EQ(bytes.size(), bytes.find('\n') + 1 + 3 * (6 + 10 * 6 * 3 / 2))
        << "3 frames of 'FRAME\\n' + I420";
    const Decoded video = decode(dir_ / "camera.y4m", true);
    EXPECT_EQ(video.width, 10);
    EXPECT_EQ(video.height, 6);
    EXPECT_DOUBLE_EQ(video.fps, 15.0);
    ASSERT_EQ(video.means.size(), 3u);
    for (int i = 0; i < 3; ++i) {
        const std::array<double, 3> want = srgbMean(readImage(dir_ / ("f_" + std::to_string(i) + ".png")));
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(video.means[i][c], want[c], 2.5) << "frame " << i << " channel " << c;
    }
    ASSERT_EQ(runCli(encode + " --crf 30"), 0) << errors();  // the CRF is an MP4's
    EXPECT_EQ(text(dir_ / "camera.y4m"), bytes);
    EXPECT_EQ(runCli("encode " + (dir_ / "f_#.png").string() + " -o " + (dir_ / "v.avi").string()), 1);
    test::expectContains(errors(), {"v.avi", ".mp4", ".y4m"});
}

}  // namespace
}  // namespace deltagi
