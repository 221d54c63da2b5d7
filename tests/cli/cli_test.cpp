// The `deltagi` command end to end: bad input gives one `deltagi: error:` line naming the file and key and a
// non-zero exit; a tiny scene renders with every AOV; `info --json` is valid JSON; outputs are never inputs,
// are checked before the work, and two runs onto one output leave it whole (interruptions:
// interruption_test.cpp).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "deltagi/image.h"
#include "deltagi/scene_io.h"
#include "scene/scene_info.h"
#include "test_cli.h"
#include "test_files.h"
#include "test_paths.h"

namespace fs = std::filesystem;
using deltagi::test::CliResult;
using deltagi::test::CliTest;
using deltagi::test::expectOneErrorLine;
using deltagi::test::lineCount;
using deltagi::test::quote;
using deltagi::test::readText;
using deltagi::test::tinyScene;
using deltagi::test::writeText;
using nlohmann::json;

namespace {

TEST_F(CliTest, VersionNamesTheGitRevision) {
    const CliResult result = run("--version");
    EXPECT_EQ(result.exitCode, 0);
    // "deltagi 0.1.0 (git 0123456789ab)", "-dirty" after it for a modified work tree, "unknown" without git.
    EXPECT_TRUE(std::regex_match(
        result.out, std::regex(R"(deltagi \d+\.\d+\.\d+ \(git ([0-9a-f]{7,}(-dirty)?|unknown)\)\n)")))
        << result.out;
}

TEST_F(CliTest, HelpListsTheExitStatuses) {
    const CliResult result = run("--help");
    EXPECT_EQ(result.exitCode, 0);
    for (const char* part : {"Exit status: 0 done, 1 bad input", "2 usage error", "130 or 143", "--version"})
        EXPECT_NE(result.out.find(part), std::string::npos) << part;
}

TEST_F(CliTest, HugeValuesInMessagesAreCut) {
    json scene = tinyScene();
    scene["lights"][0]["type"] = std::string(100000, 'x');
    const CliResult result = run("info " + quote(writeScene(scene).string()));
    expectOneErrorLine(result, {"scene.json: lights[0].type: expected \"point\""});
    EXPECT_LE(result.err.size(), 1100u);  // "deltagi: error: " and at most 1000 characters
}

TEST_F(CliTest, MissingSceneFile) {
    expectOneErrorLine(run(renderArgs(dir_ / "no-such-scene.json")), {"no-such-scene.json"});
    expectOneErrorLine(run("info " + quote((dir_ / "no-such-scene.json").string())), {"no-such-scene.json"});
}

TEST_F(CliTest, MalformedJson) {
    writeText(dir_ / "broken.json", "{\"camera\": {\"width\": 64,\n");
    expectOneErrorLine(run(renderArgs(dir_ / "broken.json")), {"broken.json"});
}

TEST_F(CliTest, UnknownKey) {
    json scene = tinyScene();
    scene["camera"]["widht"] = 64;
    expectOneErrorLine(run(renderArgs(writeScene(scene))), {"scene.json", "widht"});
}

TEST_F(CliTest, WrongType) {
    json scene = tinyScene();
    scene["camera"]["width"] = "wide";
    expectOneErrorLine(run(renderArgs(writeScene(scene))), {"scene.json", "camera.width"});
}

TEST_F(CliTest, MissingMeshFile) {
    json scene = tinyScene();
    scene["virtual"][0].erase("shape");
    scene["virtual"][0]["file"] = "missing-mesh.obj";
    expectOneErrorLine(run(renderArgs(writeScene(scene))),
                       {"scene.json", "virtual[0].file", "missing-mesh.obj"});
}

TEST_F(CliTest, BadOverride) {
    const fs::path scene = writeScene(tinyScene());
    // camera.width is a number: the key cannot go on through it.
    expectOneErrorLine(run(renderArgs(scene) + " --set camera.width.pixels=3"), {"camera.width"});
    expectOneErrorLine(run(renderArgs(scene) + " --set options.volume.resolution"),
                       {"options.volume.resolution"});
    expectOneErrorLine(run(renderArgs(scene) + " --set camera.width=-5"), {"scene.json", "camera.width"});
}

TEST_F(CliTest, ZeroThreads) {
    expectOneErrorLine(run(renderArgs(writeScene(tinyScene())) + " --threads 0"), {"--threads"});
}

TEST_F(CliTest, ZeroResolution) {
    json scene = tinyScene();
    scene["options"]["volume"]["resolution"] = 0;
    expectOneErrorLine(run(renderArgs(writeScene(scene))), {"scene.json", "options.volume.resolution"});
    expectOneErrorLine(run(renderArgs(writeScene(tinyScene())) + " --set options.volume.resolution=0"),
                       {"scene.json", "options.volume.resolution"});
}

TEST_F(CliTest, UnknownOutputType) {
    const std::string args =
        "render " + quote(writeScene(tinyScene()).string()) + " -o " + quote((dir_ / "out.tif").string());
    expectOneErrorLine(run(args), {"out.tif"});
}

// --layers writes one EXR with the compositing layers; its composite is the image's, and it must be .exr.
TEST_F(CliTest, LayersGoIntoOneExr) {
    const fs::path scene = writeScene(tinyScene());
    const fs::path layers = dir_ / "layers.exr";
    const CliResult result = run(renderArgs(scene) + " --layers " + quote(layers.string()));
    ASSERT_EQ(result.exitCode, 0) << result.err;
    std::vector<std::string> names;
    for (const deltagi::NamedImage& layer : deltagi::readLayers(layers)) names.push_back(layer.name);
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"background", "composite", "delta", "depth", "indirect",
                                               "object", "shadow"}));
    expectOneErrorLine(run(renderArgs(scene) + " --layers " + quote((dir_ / "layers.png").string())),
                       {"layers.png", ".exr"});
}

TEST_F(CliTest, UsageErrorExitsWithTwo) {
    const CliResult result = run("render");  // no scene, no -o
    EXPECT_EQ(result.exitCode, 2);
    EXPECT_EQ(result.err.rfind("deltagi: error:", 0), 0u) << result.err;
}

TEST_F(CliTest, RendersTinySceneWithAovs) {
    const fs::path scene = writeScene(tinyScene());
    const fs::path aov = dir_ / "aov";
    const CliResult result = run(renderArgs(scene) + " --threads 2 --aov " + quote(aov.string()));
    ASSERT_EQ(result.exitCode, 0) << result.err;
    // stderr is not a terminal here: only the summary line.
    EXPECT_EQ(lineCount(result.err), 1u) << result.err;
    EXPECT_NE(result.err.find("out.png"), std::string::npos) << result.err;

    for (const char* file :
         {"background.exr", "composite.exr", "object_mask.exr", "delta.exr", "timings.json"}) {
        EXPECT_TRUE(fs::is_regular_file(aov / file)) << file;
        EXPECT_GT(fs::file_size(aov / file), 0u) << file;
    }
    EXPECT_TRUE(fs::is_regular_file(dir_ / "out.png"));

    const json timings = json::parse(readText(aov / "timings.json"));
    ASSERT_TRUE(timings.at("stages").is_object());
    for (const char* stage : {"voxelize", "rsm", "inject", "mipmap", "composite"})
        EXPECT_TRUE(timings["stages"].contains(stage)) << stage << " in " << timings.dump();
    for (const auto& [name, ms] : timings["stages"].items()) EXPECT_GE(ms.get<double>(), 0.0) << name;
    EXPECT_GE(timings.at("total_ms").get<double>(), 0.0);
    EXPECT_EQ(timings.at("threads"), 2);
    EXPECT_EQ(timings.at("width"), 64);
    EXPECT_EQ(timings.at("height"), 48);
    EXPECT_EQ(timings.at("volume_resolution"), 16);
}

TEST_F(CliTest, QuietPrintsNothing) {
    const CliResult result = run(renderArgs(writeScene(tinyScene())) + " --quiet --threads 1");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_EQ(result.err, "");
    EXPECT_EQ(result.out, "");
}

TEST_F(CliTest, InfoJson) {
    const fs::path scene = writeScene(tinyScene());
    const CliResult result =
        run("info " + quote(scene.string()) + " --json --set options.volume.resolution=32");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    const json info = json::parse(result.out);
    EXPECT_EQ(info.at("real").at("triangles"), 2);
    EXPECT_EQ(info.at("virtual").at("triangles"), 12);
    EXPECT_EQ(info.at("lights"), 1);
    EXPECT_EQ(info.at("volume").at("resolution"), 32);
    EXPECT_EQ(info.at("volume").at("mip_levels"), 6);
    EXPECT_EQ(info.at("volume").at("bytes_per_volume"), deltagi::volumeBytes(32));
    const size_t objects = info.at("volume").at("bytes_object_volumes");
    EXPECT_GT(objects, 0u);
    EXPECT_LT(objects, 2 * deltagi::volumeBytes(32));
    EXPECT_EQ(info.at("volume").at("bytes_all_volumes"), 3 * deltagi::volumeBytes(32) + objects);
    EXPECT_EQ(info.at("options").at("volume").at("resolution"), 32);
    EXPECT_EQ(info.at("options").at("rsm").at("resolution"), 64);

    const CliResult table = run("info " + quote(scene.string()));
    ASSERT_EQ(table.exitCode, 0) << table.err;
    EXPECT_NE(table.out.find("triangles"), std::string::npos) << table.out;
}

// `info --options-markdown` prints the options tables, or a markdown file with its tables made anew (what
// scripts/update-options-doc.sh writes over docs/scene-format.md); `info` needs one or a scene.
TEST_F(CliTest, InfoPrintsTheOptionsMarkdown) {
    const CliResult tables = run("info --options-markdown");
    ASSERT_EQ(tables.exitCode, 0) << tables.err;
    EXPECT_EQ(tables.out, deltagi::optionTablesMarkdown());

    // A document whose rsm table is out of date comes back with the tables of the code.
    std::string stale = tables.out;
    const size_t begin = stale.find('\n', stale.find("<!-- options table: rsm -->")) + 1;
    stale.replace(begin, stale.find("<!-- end of options table -->", begin) - begin, "| old |\n");
    writeText(dir_ / "doc.md", "# Options\n\n" + stale);
    const CliResult doc = run("info --options-markdown " + quote((dir_ / "doc.md").string()));
    ASSERT_EQ(doc.exitCode, 0) << doc.err;
    EXPECT_EQ(doc.out, "# Options\n\n" + tables.out);
    expectOneErrorLine(run("info --options-markdown " + quote((dir_ / "missing.md").string())),
                       {"missing.md"});

    const CliResult usage = run("info");
    EXPECT_EQ(usage.exitCode, 2);
    EXPECT_NE(usage.err.find("expected SCENE.json, or --options-markdown"), std::string::npos) << usage.err;
}

TEST_F(CliTest, CornellExamplesLoad) {
    expectExampleLoads("cornell-box");
    expectExampleLoads("cornell-box-glossy");
}

TEST_F(CliTest, BuddhaExampleLoads) {
    if (!fs::exists(fs::path(deltagi::test::kSharedDataDir) / "meshes" / "happy-buddha.obj"))
        GTEST_SKIP() << "needs the shared data set (" << deltagi::test::kSharedDataDir << ")";
    expectExampleLoads("cornell-buddha");
    expectExampleLoads("bench-cornell-buddha");
}

TEST_F(CliTest, BenchWritesTheTableAndJson) {
    const fs::path jsonPath = dir_ / "bench.json";
    const CliResult result = run("bench " + quote(writeScene(tinyScene()).string()) +
                                 " --frames 2 --warmup 0 --quiet --json " + quote(jsonPath.string()));
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_NE(result.out.find("diffuse_ms"), std::string::npos) << result.out;
    const json figures = json::parse(readText(jsonPath));
    EXPECT_EQ(figures.at("frames"), 2);
    EXPECT_EQ(figures.at("width"), 64);
    EXPECT_GE(figures.at("total_ms").at("median").get<double>(), 0.0);
    EXPECT_EQ(figures.at("specular_ms").at("paper"), 64.0);
    EXPECT_FALSE(figures.at("live").get<bool>());

    const CliResult live = run("bench " + quote(writeScene(tinyScene()).string()) +
                               " --frames 2 --warmup 1 --live --json " + quote(jsonPath.string()));
    ASSERT_EQ(live.exitCode, 0) << live.err;
    EXPECT_NE(live.out.find("the real light changing every frame"), std::string::npos) << live.out;
    const json liveFigures = json::parse(readText(jsonPath));
    EXPECT_TRUE(liveFigures.at("live").get<bool>());
    EXPECT_EQ(liveFigures.at("light_kept_frames"), 0);
    EXPECT_EQ(liveFigures.at("camera_motion_deg"), 5.0);
}

TEST_F(CliTest, BenchBadInput) {
    json scene = tinyScene();
    scene["virtual"] = json::array();
    expectOneErrorLine(run("bench " + quote(writeScene(scene).string())), {"scene.json", "virtual"});
    expectOneErrorLine(run("bench " + quote(writeScene(tinyScene()).string()) + " --frames 0"), {"--frames"});
    expectOneErrorLine(run("bench " + quote(writeScene(tinyScene()).string()) + " --json " +
                           quote((dir_ / "no-such-folder" / "b.json").string())),
                       {"b.json"});
}

// `deltagi serve`'s bad input ends before it listens, like any command's; a port in use is one line too.
TEST_F(CliTest, ServeBadInput) {
    json scene = tinyScene();
    scene["camera"]["width"] = -3;
    expectOneErrorLine(run("serve " + quote(writeScene(scene).string()) + " --port 0"),
                       {"scene.json", "width"});
    expectOneErrorLine(run("serve " + quote((dir_ / "none.json").string())), {"none.json"});
    const int busy = ::socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(busy, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof(address);
    ASSERT_EQ(::bind(busy, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
    ASSERT_EQ(::listen(busy, 1), 0);
    ASSERT_EQ(::getsockname(busy, reinterpret_cast<sockaddr*>(&address), &length), 0);
    const CliResult result = run("serve " + quote(writeScene(tinyScene()).string()) + " --port " +
                                 std::to_string(ntohs(address.sin_port)));
    ::close(busy);
    expectOneErrorLine(result, {"cannot listen", "--port 0"});
}

// ---- reference, compare, eval ----

TEST_F(CliTest, ReferenceAndEvalBadInput) {
    const std::string scene = quote(writeScene(tinyScene()).string());
    const std::string out = " -o " + quote((dir_ / "ref.exr").string());
    const std::string json = " --json " + quote((dir_ / "eval.json").string());
    // The shared options are checked alike by both commands (CLI11 validators): the full set on `reference`.
    for (const std::string command : {"reference", "eval"}) {
        const std::string output = command == "eval" ? json : out;
        expectOneErrorLine(run(command + " " + quote((dir_ / "no-such-scene.json").string()) + output),
                           {"no-such-scene.json"});
        expectOneErrorLine(run(command + " " + scene + output + " --spp 0"), {"--spp", "0"});
        expectOneErrorLine(run(command + " " + scene + output + " --time-limit nan"),
                           {"--time-limit", "nan"});
        expectOneErrorLine(run(command + " " + scene + output + " --max-bounces 0"), {"--max-bounces", "0"});
    }
    expectOneErrorLine(run("reference " + scene + out + " --spp -4"), {"--spp", "-4"});
    expectOneErrorLine(run("reference " + scene + out + " --time-limit -1"), {"--time-limit", "-1"});
    expectOneErrorLine(run("reference " + scene + out + " --time-limit 5s"), {"--time-limit", "5s"});
    expectOneErrorLine(run("reference " + scene + out + " --set camera.width=0"),
                       {"scene.json", "camera.width"});
    expectOneErrorLine(run("reference " + scene + " -o " + quote((dir_ / "ref.tif").string())), {"ref.tif"});
    expectOneErrorLine(run("eval " + scene + " --json " + quote((dir_ / "eval.txt").string())), {"eval.txt"});
    EXPECT_FALSE(fs::exists(dir_ / "ref.exr"));
    EXPECT_FALSE(fs::exists(dir_ / "eval.json"));
}

// --max-bounces 1 renders the direct light alone: under a white ceiling (the lamp below it), much of the
// floor's light comes from the ceiling, so the image is clearly darker than with every bounce.
TEST_F(CliTest, ReferenceMaxBouncesLeavesOutTheIndirectLight) {
    json doc = tinyScene();
    json ceiling = doc["scene"][0];
    ceiling["name"] = "ceiling";
    ceiling["shape"]["positions"] = {{-2, 1.2, -2}, {2, 1.2, -2}, {2, 1.2, 2}, {-2, 1.2, 2}};
    ceiling["material"]["albedo"] = {0.9, 0.9, 0.9};
    doc["scene"].push_back(ceiling);
    doc["lights"][0]["position"] = {0.5, 1.0, 0.5};
    const std::string scene = quote(writeScene(doc).string());
    const fs::path direct = dir_ / "direct.exr", all = dir_ / "all.exr";
    for (const auto& [file, bounces] : {std::pair{direct, " --max-bounces 1"}, std::pair{all, ""}}) {
        const CliResult result =
            run("reference " + scene + " -o " + quote(file.string()) + " --spp 4 --quiet" + bounces);
        ASSERT_EQ(result.exitCode, 0) << result.err;
    }
    const deltagi::Image d = deltagi::readImage(direct), a = deltagi::readImage(all);
    double directSum = 0.0, allSum = 0.0;
    for (int y = 0; y < d.height(); ++y)
        for (int x = 0; x < d.width(); ++x) {
            directSum += d.at(x, y, 1);
            allSum += a.at(x, y, 1);
        }
    EXPECT_LT(directSum, 0.8 * allSum);
    EXPECT_GT(directSum, 0.0);
}

TEST_F(CliTest, CompareBadInput) {
    const fs::path a = dir_ / "a.exr", b = dir_ / "b.exr", small = dir_ / "small.exr";
    deltagi::writeImage(deltagi::Image(8, 6, 3, 0.5f), a);
    deltagi::writeImage(deltagi::Image(8, 6, 3, 0.25f), b);
    deltagi::writeImage(deltagi::Image(4, 6, 3, 0.5f), small);
    writeText(dir_ / "text.exr", "not an image\n");
    const std::string qa = quote(a.string()), qb = quote(b.string());
    expectOneErrorLine(run("compare " + quote((dir_ / "missing.exr").string()) + " " + qb), {"missing.exr"});
    expectOneErrorLine(run("compare " + qa + " " + quote((dir_ / "missing.exr").string())), {"missing.exr"});
    expectOneErrorLine(run("compare " + qa + " " + quote((dir_ / "text.exr").string())), {"text.exr"});
    expectOneErrorLine(run("compare " + quote(small.string()) + " " + qb),
                       {"small.exr", "b.exr", "differ in size", "4x6", "8x6"});
    expectOneErrorLine(run("compare " + qa + " " + qb + " -o " + quote((dir_ / "d.tif").string())),
                       {"d.tif"});
    expectOneErrorLine(run("compare " + qa + " " + qb + " --max 0"), {"--max", "0"});
    expectOneErrorLine(run("compare " + qa + " " + qb + " --max -1"), {"--max", "-1"});
}

TEST_F(CliTest, CompareReportsTheMetrics) {
    const fs::path a = dir_ / "a.exr", b = dir_ / "b.exr";
    deltagi::writeImage(deltagi::Image(8, 6, 3, 0.5f), a);
    deltagi::writeImage(deltagi::Image(8, 6, 3, 0.25f), b);
    const fs::path diff = dir_ / "diff.png";
    const CliResult result =
        run("compare " + quote(a.string()) + " " + quote(b.string()) + " --json -o " + quote(diff.string()));
    ASSERT_EQ(result.exitCode, 0) << result.err;
    const json metrics = json::parse(result.out);
    EXPECT_NEAR(metrics.at("rmse").get<double>(), 0.25, 1e-6);
    EXPECT_NEAR(metrics.at("mae").get<double>(), 0.25, 1e-6);
    EXPECT_NEAR(metrics.at("rel_mse").get<double>(), 0.0625 / (0.0625 + 0.01), 1e-5);
    EXPECT_TRUE(fs::is_regular_file(diff));
}

// reference and eval end to end on the tiny scene: the images, and the figures under the documented keys.
TEST_F(CliTest, ReferenceAndEvalWriteTheirOutputs) {
    const std::string scene = quote(writeScene(tinyScene()).string());
    const fs::path aov = dir_ / "aov";
    CliResult result = run("reference " + scene + " -o " + quote((dir_ / "ref.exr").string()) +
                           " --spp 2 --threads 2 --aov " + quote(aov.string()));
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_NE(result.err.find("2 spp"), std::string::npos) << result.err;
    for (const char* file : {"with.exr", "without.exr", "composite.exr", "delta.exr", "object_mask.exr"})
        EXPECT_TRUE(fs::is_regular_file(aov / file)) << file;
    EXPECT_TRUE(fs::is_regular_file(dir_ / "ref.exr"));

    result = run("eval " + scene + " --json " + quote((dir_ / "eval.json").string()) + " --spp 2 --quiet");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_EQ(result.err, "");
    const json figures = json::parse(readText(dir_ / "eval.json"));
    for (const char* key : {"delta_rel_error", "object_rel_rmse", "composite_rmse", "bias_lit",
                            "bias_shadowed", "dgi_ms", "reference_ms"})
        EXPECT_TRUE(figures.at(key).is_number()) << key;
    for (const char* baseline : {"no_relight", "shadow_only", "single_visibility"})
        EXPECT_TRUE(figures.at("baselines").at(baseline).at("delta_rel_error").is_number()) << baseline;

    // Against the reference rendered above: the same figures as an eval that path-traces it anew with the
    // same seed and samples (DGI is deterministic).
    result = run("eval " + scene + " --json " + quote((dir_ / "again.json").string()) + " --reference " +
                 quote(aov.string()));
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_NE(result.err.find("reference from"), std::string::npos) << result.err;
    result = run("eval " + scene + " --json " + quote((dir_ / "fresh.json").string()) + " --spp 2 --quiet");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    const json again = json::parse(readText(dir_ / "again.json")),
               fresh = json::parse(readText(dir_ / "fresh.json"));
    for (const char* key : {"delta_rel_error", "object_rel_rmse", "composite_rmse"})
        EXPECT_DOUBLE_EQ(again.at(key).get<double>(), fresh.at(key).get<double>()) << key;
    EXPECT_DOUBLE_EQ(again.at("baselines").at("shadow_only").at("delta_rel_error").get<double>(),
                     fresh.at("baselines").at("shadow_only").at("delta_rel_error").get<double>());

    // A reference folder that lacks an image, or whose images are of another size, is named.
    fs::remove(aov / "without.exr");
    expectOneErrorLine(run("eval " + scene + " --json " + quote((dir_ / "e.json").string()) +
                           " --reference " + quote(aov.string())),
                       {"without.exr", "missing"});
    expectOneErrorLine(run("eval " + scene + " --json " + quote((dir_ / "e.json").string()) +
                           " --reference " + quote(aov.string()) + " --set camera.width=12"),
                       {"with.exr", "12x"});
    expectOneErrorLine(run("eval " + scene + " --json " + quote((dir_ / "e.json").string()) +
                           " --reference " + quote(aov.string()) + " --spp 4"),
                       {"--reference", "--spp"});
}

// The field example names the shared file it misses; with the shared data it loads 16 lights from the probe.
TEST_F(CliTest, FieldBunnyExampleLoadsOrNamesTheMissingSharedFile) {
    const fs::path scene = fs::path(deltagi::test::kSourceDir) / "examples" / "field-bunny.json";
    const bool shared =
        fs::exists(fs::path(deltagi::test::kSharedDataDir) / "photos" / "spruit-sunrise-field");
    const CliResult missing =
        run("info " + quote(scene.string()) + " --set environment.file=../../shared/data/photos/missing.hdr");
    EXPECT_EQ(missing.exitCode, 1);
    // The first file it misses: the photo when the shared data set is absent, else the probe set to a missing
    // file.
    const std::vector<std::string> parts =
        shared ? std::vector<std::string>{"field-bunny.json: environment.file: file not found", "missing.hdr",
                                          "shared data"}
               : std::vector<std::string>{"field-bunny.json: background: file not found", "backplate",
                                          "shared data"};
    for (const std::string& part : parts)
        EXPECT_NE(missing.err.find(part), std::string::npos) << part << " not in: " << missing.err;
    if (!shared) GTEST_SKIP() << "needs the shared data set (" << deltagi::test::kSharedDataDir << ")";
    const CliResult result = run("info --json " + quote(scene.string()));
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_EQ(json::parse(result.out).at("lights"), 16);
    EXPECT_TRUE(result.err.empty()) << result.err;  // an HDR probe: no warning
}

// ---- outputs: never an input, checked before the work, whole after any interruption ----

// Every command refuses, in one line and before any work, an output that is one of its inputs; the input is
// left as it was.
TEST_F(CliTest, OutputThatIsAnInputIsRefused) {
    fs::create_directories(dir_ / "photos");
    const fs::path photo = dir_ / "photos" / "background.exr";
    deltagi::writeImage(deltagi::Image(64, 48, 3, 0.5f), photo);
    json withPhoto = tinyScene();
    withPhoto["background"] = "photos/background.exr";
    const fs::path scene = writeScene(withPhoto);
    const std::string sceneText = readText(scene), photoBytes = readText(photo);
    fs::create_symlink(scene, dir_ / "link.json");
    const std::string qs = quote(scene.string()), qphoto = quote(photo.string());
    const std::string photos = quote((dir_ / "photos").string());

    const auto refused = [&](const std::string& args, const std::string& what) {
        const CliResult result = run(args);
        expectOneErrorLine(result, {"is an input of this run (" + what + "); choose another output"});
        EXPECT_EQ(result.exitCode, 1) << args;
        EXPECT_EQ(readText(scene), sceneText) << args;
        EXPECT_EQ(readText(photo), photoBytes) << args;
    };
    refused("bench " + qs + " --frames 1 --json " + qs, "the scene file");
    refused("bench " + qs + " --frames 1 --json " + quote((dir_ / "link.json").string()), "the scene file");
    refused("eval " + qs + " --spp 1 --json " + qs, "the scene file");
    refused("render " + qs + " -o " + qphoto, "the background photo");
    refused("render " + qs + " -o " + quote((dir_ / "out.png").string()) + " --aov " + photos,
            "the background photo");
    refused("reference " + qs + " --spp 1 -o " + qphoto, "the background photo");
    refused("eval " + qs + " --spp 1 --json " + quote((dir_ / "e.json").string()) + " --aov " + photos,
            "the background photo");
    json withSky = tinyScene();
    withSky["environment"] = {{"file", "sky.exr"}};
    deltagi::writeImage(deltagi::Image(16, 8, 3, 0.25f), dir_ / "sky.exr");
    const std::string skyBytes = readText(dir_ / "sky.exr");
    refused("render " + quote(writeScene(withSky, "sky.json").string()) + " -o " +
                quote((dir_ / "sky.exr").string()),
            "the environment map");
    EXPECT_EQ(readText(dir_ / "sky.exr"), skyBytes);

    const fs::path a = dir_ / "a.exr", b = dir_ / "b.exr";
    deltagi::writeImage(deltagi::Image(8, 6, 3, 0.5f), a);
    deltagi::writeImage(deltagi::Image(8, 6, 3, 0.25f), b);
    const std::string aBytes = readText(a), bBytes = readText(b);
    refused("compare " + quote(a.string()) + " " + quote(b.string()) + " -o " + quote(a.string()),
            "the image to judge");
    refused("compare " + quote(a.string()) + " " + quote(b.string()) + " -o " + quote(b.string()),
            "the reference image");
    EXPECT_EQ(readText(a), aBytes);
    EXPECT_EQ(readText(b), bBytes);

    // eval --aov into the folder of its --reference would write over the reference's images.
    const fs::path reference = dir_ / "reference";
    fs::create_directories(reference);
    for (const char* name :
         {"with.exr", "without.exr", "background.exr", "composite.exr", "object_mask.exr", "delta.exr"})
        deltagi::writeImage(deltagi::Image(64, 48, 3, 0.5f), reference / name);
    refused("eval " + qs + " --json " + quote((dir_ / "e.json").string()) + " --reference " +
                quote(reference.string()) + " --aov " + quote(reference.string()),
            "a reference image of --reference");
    EXPECT_FALSE(fs::exists(dir_ / "e.json"));
    EXPECT_FALSE(fs::exists(dir_ / "out.png"));
}

// An output where no file can be written fails in one line before the scene is even loaded (so before the
// render): the scene named here does not exist, and the error is about the output.
TEST_F(CliTest, UnwritableOutputIsRefusedBeforeTheRender) {
    writeText(dir_ / "file", "");
    const std::string missing = quote((dir_ / "no-such-scene.json").string());
    const std::string inFile = (dir_ / "file").string();
    for (const std::string& args : {"render " + missing + " -o " + quote(inFile + "/out.png"),
                                    "render " + missing + " -o " + quote((dir_ / "out.png").string()) +
                                        " --aov " + quote(inFile + "/aov"),
                                    "reference " + missing + " -o " + quote(inFile + "/ref.exr"),
                                    "eval " + missing + " --json " + quote(inFile + "/sub/e.json")}) {
        const CliResult result = run(args);
        expectOneErrorLine(result, {"is not a folder", "file"});
        EXPECT_EQ(result.err.find("no-such-scene"), std::string::npos) << result.err;
    }
    const fs::path a = dir_ / "a.exr";
    deltagi::writeImage(deltagi::Image(8, 6, 3, 0.5f), a);
    expectOneErrorLine(
        run("compare " + quote(a.string()) + " " + quote(a.string()) + " -o " + quote(inFile + "/d.png")),
        {"is not a folder"});
    expectOneErrorLine(
        run("bench " + quote(writeScene(tinyScene()).string()) + " --json " + quote(inFile + "/b.json")),
        {"b.json"});
    if (geteuid() != 0) {  // root writes into read-only folders
        fs::create_directories(dir_ / "read-only");
        fs::permissions(dir_ / "read-only", fs::perms::owner_read | fs::perms::owner_exec);
        expectOneErrorLine(
            run("render " + missing + " -o " + quote((dir_ / "read-only" / "out.png").string())),
            {"read-only", "cannot write"});
        fs::permissions(dir_ / "read-only", fs::perms::owner_all);
    }
    EXPECT_FALSE(fs::exists(dir_ / "out.png"));
    EXPECT_TRUE(temporaries().empty());
}

// bench reads the scene and renders its frames before it touches --json: a failed run keeps the figures of
// the run before.
TEST_F(CliTest, FailedBenchKeepsThePreviousFigures) {
    const fs::path figures = dir_ / "bench.json";
    const std::string scene = quote(writeScene(tinyScene()).string());
    ASSERT_EQ(run("bench " + scene + " --frames 1 --warmup 0 -q --json " + quote(figures.string())).exitCode,
              0);
    const std::string previous = readText(figures);
    ASSERT_NE(previous, "");
    expectOneErrorLine(run("bench " + scene + " --frames 1 --warmup 0 -q --set 'virtual=[]' --json " +
                           quote(figures.string())),
                       {"virtual"});
    EXPECT_EQ(readText(figures), previous);
}

// Two renders of different images onto one EXR at once: both succeed and the file is one of the two, whole.
TEST_F(CliTest, ConcurrentRendersLeaveOneWholeImage) {
    const std::string scene = quote(writeScene(tinyScene()).string());
    const std::string red = " --set 'virtual.0.material.albedo=[0.9,0.1,0.1]' -q";
    ASSERT_EQ(run("render " + scene + " -q -o " + quote((dir_ / "blue.exr").string())).exitCode, 0);
    ASSERT_EQ(run("render " + scene + red + " -o " + quote((dir_ / "red.exr").string())).exitCode, 0);
    const std::string out = quote((dir_ / "out.exr").string());
    const std::string cli = quote(deltagi::test::kCli);
    const std::string command = "(" + cli + " render " + scene + " -q -o " + out + "; echo $? >" +
                                quote((dir_ / "rc1").string()) + ") & (" + cli + " render " + scene + red +
                                " -o " + out + "; echo $? >" + quote((dir_ / "rc2").string()) + ") & wait";
    ASSERT_EQ(std::system(command.c_str()), 0);
    EXPECT_EQ(readText(dir_ / "rc1"), "0\n");
    EXPECT_EQ(readText(dir_ / "rc2"), "0\n");
    // The files differ in their header's time stamp: compare the pixels.
    const auto samePixels = [](const fs::path& a, const fs::path& b) {
        const deltagi::Image x = deltagi::readImage(a), y = deltagi::readImage(b);
        return std::equal(x.data().begin(), x.data().end(), y.data().begin(), y.data().end());
    };
    EXPECT_TRUE(samePixels(dir_ / "out.exr", dir_ / "blue.exr") ||
                samePixels(dir_ / "out.exr", dir_ / "red.exr"));
    EXPECT_TRUE(temporaries().empty());
}

// 8 bytes per voxel over the mip chain r^3 + (r/2)^3 + ... + 1.
TEST(SceneInfo, VolumeBytesSumsTheMipChain) {
    EXPECT_EQ(deltagi::volumeBytes(1), 8u);
    EXPECT_EQ(deltagi::volumeBytes(4), 8u * (64 + 8 + 1));
    EXPECT_EQ(deltagi::volumeBytes(128), 8u * (2396745u));  // (8^8 - 1) / 7 voxels
    // A window of 3 x 2 x 1 voxels at (1, 1, 1) of 4^3: its parents are 2 x 2 x 1 at level 1, then 1.
    EXPECT_EQ(deltagi::windowedVolumeBytes(4, {1, 1, 1}, {4, 3, 2}), 8u * (6 + 4 + 1));
    EXPECT_EQ(deltagi::windowedVolumeBytes(4, {-5, 0, 0}, {9, 9, 9}), deltagi::volumeBytes(4));  // clipped
    EXPECT_EQ(deltagi::windowedVolumeBytes(4, {2, 2, 2}, {2, 3, 3}), 0u);                        // empty
}

// Numbers on the command line that are not finite are refused before any work, with one line naming the
// option (CLI11's own range checks take "nan").
TEST_F(CliTest, OptionsThatAreNotFiniteNumbersAreRefused) {
    const std::string scene = quote(writeScene(tinyScene(), "scene.json").string());
    for (const std::string& args : std::vector<std::string>{
             "bench " + scene + " --motion nan", "bench " + scene + " --camera-motion inf",
             "stability " + scene + " --object-step nan", "stability " + scene + " --direction 1,nan,0",
             "eval --suite " + scene + " --checkpoint-minutes nan", "encode f_####.png -o v.mp4 --fps nan",
             "track v.mp4 --scene " + scene + " -o t.json --max-speed nan",
             "live " + scene + " --camera v.mp4 --hold -inf", "marker 3 --size nan -o m.png",
             "render " + scene + " -o x.png --fps nan"}) {
        const CliResult r = run(args);
        EXPECT_EQ(r.exitCode, 2) << args << ": " << r.err;
        EXPECT_EQ(lineCount(r.err), 1u) << args << ": " << r.err;
        EXPECT_NE(r.err.find("expected a number"), std::string::npos) << args << ": " << r.err;
    }
}

// Two outputs of one run that name one file are refused before any work: one would overwrite the other.
TEST_F(CliTest, TwoOutputsThatAreOneFileAreRefused) {
    const std::string scene = quote(writeScene(tinyScene(), "scene.json").string());
    const std::string d = dir_.string();
    for (const std::string& outputs : std::vector<std::string>{
             "-o " + d + "/x.exr --layers " + d + "/x.exr", "-o " + d + "/background.exr --aov " + d,
             "-o " + d + "/./y.exr --layers " + d + "/sub/../y.exr"}) {
        const CliResult r = run("render " + scene + " -q " + outputs);
        expectOneErrorLine(r, {"is given twice as an output of this run"});
        EXPECT_FALSE(fs::exists(dir_ / "x.exr") || fs::exists(dir_ / "y.exr")) << outputs;
    }
}

// An output name too long for its temporary beside it is refused before the work, not after it.
TEST_F(CliTest, AnOutputNameTooLongForItsTemporaryIsRefusedFirst) {
    const std::string scene = quote(writeScene(tinyScene(), "scene.json").string());
    const CliResult r =
        run("render " + scene + " -q -o " + quote((dir_ / (std::string(244, 'a') + ".png")).string()));
    expectOneErrorLine(r, {"the file name is 248 bytes", "choose a shorter name"});
    EXPECT_EQ(r.err.find("ms"), std::string::npos) << "rendered first: " << r.err;
}

}  // namespace
