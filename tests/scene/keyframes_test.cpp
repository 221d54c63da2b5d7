// Keyframed virtual objects: interpolation (linear, slerp for rotations, held outside the keys), the scene
// file's "keyframes" and its errors, and `deltagi render` over a sequence with a moving object, at once and
// in chunks.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "deltagi/keyframes.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "evaluation/benchmark.h"
#include "evaluation/evaluation.h"
#include "evaluation/temporal.h"
#include "test_errors.h"
#include "test_files.h"
#include "test_scene_json.h"
#include "test_sequence.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::expectContains;
using test::inputErrorOf;

void expectNear(glm::vec3 a, glm::vec3 b, float tolerance = 1e-5f) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// Each channel is interpolated between its own keys (linearly; rotations along the great arc) and held
// before the first and after the last.
TEST(Keyframes, InterpolateEachChannelBetweenItsKeys) {
    ObjectAnimation a;
    a.translate = {{0.0, glm::vec3(0.0f)}, {10.0, glm::vec3(1.0f, 2.0f, 3.0f)}};
    a.rotation = {{0.0, glm::quat(1.0f, 0.0f, 0.0f, 0.0f)},
                  {10.0, glm::angleAxis(glm::radians(90.0f), glm::vec3(0.0f, 1.0f, 0.0f))}};
    a.scale = {{5.0, glm::vec3(2.0f)}};
    const glm::mat4 middle = worldFromObjectAt(a, 5.0);
    expectNear(glm::vec3(middle[3]), {0.5f, 1.0f, 1.5f});
    // x rotated 45 degrees about y, scaled by 2.
    const float h = std::sqrt(0.5f);
    expectNear(glm::vec3(middle * glm::vec4(1, 0, 0, 0)), 2.0f * glm::vec3(h, 0.0f, -h));
    // Held outside the keys.
    expectNear(glm::vec3(worldFromObjectAt(a, -3.0)[3]), glm::vec3(0.0f));
    const glm::mat4 after = worldFromObjectAt(a, 20.0);
    expectNear(glm::vec3(after[3]), {1.0f, 2.0f, 3.0f});
    expectNear(glm::vec3(after * glm::vec4(1, 0, 0, 0)), {0.0f, 0.0f, -2.0f});
    // A quarter of the way: a quarter of the angle (slerp, not a normalized lerp of the matrices).
    const glm::vec3 quarter = glm::vec3(worldFromObjectAt(a, 2.5) * glm::vec4(1, 0, 0, 0));
    EXPECT_NEAR(std::atan2(-quarter.z, quarter.x), glm::radians(22.5f), 1e-5f);
    // No keys: the identity.
    EXPECT_EQ(worldFromObjectAt(ObjectAnimation{}, 3.0), glm::mat4(1.0f));
}

class KeyframesScene : public test::SequenceTest {
  protected:
    // The tiny scene over 4 frames, its box moving by `keyframes`.
    json scene(const json& keyframes) {
        write(transforms(4));
        json doc = test::tinySceneJson(32, 24, {0.9, 0.2, 0.1});
        doc.erase("camera");
        doc["sequence"] = {{"transforms", (dir_ / "transforms.json").string()}};
        doc["virtual"][0].erase("transform");
        doc["virtual"][0]["keyframes"] = keyframes;
        doc["options"].erase("volume");
        return doc;
    }
    std::string errorOf(const json& doc) const {
        return inputErrorOf([&] { loadScene(doc, "scene.json"); });
    }
};

const json kMoving = json::array({{{"frame", 0}, {"translate", {-0.3, 0.15, 0}}},
                                  {{"frame", 3}, {"translate", {0.3, 0.15, 0}}, {"rotate_deg", {0, 90, 0}}}});

// The scene is loaded with its objects at the first frame's pose, in a volume region that holds them at
// every frame.
TEST_F(KeyframesScene, LoadsPosedForTheFirstFrameInARegionForAllFrames) {
    json doc = scene(kMoving);
    Scene s = loadScene(doc, dir_ / "scene.json");
    ASSERT_EQ(s.animations.size(), 1u);
    EXPECT_EQ(s.animations[0].meshCount, 1u);
    expectNear(s.virtuals[0].bounds().center(), {-0.3f, 0.15f, 0.0f});
    ASSERT_TRUE(s.options.volume.center && s.options.volume.size);
    const VolumeRegion region = volumeRegion(s);
    for (double frame : {0.0, 1.5, 3.0}) {
        poseObjects(s, frame);
        const Bounds3f box = s.virtuals[0].bounds();
        for (int a = 0; a < 3; ++a) {
            EXPECT_GE(box.min[a], region.bounds().min[a]) << frame;
            EXPECT_LE(box.max[a], region.bounds().max[a]) << frame;
        }
    }
    // An explicit region is kept as given.
    doc["options"]["volume"] = {{"center", {0, 0, 0}}, {"size", 4}};
    EXPECT_FLOAT_EQ(*loadScene(doc, dir_ / "scene.json").options.volume.size, 4.0f);
    // A sequence that starts later: posed for its first frame; "time" keys in seconds at sequence.fps.
    doc =
        scene({{{"time", 0.0}, {"translate", {0, 0.15, 0}}}, {{"time", 0.4}, {"translate", {0.4, 0.15, 0}}}});
    doc["sequence"]["frames"] = "2:4";
    doc["sequence"]["fps"] = 10;
    s = loadScene(doc, dir_ / "scene.json");
    EXPECT_DOUBLE_EQ(s.frameRate, 10.0);
    expectNear(s.virtuals[0].bounds().center(), {0.2f, 0.15f, 0.0f});
    // Without sequence.fps, the transforms file's "fps", else 30.
    json withFps = transforms(4);
    withFps["fps"] = 24;
    write(withFps);
    doc["sequence"].erase("fps");
    EXPECT_DOUBLE_EQ(loadScene(doc, dir_ / "scene.json").frameRate, 24.0);
    write(transforms(4));
    EXPECT_DOUBLE_EQ(loadScene(doc, dir_ / "scene.json").frameRate, 30.0);
}

TEST_F(KeyframesScene, BadKeyframesNameTheFileAndTheKey) {
    auto keys = [](json a, json b) { return json::array({std::move(a), std::move(b)}); };
    const json t0 = {0, 0.15, 0};
    expectContains(errorOf(scene(keys({{"frame", 3}, {"translate", t0}}, {{"frame", 1}, {"translate", t0}}))),
                   {"scene.json: virtual[0].keyframes[1].frame", "out of order", "after 3"});
    expectContains(errorOf(scene(keys({{"frame", 1}, {"translate", t0}}, {{"frame", 1}, {"translate", t0}}))),
                   {"keyframes[1].frame", "out of order"});
    expectContains(errorOf(scene(keys({{"translate", t0}}, {{"frame", 1}, {"translate", t0}}))),
                   {"virtual[0].keyframes[0]", "missing \"frame\""});
    expectContains(errorOf(scene(keys({{"frame", 0}, {"time", 0}, {"translate", t0}},
                                      {{"frame", 1}, {"translate", t0}}))),
                   {"keyframes[0].time", "not both"});
    expectContains(errorOf(scene(keys({{"frame", 0}, {"translate", t0}}, {{"time", 1}, {"translate", t0}}))),
                   {"keyframes[1].time", "every keyframe"});
    expectContains(errorOf(scene(keys({{"frame", 0}}, {{"frame", 1}, {"translate", t0}}))),
                   {"keyframes[0]", "at least one of"});
    expectContains(errorOf(scene(keys({{"frame", 0}, {"scale", 0}}, {{"frame", 1}, {"translate", t0}}))),
                   {"keyframes[0].scale", "non-zero"});
    expectContains(
        errorOf(scene(keys({{"frame", 0}, {"scale", {1, 1, 1}}}, {{"frame", 2}, {"scale", {1, -1, 1}}}))),
        {"keyframes[1].scale", "y factor changes sign"});
    expectContains(errorOf(scene(keys({{"frame", 0}, {"scale", 1e-20}}, {{"frame", 1}, {"translate", t0}}))),
                   {"keyframes[0]", "invertible"});
    expectContains(
        errorOf(scene(keys({{"frame", 0}, {"translate", {1e39, 0, 0}}}, {{"frame", 1}, {"translate", t0}}))),
        {"keyframes[0].translate[0]", "finite"});
    expectContains(
        errorOf(scene(keys({{"frame", -1}, {"translate", t0}}, {{"frame", 1}, {"translate", t0}}))),
        {"keyframes[0].frame", "expected a number in"});
    expectContains(errorOf(scene(keys({{"frame", 0}, {"translate", t0}, {"rotate", 5}}, {{"frame", 1}}))),
                   {"keyframes[0].rotate"});
    expectContains(errorOf(scene(json::array())), {"virtual[0].keyframes", "at least one keyframe"});
    json doc = scene(kMoving);
    doc["virtual"][0]["transform"] = {{"translate", t0}};
    expectContains(errorOf(doc), {"virtual[0].keyframes", "not both"});
    doc = scene(kMoving);
    doc["scene"][0]["keyframes"] = kMoving;
    expectContains(errorOf(doc), {"scene[0].keyframes", "only virtual objects"});
    json still = test::tinySceneJson(32, 24, {0.5, 0.5, 0.5});
    still["virtual"][0].erase("transform");
    still["virtual"][0]["keyframes"] = kMoving;
    expectContains(errorOf(still), {"virtual[0].keyframes", "\"sequence\""});
    doc = scene(kMoving);
    doc["sequence"]["fps"] = 0;
    expectContains(errorOf(doc), {"sequence.fps", "expected a number in"});
    doc["sequence"].erase("fps");
    json badFps = transforms(4);
    badFps["fps"] = "thirty";
    write(badFps);
    expectContains(errorOf(doc), {"transforms.json: fps", "expected a number"});
}

// The object moves from frame to frame; rendering frames 2:4 alone gives the frames of the whole run.
TEST_F(KeyframesScene, ChunksRenderTheFramesOfTheWholeRun) {
    const fs::path sceneFile = write(scene(kMoving), "scene.json");
    const std::string render = "render " + sceneFile.string() + " -q ";
    ASSERT_EQ(runCli(render + "-o " + (dir_ / "all_####.exr").string() + " --layers " +
                     (dir_ / "layers_#.exr").string()),
              0)
        << errors();
    ASSERT_EQ(runCli(render + "--frames 2:4 -o " + (dir_ / "part_####.exr").string()), 0) << errors();
    ASSERT_EQ(runCli(render + "--frames 3:4 -o " + (dir_ / "last_####.exr").string()), 0) << errors();
    float largest = 0.0f;
    for (const auto& [whole, chunk] :
         {std::pair{"all_0002.exr", "part_0002.exr"}, std::pair{"all_0003.exr", "part_0003.exr"},
          std::pair{"all_0003.exr", "last_0003.exr"}}) {
        const Image a = readImage(dir_ / whole), b = readImage(dir_ / chunk);
        ASSERT_EQ(a.data().size(), b.data().size());
        for (size_t k = 0; k < a.data().size(); ++k)
            largest = std::max(largest, std::abs(a.data()[k] - b.data()[k]));
    }
    EXPECT_LE(largest, 1e-4f);
    // The box moved: its coverage (the object layer's alpha) differs between the first and the last frame.
    auto coverage = [&](int frame) {
        for (const NamedImage& layer : readLayers(dir_ / ("layers_" + std::to_string(frame) + ".exr")))
            if (layer.name == "object") return layer.image;
        ADD_FAILURE() << "no object layer";
        return Image();
    };
    const Image first = coverage(0), last = coverage(3);
    ASSERT_EQ(first.data().size(), last.data().size());
    double sumFirst = 0.0, moved = 0.0;
    for (size_t p = 0; p < first.pixelCount(); ++p) {
        sumFirst += first.data()[p * 4 + 3];
        moved += std::abs(first.data()[p * 4 + 3] - last.data()[p * 4 + 3]);
    }
    EXPECT_GT(sumFirst, 5.0);  // the box is in view
    EXPECT_GT(moved, 0.5 * sumFirst);
}

// `stability` over a sequence measures the sequence: each frame's camera, and each object's own motion (a
// keyframed one and one that stays), followed from frame to frame.
TEST_F(KeyframesScene, StabilityFollowsTheSequencesCamerasAndEachObjectsMotion) {
    json doc = scene(kMoving);
    json view = transforms(4, 128, 96);  // a wider view, and larger boxes: patches of 4 x 4 pixels on them
    view["fl_x"] = view["fl_y"] = 60.0;
    view["cx"] = 64.0;
    view["cy"] = 48.0;
    write(view);
    doc["virtual"][0]["shape"]["size"] = {0.5, 0.5, 0.5};
    json still = doc["virtual"][0];
    still.erase("keyframes");
    still["name"] = "still box";
    still["transform"] = {{"translate", {0.0, 0.15, -0.6}}};
    doc["virtual"].push_back(still);
    Scene s = loadScene(doc, dir_ / "scene.json");
    const Camera camera = s.camera;
    const std::vector<glm::vec3> moving = s.virtuals[0].positions;
    const MotionFrames m = renderSequence(s);
    ASSERT_EQ(m.frames.size(), 4u);
    EXPECT_EQ(m.indices, (std::vector<int>{0, 1, 2, 3}));
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.cameras[i].position().x, 0.1f * i, 1e-6f);
    // Put back as loaded.
    EXPECT_EQ(s.camera, camera);
    EXPECT_EQ(s.virtuals[0].positions, moving);
    // Two groups: the keyframed box (from -0.3 to 0.3 in x, a quarter turn) and the box that stays.
    ASSERT_EQ(m.objectGroups.size(), 2u);
    const glm::vec3 end = m.objectGroups[0].poses[3] * glm::vec4(-0.3f, 0.15f, 0.0f, 1.0f);
    EXPECT_NEAR(end.x, 0.3f, 1e-5f);
    EXPECT_EQ(m.objectGroups[1].poses[3], glm::mat4(1.0f));
    ASSERT_EQ(m.objectGroups[0].bounds.size(), 4u);
    EXPECT_NEAR(m.objectGroups[0].bounds[3].center().x, 0.3f, 1e-5f);
    const TemporalFigures followed = temporalInstability(m);
    EXPECT_TRUE(followed.followsSurfaces);
    EXPECT_GT(followed.realSamples, 0u);
    EXPECT_GT(followed.objectSamples, 0u);
    // Taken as still, the moving box's points are not found again: far fewer object samples.
    MotionFrames asStill = m;
    asStill.objectGroups.resize(1);
    asStill.objectGroups[0].poses.assign(4, glm::mat4(1.0f));
    asStill.objectGroups[0].bounds.clear();
    EXPECT_LT(2 * temporalInstability(asStill).objectSamples, followed.objectSamples);
    EXPECT_THROW(renderSequence(s, 2), InputError);

    // The command: the sequence's frames, and no synthetic motion with it.
    const fs::path file = write(doc, "scene.json");
    ASSERT_EQ(runCli("stability " + file.string() + " > " + (dir_ / "out.txt").string()), 0) << errors();
    expectContains(test::readText(dir_ / "out.txt"), {"4 frames 0:4 of", "following the surface points"});
    EXPECT_EQ(runCli("stability " + file.string() + " --camera-step 1"), 1);
    expectContains(errors(), {"--camera-step", "not with a \"sequence\""});
}

// `bench` over a sequence times the sequence: each frame's camera, photo (read before the frame) and
// keyframed objects, in order, from its first frame again after its last.
TEST_F(KeyframesScene, BenchPlaysTheSequence) {
    Scene s = loadScene(scene(kMoving), dir_ / "scene.json");
    const Camera camera = s.camera;
    const std::vector<glm::vec3> moving = s.virtuals[0].positions;
    BenchOptions options;
    options.warmup = 1;
    options.frames = 4;  // 5 in all over the 4 frames: the first again at the end
    std::vector<int> measured;
    const BenchResult r = runBenchmark(s, options, [&](int frame, double) { measured.push_back(frame); });
    EXPECT_EQ(measured, (std::vector<int>{0, 1, 2, 3}));
    EXPECT_EQ(r.sequenceFrames, 4);
    expectContains(r.sequence, {"frames 0:4 of", "transforms.json"});
    expectContains(benchTable(r), {"the tracked sequence's frames 0:4", "from its first frame again"});
    EXPECT_EQ(benchToJson(r)["sequence"], r.sequence);
    EXPECT_EQ(s.camera, camera);
    EXPECT_EQ(s.virtuals[0].positions, moving);
    // Each frame's photo is read as the frame comes: a photo gone since the scene was loaded is named.
    fs::remove(dir_ / "images/frame_2.png");
    expectContains(inputErrorOf([&] { runBenchmark(s, options); }), {"frames[2].file_path"});
    options.live = true;
    expectContains(inputErrorOf([&] { runBenchmark(s, options); }), {"--live", "not with a \"sequence\""});
}

// `eval` over a sequence scores every frame against its own reference (its camera, photo and keyframed
// objects), with their mean and worst; the other one-image commands say which frame they take.
TEST_F(KeyframesScene, EvalScoresEveryFrame) {
    json doc = scene(kMoving);
    doc["sequence"]["frames"] = "1:4";
    Scene s = loadScene(doc, dir_ / "scene.json");
    const Camera camera = s.camera;
    ReferenceOptions reference;
    reference.samplesPerPixel = 4;
    std::vector<int> progress;
    const SequenceEvaluation e =
        evaluateSequence(s, reference, [&](int done, int) { progress.push_back(done); });
    ASSERT_EQ(e.frames.size(), 3u);
    EXPECT_EQ(progress, (std::vector<int>{1, 2, 3}));
    double sum = 0.0, worst = 0.0;
    for (size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(e.frames[k].index, static_cast<int>(k) + 1);
        EXPECT_TRUE(std::isfinite(e.frames[k].dgi.deltaRelError));
        EXPECT_GT(e.frames[k].referenceMs, 0.0);
        sum += e.frames[k].dgi.deltaRelError;
        worst = std::max(worst, e.frames[k].dgi.deltaRelError);
    }
    EXPECT_NEAR(e.mean.deltaRelError, sum / 3.0, 1e-12);
    EXPECT_EQ(e.worst.deltaRelError, worst);
    // The frames differ: the camera and the box move.
    EXPECT_NE(e.frames[0].dgi.compositeRmse, e.frames[2].dgi.compositeRmse);
    EXPECT_EQ(s.camera, camera);
    const json figures = json::parse(sequenceEvaluationToJson(e, s).dump());
    expectContains(figures["sequence"].get<std::string>(), {"frames 1:4 of"});
    EXPECT_EQ(figures["frames"].size(), 3u);
    EXPECT_EQ(figures["frames"][2]["index"], 3);
    EXPECT_EQ(figures["worst"]["delta_rel_error"], worst);

    const fs::path file = write(doc, "scene.json");
    ASSERT_EQ(runCli("eval " + file.string() + " --spp 2 --json " + (dir_ / "eval.json").string()), 0)
        << errors();
    EXPECT_EQ(json::parse(test::readText(dir_ / "eval.json"))["frames"].size(), 3u);
    EXPECT_EQ(runCli("eval " + file.string() + " --spp 2 --json " + (dir_ / "e.json").string() + " --aov " +
                     (dir_ / "aov").string()),
              1);
    expectContains(errors(), {"--aov", "not with a \"sequence\""});
    ASSERT_EQ(runCli("reference " + file.string() + " --spp 1 -q -o " + (dir_ / "ref.exr").string()), 0);
    expectContains(errors(), {"the sequence's first frame, frame 1 of", "sequence.frames=2:3"});
}

}  // namespace
}  // namespace deltagi
