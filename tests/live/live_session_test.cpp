// The live session's message handler (src/live/live_session.h), without sockets: bad messages are refused
// with an error and change nothing; a drag rests the object on the surface under the cursor; the saved
// document loads to the session's scene bit for bit.
#include "live/live_session.h"

#include <pthread.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "test_files.h"
#include "test_scene_json.h"

namespace deltagi::live {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

class LiveSessionTest : public ::testing::Test {
  protected:
    void SetUp() override {
        folder_ =
            fs::temp_directory_path() / ("deltagi-live-" + std::to_string(::getpid()) + "-" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(folder_);
    }
    void TearDown() override { fs::remove_all(folder_); }

    // The tiny scene of tests/test_scene_json.h (a floor, a box on it, a point light), as a file.
    fs::path writeScene(const json& document, const std::string& name = "scene.json") {
        const fs::path file = folder_ / name;
        test::writeText(file, document.dump(2));
        return file;
    }
    std::unique_ptr<Session> tinySession(int width = 64, int height = 48) {
        return std::make_unique<Session>(writeScene(test::tinySceneJson(width, height, {0.2, 0.3, 0.8})),
                                         std::vector<std::string>{});
    }

    fs::path folder_;
};

void expectRefused(Session& session, const std::string& message, const std::string& part) {
    const uint64_t version = session.version();
    const json state = session.state();
    const MessageResult result = session.handle(message);
    EXPECT_FALSE(result.changed) << message;
    ASSERT_TRUE(result.reply.is_object()) << message;
    EXPECT_EQ(result.reply["type"], "error") << message;
    EXPECT_NE(result.reply["message"].get<std::string>().find(part), std::string::npos)
        << message << " -> " << result.reply["message"];
    EXPECT_EQ(session.version(), version) << message;
    EXPECT_EQ(session.state(), state) << message;
}

TEST_F(LiveSessionTest, MalformedMessagesAreRefusedAndChangeNothing) {
    auto session = tinySession();
    expectRefused(*session, "{\"type\": \"drag\", ", "message");
    expectRefused(*session, "", "message");
    expectRefused(*session, "[1, 2, 3]", "expected a JSON object");
    expectRefused(*session, "{}", "\"type\"");
    expectRefused(*session, "{\"type\": 3}", "\"type\"");
    expectRefused(*session, "{\"type\": \"explode\"}", "expected ping, select");
    expectRefused(*session, "{\"type\": \"view\", \"view\": \"composite\", \"extra\": 1}",
                  "unknown key \"extra\"");
    expectRefused(*session, "{\"type\": \"view\", \"view\": \"../../etc/passwd\"}", "expected composite");
    expectRefused(*session, "{\"type\": \"select\", \"object\": 0, \"seq\": -1}", "seq");
    expectRefused(*session, std::string(200, '[') + std::string(200, ']'), "message");
}

TEST_F(LiveSessionTest, OversizedMessagesAreRefusedBeforeTheyAreParsed) {
    auto session = tinySession();
    std::string big = "{\"type\": \"ping\", \"pad\": \"" + std::string(kMaxMessageBytes, 'x') + "\"}";
    expectRefused(*session, big, "bytes, more than");
}

// The server's threads may have a small stack: a long malformed message is refused there too.
TEST_F(LiveSessionTest, AMalformedMessageIsRefusedOnASmallStack) {
    auto session = tinySession();
    const std::string message = "{\"type\": \"" + std::string(kMaxMessageBytes - 20, 'x');
    MessageResult result;
    pthread_attr_t attributes;
    pthread_attr_init(&attributes);
    pthread_attr_setstacksize(&attributes, 128 * 1024);
    struct Call {
        Session* session;
        const std::string* message;
        MessageResult* result;
    } call{session.get(), &message, &result};
    pthread_t thread;
    ASSERT_EQ(pthread_create(
                  &thread, &attributes,
                  [](void* p) -> void* {
                      auto* c = static_cast<Call*>(p);
                      *c->result = c->session->handle(*c->message);
                      return nullptr;
                  },
                  &call),
              0);
    pthread_join(thread, nullptr);
    pthread_attr_destroy(&attributes);
    EXPECT_FALSE(result.changed);
    ASSERT_TRUE(result.reply.is_object());
    EXPECT_NE(result.reply["message"].get<std::string>().find("message: line 1"), std::string::npos);
}

TEST_F(LiveSessionTest, OutOfRangeNumbersAndUnknownObjectsAreRefused) {
    auto session = tinySession();
    expectRefused(*session, R"({"type": "drag", "object": 0, "x": 1e999, "y": 10})", "message");
    expectRefused(*session, R"({"type": "drag", "object": 0, "x": -1, "y": 10})", "drag.x");
    expectRefused(*session, R"({"type": "drag", "object": 0, "x": 10, "y": 4800})", "drag.y");
    expectRefused(*session, R"({"type": "drag", "object": 0, "x": "NaN", "y": 10})", "drag.x");
    expectRefused(*session, R"({"type": "drag", "object": 0, "y": 10})", "drag.x");
    expectRefused(*session, R"({"type": "drag", "object": 7, "x": 10, "y": 10})", "drag.object");
    expectRefused(*session, R"({"type": "drag", "object": -1, "x": 10, "y": 10})", "drag.object");
    expectRefused(*session, R"({"type": "drag", "object": 0.5, "x": 10, "y": 10})", "drag.object");
    expectRefused(*session, R"({"type": "select", "object": 18446744073709551615})", "select.object");
    expectRefused(*session, R"({"type": "rotate", "object": 0, "degrees": 1e30})", "rotate.degrees");
    expectRefused(*session, R"({"type": "light", "light": 1, "intensity": 1})", "light.light");
    expectRefused(*session, R"({"type": "light", "light": 0, "intensity": -1})", "light.intensity");
    expectRefused(*session, R"({"type": "light", "light": 0, "position": [1, 2]})", "light.position");
    expectRefused(*session, R"({"type": "light", "light": 0, "position": [1, 2, 1e300]})", "light.position");
    // The sky above the floor: no real surface to rest on.
    expectRefused(*session, R"({"type": "drag", "object": 0, "x": 1, "y": 1})", "no real surface");
}

TEST_F(LiveSessionTest, HugeResolutionsAndUnknownOptionsAreRefused) {
    auto session = tinySession();
    expectRefused(*session, R"({"type": "options", "values": {"volume.resolution": 1024}})", "at most 256");
    expectRefused(*session, R"({"type": "options", "values": {"volume.resolution": 100}})", "power of two");
    expectRefused(*session, R"({"type": "options", "values": {"volume.resolution": 1e12}})", "integer");
    expectRefused(*session, R"({"type": "options", "values": {"volume.resolution": "auto"}})", "resolution");
    expectRefused(*session, R"({"type": "options", "values": {"diffuse.count": 100000}})", "count");
    expectRefused(*session, R"({"type": "options", "values": {"trace.jitter": 0}})", "not an option");
    expectRefused(*session, R"({"type": "options", "values": {}})", "options.values");
    expectRefused(*session, R"({"type": "options", "values": {"volume": {"resolution": 64}}})",
                  "not an option");
    const MessageResult ok = session->handle(R"({"type": "options", "values": {"volume.resolution": 32}})");
    EXPECT_TRUE(ok.changed) << ok.reply;
    EXPECT_EQ(session->scene().options.volume.resolution, 32);
    EXPECT_EQ(session->state()["options"]["volume.resolution"], 32);
}

// Random damage to valid messages: every outcome is a reply or a change, never an exception or a crash.
TEST_F(LiveSessionTest, DamagedMessagesNeverThrow) {
    auto session = tinySession();
    const std::vector<std::string> valid = {
        R"({"type": "drag", "object": 0, "x": 32, "y": 30, "seq": 3})",
        R"({"type": "rotate", "object": 0, "degrees": 15})",
        R"({"type": "light", "light": 0, "position": [0.5, 1.4, 0.5], "intensity": 2})",
        R"({"type": "options", "values": {"volume.resolution": 32, "diffuse.pixel_stride": "auto"}})",
        R"({"type": "view", "view": "delta"})",
        R"({"type": "select", "object": 0})"};
    std::mt19937 random(7);
    const std::string alphabet = "{}[]\":,.-+eE0123456789 abcdefghijklmnopqrstuvwxyz\\\x01\xff";
    for (int i = 0; i < 3000; ++i) {
        std::string message = valid[random() % valid.size()];
        const int edits = 1 + static_cast<int>(random() % 4);
        for (int e = 0; e < edits && !message.empty(); ++e) {
            const size_t at = random() % message.size();
            switch (random() % 3) {
                case 0:
                    message[at] = alphabet[random() % alphabet.size()];
                    break;
                case 1:
                    message.erase(at, 1 + random() % 3);
                    break;
                default:
                    message.insert(at, 1, alphabet[random() % alphabet.size()]);
            }
        }
        MessageResult result;
        ASSERT_NO_THROW(result = session->handle(message)) << message;
        EXPECT_TRUE(result.changed || result.reply.is_object()) << message;
    }
    // Still a scene the renderer takes.
    EXPECT_NO_THROW(checkFrame(session->scene()));
}

TEST_F(LiveSessionTest, ADragRestsTheObjectOnTheSurfaceUnderTheCursor) {
    auto session = tinySession(160, 120);
    const Bounds3f before = session->scene().virtuals[0].bounds();
    const json anchor = session->state()["objects"][0]["anchor"];
    ASSERT_TRUE(anchor.is_array());
    const MessageResult result =
        session->handle(R"({"type": "drag", "object": 0, "x": 100.5, "y": 90.25, "seq": 41})", 3);
    ASSERT_TRUE(result.changed) << result.reply;
    EXPECT_EQ(session->lastInputClient(), 3);
    EXPECT_EQ(session->lastInputSeq(), 41);
    const Bounds3f after = session->scene().virtuals[0].bounds();
    // On the floor (y = 0), same size, somewhere else.
    EXPECT_NEAR(after.min.y, 0.0f, 1e-5f);
    EXPECT_NEAR(after.max.y - after.min.y, before.max.y - before.min.y, 1e-5f);
    EXPECT_GT(glm::length(after.center() - before.center()), 0.05f);
    // Its contact point is the surface point under the cursor: it projects back to the pixel.
    const json moved = session->state()["objects"][0]["anchor"];
    EXPECT_NEAR(moved[0].get<double>(), 100.5, 1e-2);
    EXPECT_NEAR(moved[1].get<double>(), 90.25, 1e-2);
    // A rotation about the floor's normal keeps it resting where it is.
    ASSERT_TRUE(session->handle(R"({"type": "rotate", "object": 0, "degrees": 30})").changed);
    const Bounds3f turned = session->scene().virtuals[0].bounds();
    EXPECT_NEAR(turned.min.y, 0.0f, 1e-5f);
    EXPECT_NEAR(turned.center().x, after.center().x, 1e-4f);
    EXPECT_NEAR(turned.center().z, after.center().z, 1e-4f);
    EXPECT_GT(turned.max.x - turned.min.x, after.max.x - after.min.x + 0.01f);  // a turned box is wider
}

TEST_F(LiveSessionTest, ViewsAndSelectionAreSessionState) {
    auto session = tinySession();
    const uint64_t structure = session->structureVersion();
    ASSERT_TRUE(session->handle(R"({"type": "view", "view": "delta"})").changed);
    EXPECT_EQ(session->view(), View::Delta);
    EXPECT_EQ(session->state()["view"], "delta");
    EXPECT_EQ(session->structureVersion(), structure);  // no layers needed: the renderers keep their work
    ASSERT_TRUE(session->handle(R"({"type": "view", "view": "shadow"})").changed);
    EXPECT_GT(session->structureVersion(), structure);  // the layers are an option of the frames
    ASSERT_TRUE(session->handle(R"({"type": "select", "object": 0})").changed);
    const MessageResult ping = session->handle(R"({"type": "ping"})");
    EXPECT_FALSE(ping.changed);
    EXPECT_EQ(ping.reply["type"], "pong");
}

// What "save scene" downloads loads to the session's scene, bit for bit, and renders to its image.
TEST_F(LiveSessionTest, TheSavedDocumentLoadsToTheSessionsSceneBitForBit) {
    auto session = tinySession(48, 36);
    for (const char* message :
         {R"({"type": "drag", "object": 0, "x": 20.3, "y": 27.9})",
          R"({"type": "rotate", "object": 0, "degrees": 33})",
          R"({"type": "drag", "object": 0, "x": 30.1, "y": 25.2})",
          R"({"type": "light", "light": 0, "position": [0.3, 1.7, 0.45], "intensity": 2.3})",
          R"({"type": "options", "values": {"diffuse.count": 6, "shadow.relight_pixel_stride": 4}})"}) {
        const MessageResult r = session->handle(message);
        ASSERT_TRUE(r.changed) << message << " -> " << r.reply;
    }
    const fs::path saved = writeScene(session->document(), "saved.json");
    const Scene loaded = loadScene(saved);
    const Scene& live = session->scene();
    ASSERT_EQ(loaded.virtuals.size(), live.virtuals.size());
    for (size_t m = 0; m < live.virtuals.size(); ++m) {
        ASSERT_EQ(loaded.virtuals[m].positions, live.virtuals[m].positions);
        ASSERT_EQ(loaded.virtuals[m].normals, live.virtuals[m].normals);
        ASSERT_EQ(loaded.virtuals[m].triangles, live.virtuals[m].triangles);
    }
    ASSERT_EQ(loaded.lights.size(), live.lights.size());
    EXPECT_EQ(loaded.lights[0].position, live.lights[0].position);
    EXPECT_EQ(loaded.lights[0].intensity, live.lights[0].intensity);
    EXPECT_EQ(optionsToJson(loaded.options), optionsToJson(live.options));
    const RenderOutput a = render(loaded);
    FrameRenderer frames;
    const RenderOutput b = frames.renderStill(live);  // the session's idle frame
    ASSERT_EQ(a.composite.data().size(), b.composite.data().size());
    for (size_t i = 0; i < a.composite.data().size(); ++i)
        ASSERT_EQ(a.composite.data()[i], b.composite.data()[i]) << "value " << i;
}

TEST_F(LiveSessionTest, TheSavedDocumentNamesFilesByAbsolutePaths) {
    test::writeText(folder_ / "tri.obj", "v 0 0 0\nv 0.2 0 0\nv 0 0.2 0\nf 1 2 3\n");
    json document = test::tinySceneJson(32, 24, {0.2, 0.3, 0.8});
    document["virtual"].push_back({{"name", "tri"}, {"file", "tri.obj"}});
    Session session(writeScene(document), {});
    const json saved = session.document();
    const fs::path file = saved["virtual"][1]["file"].get<std::string>();
    EXPECT_TRUE(file.is_absolute()) << file;
    EXPECT_TRUE(fs::exists(file)) << file;
    EXPECT_EQ(session.state()["objects"].size(), 2u);
}

TEST_F(LiveSessionTest, ASequenceSceneIsRefused) {
    writeImage(Image(32, 24, 3, 0.5f), folder_ / "f.png");
    const json transforms = {
        {"fl_x", 30},
        {"fl_y", 30},
        {"cx", 16},
        {"cy", 12},
        {"w", 32},
        {"h", 24},
        {"frames",
         {{{"file_path", "f.png"},
           {"transform_matrix", {{1, 0, 0, 0}, {0, 1, 0, 0.5}, {0, 0, 1, 2}, {0, 0, 0, 1}}}}}}};
    test::writeText(folder_ / "transforms.json", transforms.dump());
    json document = test::tinySceneJson(32, 24, {0.2, 0.3, 0.8});
    document.erase("camera");
    document["sequence"] = {{"transforms", "transforms.json"}};
    try {
        Session session(writeScene(document), {});
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("a live session shows one camera"), std::string::npos)
            << e.what();
    }
}

TEST(LiveSessionImages, InteractiveOptionsTakeOneSamplePerPixelAndSparserCones) {
    Options full;
    full.diffuse.count = 12;
    full.diffuse.relightPixelStride = 32;
    Options fast = interactiveOptions(full, 640, 480, 1);
    EXPECT_EQ(fast.render.samplesPerPixel, 1);
    EXPECT_EQ(fast.diffuse.pixelStride, 2 * kAutoDiffuseStride);
    EXPECT_EQ(fast.diffuse.relightPixelStride, 32);  // at most 32
    EXPECT_EQ(fast.specular.relightPixelStride, 2 * kAutoRelightSpecularStride);
    EXPECT_EQ(fast.shadow.relightPixelStride, 2 * kAutoRelightShadowStride);
    EXPECT_EQ(fast.shadow.pixelStride, 2 * kAutoShadowStride);
    EXPECT_EQ(fast.rsm.resolution, 192);  // "auto" is 384 at 128^3
    EXPECT_EQ(fast.diffuse.objectRays, 4);
    EXPECT_EQ(fast.diffuse.objectRayPixelStride, 2 * kAutoObjectRayStride);
    EXPECT_EQ(interactiveOptions(full, 320, 240, 1).diffuse.pixelStride,
              kAutoDiffuseStride);                                       // auto is 4 there
    EXPECT_EQ(interactiveOptions(full, 640, 480, 3).rsm.resolution, 0);  // several lights keep "auto"
    full.rsm.resolution = 64;
    EXPECT_EQ(interactiveOptions(full, 640, 480, 3).rsm.resolution, 64);  // not below the smallest
    full.rsm.resolution = 0;
    // Everything else is the scene's.
    fast.render.samplesPerPixel = full.render.samplesPerPixel;
    fast.diffuse.pixelStride = full.diffuse.pixelStride;
    fast.diffuse.relightPixelStride = full.diffuse.relightPixelStride;
    fast.specular.relightPixelStride = full.specular.relightPixelStride;
    fast.shadow.pixelStride = full.shadow.pixelStride;
    fast.shadow.relightPixelStride = full.shadow.relightPixelStride;
    fast.rsm.resolution = full.rsm.resolution;
    fast.diffuse.objectRays = full.diffuse.objectRays;
    fast.diffuse.objectRayPixelStride = full.diffuse.objectRayPixelStride;
    EXPECT_EQ(optionsToJson(fast), optionsToJson(full));
}

// Interactive frames at half the width and height: the camera sees the same picture (a world point lands at
// half its pixel coordinates), the photo is averaged over 2 x 2 blocks, the strides are halved so that the
// cones stay as dense on the surfaces; sizes that do not divide, or would be too small, stay as they are.
TEST(LiveSessionImages, InteractiveFramesAtHalfSizeShowTheSamePicture) {
    Scene scene;
    scene.camera.width = 640;
    scene.camera.height = 480;
    scene.camera.setFieldOfView(50.0);
    scene.camera.cx += 3.0f;  // a principal point off the centre
    scene.camera.worldFromCamera[3] = glm::vec4(0.1f, 0.2f, 2.0f, 1.0f);
    Image photo(640, 480, 3, 0.0f);
    for (int y = 0; y < 480; ++y)
        for (int x = 0; x < 640; ++x)
            photo.setRgb(x, y, {static_cast<float>(x % 2), static_cast<float>(y), 0.5f});
    scene.background = photo;
    Options options;
    options.diffuse.pixelStride = 16;
    Scene half;
    ASSERT_EQ(interactiveScene(scene, options, 2, half), 2);
    EXPECT_EQ(half.camera.width, 320);
    EXPECT_EQ(half.camera.height, 240);
    EXPECT_EQ(half.options.diffuse.pixelStride, 16);
    const glm::vec3 point(0.3f, -0.1f, -1.0f);  // camera space
    const glm::vec2 there = scene.camera.imagePoint(point), small = half.camera.imagePoint(point);
    EXPECT_NEAR(small.x, 0.5f * there.x, 1e-4f);
    EXPECT_NEAR(small.y, 0.5f * there.y, 1e-4f);
    ASSERT_TRUE(half.background.has_value());
    ASSERT_EQ(half.background->width(), 320);
    EXPECT_FLOAT_EQ(half.background->at(5, 7, 0), 0.5f);   // columns 10 and 11: 0 and 1
    EXPECT_FLOAT_EQ(half.background->at(5, 7, 1), 14.5f);  // rows 14 and 15
    EXPECT_EQ(scene.camera.width, 640);                    // the session's own scene is untouched
    // The strides, resolved for the full image, halved.
    const Options full = interactiveOptions(Options{}, 640, 480, 1);
    const Options smaller = interactiveOptions(Options{}, 640, 480, 1, 2);
    EXPECT_EQ(smaller.diffuse.pixelStride, full.diffuse.pixelStride / 2);
    EXPECT_EQ(smaller.shadow.relightPixelStride, full.shadow.relightPixelStride / 2);
    EXPECT_EQ(smaller.shadow.pixelStride, std::max(full.shadow.pixelStride / 2, 1));
    // Too small, or not divisible: full size.
    EXPECT_FALSE(canReduceResolution(96, 72, 2));
    EXPECT_FALSE(canReduceResolution(641, 480, 2));
    EXPECT_EQ(interactiveScene(scene, options, 1, half), 1);
    EXPECT_EQ(half.camera.width, 640);
}

TEST(LiveSessionImages, ViewsShowTheirImages) {
    RenderOutput out;
    out.composite = Image(4, 2, 3, 0.5f);
    out.background = Image(4, 2, 3, 1.0f);
    out.delta = Image(4, 2, 3, 0.0f);
    out.delta.setRgb(1, 0, {0.125f, -0.125f, 0.0f});
    out.objectMask = Image(4, 2, 1, 0.0f);
    out.objectMask.at(2, 1, 0) = 1.0f;
    auto pixel = [](const std::vector<uint8_t>& rgb, int x, int y, int c) {
        return rgb[(y * 4 + x) * 3 + c];
    };
    const auto composite = viewPixels(out, View::Composite);
    EXPECT_EQ(pixel(composite, 0, 0, 0), 188);  // sRGB of 0.5
    EXPECT_EQ(pixel(viewPixels(out, View::Background), 3, 1, 2), 255);
    const auto delta = viewPixels(out, View::Delta);
    EXPECT_EQ(pixel(delta, 0, 0, 0), 128);  // no change: grey
    EXPECT_EQ(pixel(delta, 1, 0, 0), 255);  // +0.125 x 4 + 0.5
    EXPECT_EQ(pixel(delta, 1, 0, 1), 0);
    const auto mask = viewPixels(out, View::Mask);
    EXPECT_EQ(pixel(mask, 2, 1, 0), 255);
    EXPECT_EQ(pixel(mask, 0, 0, 0), 0);
    EXPECT_EQ(viewPixels(out, View::Depth).size(), 4u * 2u * 3u);  // no layers: black, not a crash
}

TEST(LiveSessionImages, ThePngIsTheOneDeltagiRenderWrites) {
    const fs::path folder = fs::temp_directory_path() / ("deltagi-live-png-" + std::to_string(::getpid()));
    fs::create_directories(folder);
    Image image(7, 5, 3);
    for (size_t i = 0; i < image.data().size(); ++i)
        image.data()[i] = static_cast<float>(i % 17) / 13.0f - 0.1f;
    writeImage(image, folder / "written.png");
    test::writeText(folder / "encoded.png", encodePng(image));
    const Image a = readImage(folder / "written.png"), b = readImage(folder / "encoded.png");
    ASSERT_EQ(a.data().size(), b.data().size());
    for (size_t i = 0; i < a.data().size(); ++i) EXPECT_EQ(a.data()[i], b.data()[i]);
    const std::string jpeg = encodeJpeg(std::vector<uint8_t>(7 * 5 * 3, 100), 7, 5, 80);
    ASSERT_GT(jpeg.size(), 4u);
    EXPECT_EQ(static_cast<unsigned char>(jpeg[0]), 0xFF);  // SOI
    EXPECT_EQ(static_cast<unsigned char>(jpeg[1]), 0xD8);
    fs::remove_all(folder);
}

// A page's camera frame: a JPEG of the camera's size decodes to its linear pixels (the sRGB bytes decoded as
// image files are, within the JPEG's loss); anything else is refused with one line before its pixels are
// decoded.
TEST(LiveSessionImages, CameraFramesAreJpegsOfTheCamerasSize) {
    std::vector<uint8_t> rgb(32 * 24 * 3);
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 32; ++x) {
            uint8_t* p = &rgb[(y * 32 + x) * 3];
            p[0] = x < 16 ? 40 : 200;
            p[1] = 120;
            p[2] = y < 12 ? 230 : 10;
        }
    const std::string jpeg = encodeJpeg(rgb, 32, 24, 95);
    const Image frame = decodeCameraFrame(jpeg, 32, 24);
    ASSERT_EQ(frame.width(), 32);
    ASSERT_EQ(frame.height(), 24);
    ASSERT_EQ(frame.channels(), 3);
    const std::vector<uint8_t> back = encodeSrgb8(frame);  // the linear pixels, encoded again
    for (int y : {4, 19})
        for (int x : {4, 27})
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(back[(y * 32 + x) * 3 + c], rgb[(y * 32 + x) * 3 + c], 3)
                    << x << "," << y << "," << c;
    const auto refused = [](const std::string& bytes, int w, int h, const std::string& part) {
        try {
            decodeCameraFrame(bytes, w, h);
            ADD_FAILURE() << "accepted: " << part;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("camera frame"), std::string::npos) << what;
            EXPECT_NE(what.find(part), std::string::npos) << what;
            EXPECT_EQ(what.find('\n'), std::string::npos) << what;
        }
    };
    refused(jpeg, 64, 48, "32x24, the scene camera is 64x48");
    refused("", 32, 24, "not a JPEG");
    refused(std::string("\x89PNG\r\n\x1a\n", 8) + std::string(100, 'x'), 32, 24, "not a JPEG");
    refused(jpeg.substr(0, 40), 32, 24, "cannot decode");
    // A header that declares a huge image is refused by its size, not decoded.
    const std::string huge = encodeJpeg(std::vector<uint8_t>(8 * 8 * 3, 50), 8, 8, 80);
    refused(huge, 32, 24, "8x8");
}

TEST_F(LiveSessionTest, DragsPickAsTheRegisteredCameraSees) {
    auto session = tinySession(160, 120);
    glm::mat4 pose = session->scene().camera.worldFromCamera;
    const uint64_t version = session->version();
    const json anchor = session->state()["objects"][0]["anchor"];
    const json documentCamera = session->document()["camera"];
    pose[3] += glm::vec4(0.05f, 0.0f, 0.0f, 0.0f);  // the camera 5 cm to its right (world x)
    session->setCameraPose(pose);
    EXPECT_EQ(session->version(), version);  // not a change of the scene
    const json moved = session->state()["objects"][0]["anchor"];
    EXPECT_GT(std::abs(moved[0].get<double>() - anchor[0].get<double>()), 1.0) << anchor << " " << moved;
    EXPECT_EQ(session->document()["camera"], documentCamera);  // what "save scene" writes: the file's camera
}

}  // namespace
}  // namespace deltagi::live
