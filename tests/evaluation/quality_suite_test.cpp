// The quality suite: the suite file, the reference cache (reused while nothing the path tracer reads changes,
// rendered again when something does), the equal-error fit on numbers whose answer is known, the split of
// the delta error, and the table; `deltagi eval --suite` end to end on a two-scene suite of tiny scenes.
#include "evaluation/quality_suite.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "test_cli.h"
#include "test_files.h"
#include "test_paths.h"
#include "test_scene_json.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---- The equal-error fit ----

TEST(EqualErrorFit, RecoversTheNoiseConstantOfExactPoints) {
    const double c = 1.37;
    const int referenceSpp = 256;
    const std::vector<int> spp{1, 4, 16};
    std::vector<double> errors;
    for (const int n : spp) errors.push_back(c * std::sqrt(1.0 / n - 1.0 / referenceSpp));
    EXPECT_NEAR(noiseConstantOf(spp, errors, referenceSpp), c, 1e-12);
    for (const double point : pointNoiseConstants(spp, errors, referenceSpp)) EXPECT_NEAR(point, c, 1e-12);
}

TEST(EqualErrorFit, TakesThePointWithTheMostSamples) {
    // Figures of few samples that fall as 1/spp (caustics), not 1/sqrt(spp): the largest point's c, whatever
    // the order of the points.
    const double c = 0.8;
    const std::vector<int> spp{16, 1, 256, 4};
    const std::vector<double> errors{
        4.0 * c * std::sqrt(1.0 / 16 - 1.0 / 1024), 64.0 * c * std::sqrt(1.0 - 1.0 / 1024),
        c * std::sqrt(1.0 / 256 - 1.0 / 1024), 16.0 * c * std::sqrt(1.0 / 4 - 1.0 / 1024)};
    EXPECT_NEAR(noiseConstantOf(spp, errors, 1024), c, 1e-12);
    const std::vector<double> points = pointNoiseConstants(spp, errors, 1024);
    ASSERT_EQ(points.size(), 4u);
    EXPECT_NEAR(points[0], 4.0 * c, 1e-12);
    EXPECT_NEAR(points[1], 64.0 * c, 1e-12);
    // The suite says so: the first point (16 spp) is 4 times c.
    EXPECT_EQ(overstatingPoint(spp, errors, 1024), std::optional<size_t>(0));
    // Points that scatter by 10 % around the curve are well behaved.
    const std::vector<double> scattered{
        1.1 * c * std::sqrt(1.0 / 16 - 1.0 / 1024), 0.9 * c * std::sqrt(1.0 - 1.0 / 1024),
        c * std::sqrt(1.0 / 256 - 1.0 / 1024), c * std::sqrt(1.0 / 4 - 1.0 / 1024)};
    EXPECT_FALSE(overstatingPoint(spp, scattered, 1024).has_value());
}

TEST(EqualErrorFit, LeavesOutPointsAtOrAboveTheReferenceAndBadErrors) {
    const std::vector<int> spp{1, 4, 64, 16};
    const std::vector<double> errors{2.0 * std::sqrt(1.0 - 1.0 / 64), std::nan(""), 0.5, 0.0};
    EXPECT_NEAR(noiseConstantOf(spp, errors, 64), 2.0, 1e-12);
    EXPECT_TRUE(std::isnan(noiseConstantOf(std::vector<int>{64}, std::vector<double>{0.3}, 64)));
    const std::vector<double> points = pointNoiseConstants(spp, errors, 64);
    EXPECT_TRUE(std::isnan(points[1]) && std::isnan(points[2]) && std::isnan(points[3]));
}

TEST(EqualErrorFit, EqualErrorSamplesTakeTheReferenceNoiseOut) {
    // c = 1: an error of 0.1 is what 100 samples give against the truth.
    EXPECT_NEAR(equalErrorSamples(1.0, 0.1, 0.0), 100.0, 1e-9);
    // Measured against a reference whose noise is 0.05, the error holds that as well: sqrt(0.1² + 0.05²).
    EXPECT_NEAR(equalErrorSamples(1.0, std::sqrt(0.01 + 0.0025), 0.05), 100.0, 1e-6);
    // Within the reference's noise: DGI is as good as any number of samples can tell.
    EXPECT_TRUE(std::isinf(equalErrorSamples(1.0, 0.04, 0.05)));
    EXPECT_TRUE(std::isnan(equalErrorSamples(std::nan(""), 0.1, 0.05)));
}

// ---- The split of the delta error, on images whose answer is known ----

Image filled(glm::vec3 value, int width = 2) {
    Image image(width, 1, 3);
    for (int x = 0; x < width; ++x) image.setRgb(x, 0, value);
    return image;
}

TEST(DeltaSplit, ComparesEachPartOverItsOwnBackground) {
    // Two real pixels, background 0.5 (with the indirect light of the real scene); the true change is -0.3
    // of which -0.2 is shadow (direct light). The direct-only reference has its own background, 0.4 (no
    // indirect light): its change is still -0.2.
    Evaluation e;
    e.classes.width = 2;
    e.classes.height = 1;
    e.classes.classes = {PixelClass::RealLit, PixelClass::RealShadowed};
    e.reference.background = filled(glm::vec3(0.5f));
    e.reference.composite = filled(glm::vec3(0.2f));
    e.shadowOnlyComposite = filled(glm::vec3(0.35f));  // DGI's shadow: -0.15, 0.05 too little
    e.dgiRender.composite = filled(glm::vec3(0.3f));   // DGI's indirect: -0.05, the truth's -0.1
    ReferenceOutput direct;
    direct.background = filled(glm::vec3(0.4f));
    direct.composite = filled(glm::vec3(0.2f));
    direct.objectMask = Image(2, 1, 1);

    const DeltaSplit split = splitDeltaError(e, direct);
    EXPECT_NEAR(split.shadowPart, 0.05 / 0.3, 1e-6);
    EXPECT_NEAR(split.indirectPart, 0.05 / 0.3, 1e-6);
    EXPECT_NEAR(split.referenceShadowShare, 0.2 / 0.3, 1e-6);
    EXPECT_NEAR(split.referenceIndirectShare, 0.1 / 0.3, 1e-6);

    // Object pixels do not count.
    e.classes.classes[1] = PixelClass::Object;
    EXPECT_NEAR(splitDeltaError(e, direct).shadowPart, 0.05 / 0.3, 1e-6);
}

TEST(DeltaSplit, AReferenceMovesOntoAnotherBackgroundByItsRealShare) {
    ReferenceOutput r;
    r.background = filled(glm::vec3(0.4f), 3);
    r.composite = filled(glm::vec3(0.3f), 3);
    r.objectMask = Image(3, 1, 1);
    r.objectMask.at(1, 0, 0) = 1.0f;  // the object: its radiance stays
    r.objectMask.at(2, 0, 0) = 0.5f;  // the silhouette: half moves
    const Image moved = onBackground(r, filled(glm::vec3(0.6f), 3));
    EXPECT_NEAR(moved.at(0, 0, 0), 0.5f, 1e-6f);
    EXPECT_NEAR(moved.at(1, 0, 0), 0.3f, 1e-6f);
    EXPECT_NEAR(moved.at(2, 0, 0), 0.4f, 1e-6f);
}

// ---- Suites of tiny scenes ----

// The tiny test scene at 32x24 with a grey box of `boxAlbedo`.
json tinyScene(double boxAlbedo) {
    return test::tinySceneJson(32, 24, {boxAlbedo, boxAlbedo, boxAlbedo});
}

// ||a - b|| over every value of two images of one size.
double distance(const Image& a, const Image& b) {
    double sum = 0.0;
    for (size_t i = 0; i < a.data().size(); ++i) sum += std::pow(double(a.data()[i]) - b.data()[i], 2);
    return std::sqrt(sum);
}

// The mean of two renders from independent random sequences is as far from the truth (a render of 32 times
// their samples) as referenceNoiseOf() says from their distance to each other (0.93-1.02 times over eight
// sets of seeds at 96x72). One render alone is sqrt(2) times further: a wrong factor fails.
TEST(ReferenceNoise, TwoIndependentRendersMeasureTheirMeansNoise) {
    const fs::path dir = fs::temp_directory_path() / ("deltagi_noise_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "scene.json") << test::tinySceneJson(96, 72, {0.5, 0.5, 0.5}).dump();
    const Scene scene = loadScene(dir / "scene.json");
    fs::remove_all(dir);
    ReferenceOptions options;
    options.samplesPerPixel = 8;
    const ReferenceOutput first = renderReference(scene, options);
    options.seed = 1;
    const ReferenceOutput second = renderReference(scene, options);
    options.seed = 2;
    options.samplesPerPixel = 256;
    const ReferenceOutput truth = renderReference(scene, options);

    const ReferenceOutput mean = meanOfReferences(first, second);
    EXPECT_EQ(mean.samplesPerPixel, 16);
    EXPECT_NEAR(mean.delta.at(5, 7, 1), 0.5f * (first.delta.at(5, 7, 1) + second.delta.at(5, 7, 1)), 1e-6f);
    const double norm = distance(truth.delta, Image(96, 72, 3));
    ASSERT_GT(norm, 0.0);
    const double predicted = referenceNoiseOf(distance(first.delta, second.delta) / norm);
    const double actual = distance(mean.delta, truth.delta) / norm;
    ASSERT_GT(actual, 0.0);
    EXPECT_GT(predicted / actual, 0.8) << predicted << " against " << actual;
    EXPECT_LT(predicted / actual, 1.2) << predicted << " against " << actual;
}

using test::readText;

class QualitySuiteTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("deltagi_suite_test_" + std::string(test->name()) + "_" + std::to_string(getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ignored;
        fs::remove_all(dir_, ignored);
    }

    fs::path write(const std::string& name, const std::string& text) const {
        const fs::path path = dir_ / name;
        std::ofstream(path, std::ios::binary) << text;
        return path;
    }

    // Two scenes (a grey and a white box), 4 spp, the fit from 1 and 2 spp.
    fs::path writeSuite() const {
        write("grey.json", tinyScene(0.5).dump(2));
        write("white.json", tinyScene(0.9).dump(2));
        return write("suite.json", R"({"seed": 3, "fit_spp": [1, 2], "scenes": [
            {"scene": "grey.json", "spp": 4},
            {"scene": "white.json", "name": "white box", "spp": 4, "direct_spp": 2,
             "set": ["options.volume.resolution=32"]}]})");
    }

    SuiteRunOptions runOptions() const {
        SuiteRunOptions options;
        options.cacheFolder = dir_ / "refs";
        return options;
    }

    fs::path dir_;
};

TEST_F(QualitySuiteTest, ReadsTheSuiteFile) {
    const QualitySuite suite = loadSuite(writeSuite());
    EXPECT_EQ(suite.seed, 3u);
    EXPECT_EQ(suite.fitSamples, (std::vector<int>{1, 2}));
    ASSERT_EQ(suite.scenes.size(), 2u);
    EXPECT_EQ(suite.scenes[0].name, "grey");
    EXPECT_EQ(suite.scenes[0].file, dir_ / "grey.json");
    EXPECT_EQ(suite.scenes[1].name, "white box");
    EXPECT_EQ(suite.scenes[0].directSamplesPerPixel, 0);  // spp / kDirectSamplesDivisor
    EXPECT_EQ(suite.scenes[1].samplesPerPixel, 4);
    EXPECT_EQ(suite.scenes[1].directSamplesPerPixel, 2);
    EXPECT_EQ(suite.scenes[1].overrides, (std::vector<std::string>{"options.volume.resolution=32"}));
}

TEST_F(QualitySuiteTest, AFolderIsASuiteOfItsSceneFiles) {
    writeSuite();
    fs::create_directories(dir_ / "folder");
    fs::copy_file(dir_ / "white.json", dir_ / "folder" / "b.json");
    fs::copy_file(dir_ / "grey.json", dir_ / "folder" / "a.json");
    const QualitySuite suite = loadSuite(dir_ / "folder");
    ASSERT_EQ(suite.scenes.size(), 2u);
    EXPECT_EQ(suite.scenes[0].name, "a");
    EXPECT_EQ(suite.scenes[1].samplesPerPixel, kDefaultSuiteSamples);
}

// Each bad suite fails with an InputError that names the file and the key.
TEST_F(QualitySuiteTest, BadSuitesNameTheFileAndKey) {
    write("grey.json", tinyScene(0.5).dump());
    const auto expectError = [&](const std::string& text, const std::string& key) {
        const fs::path file = write("bad.json", text);
        try {
            loadSuite(file);
            ADD_FAILURE() << "no error for " << text;
        } catch (const InputError& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find("bad.json"), std::string::npos) << message;
            EXPECT_NE(message.find(key), std::string::npos) << message;
        }
    };
    expectError(R"({"scenes": [{"scene": "grey.json", "spp": "many"}]})", "scenes[0].spp");
    expectError(R"({"scenes": [{"scene": "grey.json", "spp": 0}]})", "scenes[0].spp");
    expectError(R"({"scenes": [{"scene": "missing.json"}]})", "scenes[0].scene");
    expectError(R"({"scenes": [{"scene": "grey.json", "spp": 4, "direct_spp": 8}]})", "scenes[0].direct_spp");
    expectError(R"({"scenes": [{"scene": "grey.json", "sp": 4}]})", "scenes[0].sp");
    expectError(R"({"scenes": [{"scene": "grey.json", "set": ["no equals sign"]}]})", "scenes[0].set[0]");
    expectError(R"({"scenes": []})", "scenes");
    expectError(R"({"fit_spp": 4, "scenes": [{"scene": "grey.json"}]})", "fit_spp");
    expectError(R"({"scenes": [{"scene": "grey.json"}])", "not valid JSON");
    EXPECT_THROW(loadSuite(dir_ / "no-such-suite.json"), InputError);
}

TEST_F(QualitySuiteTest, TheCacheIsReusedUntilTheSceneChanges) {
    const QualitySuite suite = loadSuite(writeSuite());
    const SuiteScene& grey = suite.scenes[0];
    // full and direct 4 spp, each from seeds 3 and 4, full 1 and 2 spp: the last two stored from the first
    // samples of the first.
    const SceneQuality first = evaluateSuiteScene(suite, grey, runOptions());
    EXPECT_EQ(first.cacheHits, 2u);
    EXPECT_EQ(first.cacheMisses, 4u);
    EXPECT_TRUE(fs::is_regular_file(dir_ / "refs" / first.key / "full-4spp-seed4" / "reference.json"));
    EXPECT_GT(first.referenceNoise, 0.0);

    const SceneQuality again = evaluateSuiteScene(suite, grey, runOptions());
    EXPECT_EQ(again.cacheHits, 6u);
    // A cache that holds the first render only: the second is rendered and the mean made of a read and a
    // rendered reference, whose mask has other channels.
    fs::remove_all(dir_ / "refs" / first.key / "full-4spp-seed4");
    const SceneQuality mixed = evaluateSuiteScene(suite, grey, runOptions());
    EXPECT_EQ(mixed.cacheMisses, 1u);
    EXPECT_EQ(mixed.dgi.deltaRelError, first.dgi.deltaRelError);
    EXPECT_EQ(again.cacheMisses, 0u);
    EXPECT_EQ(again.key, first.key);
    EXPECT_EQ(again.dgi.deltaRelError, first.dgi.deltaRelError);  // the same images, read back exactly
    EXPECT_EQ(again.shadowPart, first.shadowPart);
    EXPECT_EQ(again.noiseConstant, first.noiseConstant);
    EXPECT_EQ(again.referenceMs, first.referenceMs);  // the time of the render, kept with it

    // DGI's options are not the path tracer's business: the references stay.
    json scene = tinyScene(0.5);
    scene["options"]["volume"]["resolution"] = 32;
    write("grey.json", scene.dump(2));
    EXPECT_EQ(evaluateSuiteScene(suite, grey, runOptions()).cacheMisses, 0u);

    // The object's material changes the truth: everything is rendered again, under another key.
    scene["virtual"][0]["material"]["albedo"] = {0.2, 0.2, 0.2};
    write("grey.json", scene.dump(2));
    const SceneQuality changed = evaluateSuiteScene(suite, grey, runOptions());
    EXPECT_NE(changed.key, first.key);
    EXPECT_EQ(changed.cacheHits, 2u);
    EXPECT_EQ(changed.cacheMisses, 4u);

    // More samples: only the full and direct references are rendered again, the fit's are kept.
    SuiteRunOptions moreSamples = runOptions();
    moreSamples.samplesPerPixel = 8;
    const SceneQuality more = evaluateSuiteScene(suite, grey, moreSamples);
    EXPECT_EQ(more.cacheMisses, 4u);
    EXPECT_EQ(more.cacheHits, 2u);
    EXPECT_EQ(more.referenceSpp, 8);
    // The path tracer's time per sample is the largest fit reference's (2 samples, kept), whatever the full
    // one's samples and time.
    EXPECT_EQ(changed.timedSpp, 2);
    const double fitMs =
        json::parse(readText(dir_ / "refs" / changed.key / "full-2spp-seed3" / "reference.json"))["ms"];
    EXPECT_EQ(changed.pathTracerMsPerSpp, fitMs / 2);
    EXPECT_EQ(changed.equalErrorMs, changed.equalErrorSpp * changed.pathTracerMsPerSpp);
    EXPECT_EQ(more.timedSpp, 2);
    EXPECT_EQ(more.pathTracerMsPerSpp, changed.pathTracerMsPerSpp);
}

// A reference of more samples goes on from the sums an earlier one kept: the same image as a render of all
// its samples at once; without usable sums (a damaged file) it renders them all.
TEST_F(QualitySuiteTest, AReferenceGoesOnFromAnEarlierOnesSums) {
    write("grey.json", tinyScene(0.5).dump(2));
    const Scene scene = loadScene(dir_ / "grey.json");
    ReferenceOptions four, seven;
    four.samplesPerPixel = 4;
    seven.samplesPerPixel = 7;
    const fs::path a = dir_ / "refs" / "full-4spp-seed0", b = dir_ / "refs" / "full-7spp-seed0";
    ASSERT_TRUE(cachedReference(scene, four, a).resumedFrom.empty());
    ASSERT_TRUE(fs::is_regular_file(a / "sums.bin"));
    const ReferenceOutput whole = renderReference(scene, seven);
    const CachedReference more = cachedReference(scene, seven, b, {}, {}, {{4, a}, {2, dir_ / "none"}});
    EXPECT_EQ(more.resumedFrom, a);
    EXPECT_EQ(more.output.samplesPerPixel, 7);
    // Its time is that of all 7 samples: the 4 of the earlier render, kept with it, and the 3 added.
    const double earlierMs = nlohmann::json::parse(std::ifstream(a / "reference.json"))["ms"].get<double>();
    EXPECT_GT(earlierMs, 0.0);
    EXPECT_EQ(more.resumedMs, earlierMs);
    EXPECT_GT(more.output.totalMs, earlierMs);
    EXPECT_EQ(nlohmann::json::parse(std::ifstream(b / "reference.json"))["ms"].get<double>(),
              more.output.totalMs);
    EXPECT_EQ(more.output.sums.values, whole.sums.values);
    EXPECT_TRUE(std::ranges::equal(more.output.composite.data(), whole.composite.data()));
    EXPECT_TRUE(std::ranges::equal(more.output.objectMask.data(), whole.objectMask.data()));

    // Truncated sums: rendered from the start, to the same image.
    fs::remove_all(b);
    fs::resize_file(a / "sums.bin", fs::file_size(a / "sums.bin") / 2);
    const CachedReference again = cachedReference(scene, seven, b, {}, {}, {{4, a}});
    EXPECT_TRUE(again.resumedFrom.empty());
    EXPECT_TRUE(std::ranges::equal(again.output.composite.data(), whole.composite.data()));
}

// A render cut short goes on from its last checkpoint, to the same image; the checkpoints are gone once the
// reference is stored, and a checkpoint never replaces a reference already in the cache.
TEST_F(QualitySuiteTest, AnInterruptedReferenceGoesOnFromItsLastCheckpoint) {
    write("grey.json", tinyScene(0.5).dump(2));
    const Scene scene = loadScene(dir_ / "grey.json");
    ReferenceOptions six;
    six.samplesPerPixel = 6;
    six.checkpointSeconds = 1e-9;  // after every pass
    const fs::path refs = dir_ / "refs";
    const auto checkpointFolder = [&](int n) { return refs / fmt::format("full-{}spp-seed0", n); };
    const fs::path target = checkpointFolder(6);
    // A reference of 2 samples is in the cache already: the checkpoint of pass 2 leaves it alone.
    ReferenceOptions two;
    two.samplesPerPixel = 2;
    ASSERT_FALSE(cachedReference(scene, two, checkpointFolder(2)).hit);
    const std::string twoMeta = readText(checkpointFolder(2) / "reference.json");

    struct Interrupted {};
    EXPECT_THROW(cachedReference(
                     scene, six, target,
                     [](int done, int, double) {
                         if (done == 4) throw Interrupted{};
                     },
                     {}, {}, checkpointFolder),
                 Interrupted);
    EXPECT_FALSE(fs::exists(target / "reference.json"));
    EXPECT_EQ(readText(checkpointFolder(2) / "reference.json"), twoMeta);
    EXPECT_FALSE(fs::exists(checkpointFolder(1)));  // only the newest checkpoint is kept
    EXPECT_FALSE(fs::exists(checkpointFolder(3)));
    ASSERT_TRUE(fs::is_regular_file(checkpointFolder(4) / "sums.bin"));
    EXPECT_TRUE(json::parse(readText(checkpointFolder(4) / "reference.json")).value("checkpoint", false));

    std::vector<int> passes;
    const CachedReference resumed = cachedReference(
        scene, six, target, [&](int done, int, double) { passes.push_back(done); }, {},
        {{2, checkpointFolder(2)}, {4, checkpointFolder(4)}}, checkpointFolder);
    EXPECT_EQ(resumed.resumedFrom, checkpointFolder(4));
    EXPECT_EQ(passes, (std::vector<int>{5, 6}));
    ReferenceOptions plain;
    plain.samplesPerPixel = 6;
    const ReferenceOutput whole = renderReference(scene, plain);
    EXPECT_EQ(resumed.output.sums.values, whole.sums.values);
    EXPECT_TRUE(std::ranges::equal(resumed.output.composite.data(), whole.composite.data()));
    EXPECT_TRUE(fs::exists(target / "reference.json"));
    EXPECT_FALSE(fs::exists(checkpointFolder(4)));  // the checkpoint it went on from
    EXPECT_FALSE(fs::exists(checkpointFolder(5)));  // its own
    EXPECT_EQ(readText(checkpointFolder(2) / "reference.json"), twoMeta);
}

TEST_F(QualitySuiteTest, TheKeyFollowsTheContentOfReferencedFiles) {
    const std::string mesh = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    write("tri.obj", mesh);
    json scene = tinyScene(0.5);
    scene["scene"].push_back({{"file", "tri.obj"}});
    const fs::path file = write("mesh.json", scene.dump());
    const std::string key = referenceContentKey(file, {});
    EXPECT_EQ(referenceContentKey(file, {"options.volume.resolution=64"}), key);
    EXPECT_NE(referenceContentKey(file, {"lights.0.intensity=4"}), key);
    write("tri.obj", "v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_NE(referenceContentKey(file, {}), key);
    write("tri.obj", mesh);
    EXPECT_EQ(referenceContentKey(file, {}), key);
}

// Textures count too: an OBJ's MTL maps and a glTF's images and buffers, which the scene file never names.
TEST_F(QualitySuiteTest, TheKeyFollowsTexturesAndBuffersOfMeshFiles) {
    write("tri.obj",
          "mtllib tri.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n");
    write("tri.mtl", "newmtl m\nKd 1 1 1\nmap_Kd -bm 1 checker.png\n");
    write("checker.png", "first");
    write("thing.gltf", R"({"asset": {"version": "2.0"}, "buffers": [{"uri": "thing.bin", "byteLength": 4}],
                            "images": [{"uri": "colour.png"}, {"uri": "data:image/png;base64,AAAA"}]})");
    write("thing.bin", "abcd");
    write("colour.png", "first");
    json scene = tinyScene(0.5);
    scene["scene"].push_back({{"file", "tri.obj"}});
    scene["virtual"].push_back({{"file", "thing.gltf"}});
    const fs::path file = write("textured.json", scene.dump());
    const std::string key = referenceContentKey(file, {});
    for (const char* dependency : {"checker.png", "thing.bin", "colour.png"}) {
        write(dependency, "second");
        EXPECT_NE(referenceContentKey(file, {}), key) << dependency;
        write(dependency, dependency == std::string("thing.bin") ? "abcd" : "first");
        EXPECT_EQ(referenceContentKey(file, {}), key) << dependency;
    }
}

TEST_F(QualitySuiteTest, ABlackObjectOnAFloorChangesOnlyTheDirectLight) {
    // Nothing reaches the floor by way of a black box, and a plane does not light itself: the reference's
    // change is all shadow (direct light), the indirect share 0.
    write("black.json", tinyScene(0.0).dump());
    const QualitySuite suite = loadSuite(
        write("suite.json",
              R"({"fit_spp": [1, 2], "scenes": [{"scene": "black.json", "spp": 4, "direct_spp": 4}]})"));
    const SceneQuality q = evaluateSuiteScene(suite, suite.scenes[0], runOptions());
    EXPECT_NEAR(q.referenceShadowShare, 1.0, 1e-5);
    EXPECT_NEAR(q.referenceIndirectShare, 0.0, 1e-5);
    // DGI's shadow only is then judged against the whole change.
    EXPECT_NEAR(q.shadowPart, q.shadowOnly.deltaRelError, 1e-5);
}

// A scene with a sequence is scored frame by frame: each frame's camera, its references cached apart.
TEST_F(QualitySuiteTest, ASequenceIsScoredFrameByFrame) {
    json frames = json::array();
    for (int i = 0; i < 2; ++i)
        frames.push_back(
            {{"transform_matrix", {{1, 0, 0, 0.1 * i}, {0, 1, 0, 0.8}, {0, 0, 1, 2}, {0, 0, 0, 1}}}});
    write("transforms.json",
          json{{"fl_x", 30.0}, {"fl_y", 30.0}, {"w", 32}, {"h", 24}, {"frames", frames}}.dump());
    json scene = tinyScene(0.5);
    scene.erase("camera");
    scene["sequence"] = {{"transforms", "transforms.json"}};
    write("path.json", scene.dump());
    const QualitySuite suite =
        loadSuite(write("suite.json", R"({"fit_spp": [1], "scenes": [{"scene": "path.json", "spp": 2}]})"));
    SuiteRunOptions options = runOptions();
    std::vector<std::string> reported;
    options.onScene = [&](const SceneQuality& q) { reported.push_back(q.name); };
    const std::vector<SceneQuality> got = evaluateSuiteEntry(suite, suite.scenes[0], options);
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(reported, (std::vector<std::string>{"path frame 0", "path frame 1"}));
    EXPECT_EQ(got[1].key, referenceContentKey(dir_ / "path.json", {}) + "-frame1");
    EXPECT_TRUE(fs::is_regular_file(dir_ / "refs" / got[1].key / "full-2spp-seed1" / "reference.json"));
    EXPECT_NE(got[0].dgi.compositeRmse, got[1].dgi.compositeRmse);  // two cameras, two images
    // A still scene is one row, reported too.
    write("grey.json", tinyScene(0.5).dump());
    const QualitySuite still =
        loadSuite(write("still.json", R"({"fit_spp": [1], "scenes": [{"scene": "grey.json", "spp": 2}]})"));
    EXPECT_EQ(evaluateSuiteEntry(still, still.scenes[0], options).size(), 1u);
    EXPECT_EQ(reported.back(), "grey");
}

TEST_F(QualitySuiteTest, TheTableHasARowPerScene) {
    const QualitySuite suite = loadSuite(writeSuite());
    std::vector<SceneQuality> results;
    for (const SuiteScene& entry : suite.scenes)
        results.push_back(evaluateSuiteScene(suite, entry, runOptions()));

    const json table = json::parse(suiteToJson(results, "deltagi eval --suite suite.json").dump());
    EXPECT_EQ(table.at("command"), "deltagi eval --suite suite.json");
    ASSERT_EQ(table.at("scenes").size(), 2u);
    const json& white = table.at("scenes").at(1);
    EXPECT_EQ(white.at("name"), "white box");
    EXPECT_EQ(white.at("set"), json::array({"options.volume.resolution=32"}));
    for (const char* key : {"delta_rel_error", "object_rel_rmse", "dgi_ms"})
        EXPECT_TRUE(white.at(key).is_number());
    for (const char* key : {"shadow_only", "no_relight"})
        EXPECT_TRUE(white.at("baselines").at(key).at("delta_rel_error").is_number()) << key;
    EXPECT_EQ(white.at("baselines").at("no_relight").at("delta_rel_error"), 1.0);
    for (const char* key :
         {"shadow_part", "indirect_part", "reference_shadow_share", "reference_indirect_share"})
        EXPECT_TRUE(white.at("split").at(key).is_number()) << key;
    EXPECT_EQ(white.at("reference").at("spp"), 4);
    EXPECT_EQ(white.at("reference").at("fit").size(), 2u);
    EXPECT_GT(white.at("reference").at("noise_constant").get<double>(), 0.0);
    EXPECT_TRUE(white.at("equal_error").contains("spp"));
    EXPECT_TRUE(white.at("equal_error").contains("ms"));
    // 4 samples are far too few: the warning says so.
    ASSERT_FALSE(white.at("warnings").empty());
    EXPECT_NE(white.at("warnings").at(0).get<std::string>().find("noise"), std::string::npos);

    const std::string md = suiteMarkdown(results, "deltagi eval --suite suite.json");
    EXPECT_NE(md.find("deltagi eval --suite suite.json"), std::string::npos);
    EXPECT_NE(md.find("| grey | "), std::string::npos) << md;
    EXPECT_NE(md.find("| white box | "), std::string::npos) << md;
    EXPECT_NE(md.find("equal-error spp"), std::string::npos);
    EXPECT_NE(md.find("## Warnings"), std::string::npos);
}

// ---- `deltagi eval --suite` ----

struct CliResult {
    int exitCode = -1;
    std::string err;
};

using test::quote;

class EvalSuiteCliTest : public QualitySuiteTest {
  protected:
    CliResult run(const std::string& args) const {
        const fs::path err = dir_ / "stderr.txt";
        const std::string command = quote(test::kCli) + " " + args + " >" +
                                    quote((dir_ / "stdout.txt").string()) + " 2>" + quote(err.string());
        const int status = std::system(command.c_str());
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, readText(err)};
    }
};

TEST_F(EvalSuiteCliTest, WritesTheTableAndReusesTheCache) {
    const fs::path suite = writeSuite();
    const std::string args =
        "eval --suite " + quote(suite.string()) + " --cache " + quote((dir_ / "refs").string()) + " --json " +
        quote((dir_ / "q.json").string()) + " --markdown " + quote((dir_ / "q.md").string());
    CliResult result = run(args);
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_EQ(json::parse(readText(dir_ / "q.json")).at("scenes").size(), 2u);
    EXPECT_NE(readText(dir_ / "q.md").find("| white box |"), std::string::npos);
    // The fit's 1 and 2 samples come from the full reference's first samples: read back, not rendered.
    EXPECT_NE(result.err.find("2 of the fit's references stored from its first samples"), std::string::npos)
        << result.err;
    EXPECT_EQ(result.err.find("rendering the full reference, 1 spp"), std::string::npos) << result.err;
    EXPECT_EQ(result.err.find("rendering the full reference, 2 spp"), std::string::npos) << result.err;

    result = run(args);
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_NE(result.err.find("cache hit"), std::string::npos) << result.err;
    EXPECT_EQ(result.err.find("rendering"), std::string::npos) << result.err;
}

TEST_F(EvalSuiteCliTest, BadInvocationsEndWithOneErrorLine) {
    const fs::path suite = writeSuite();
    const auto expectOneLine = [](const CliResult& r, int exitCode, const std::string& mustName) {
        EXPECT_EQ(r.exitCode, exitCode) << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
        EXPECT_NE(r.err.find(mustName), std::string::npos) << r.err;
    };
    expectOneLine(run("eval --suite " + quote((dir_ / "missing.json").string())), 1, "missing.json");
    write("bad.json", R"({"scenes": [{"scene": "grey.json", "spp": -1}]})");
    expectOneLine(run("eval --suite " + quote((dir_ / "bad.json").string())), 1, "scenes[0].spp");
    expectOneLine(
        run("eval --suite " + quote(suite.string()) + " --json " + quote((dir_ / "q.txt").string())), 1,
        "q.txt");
    expectOneLine(run("eval"), 2, "--suite");
    expectOneLine(run("eval " + quote((dir_ / "grey.json").string()) + " --suite " + quote(suite.string())),
                  2, "--suite");
    expectOneLine(run("eval --suite " + quote(suite.string()) + " --time-limit 3"), 2, "--time-limit");
}

}  // namespace
}  // namespace deltagi
