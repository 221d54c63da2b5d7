// The memory guard (estimateRenderMemory, src/scene/json_reader.h) bounds what a render really takes: its
// estimate, which `deltagi info --json` prints, against the peak resident memory of the same render (wait4's
// ru_maxrss), for each part it counts: the frame's images at 1 and 16 samples per pixel, the volumes and the
// meshes of `shape` entries. Not under the sanitizers, whose shadow memory is no render's.
#include <sys/resource.h>
#include <sys/wait.h>

#include "test_cli.h"
#include "test_paths.h"

namespace deltagi::test {
namespace {

using nlohmann::json;

struct Memory {
    double estimate = 0.0, peak = 0.0;  // bytes
};

class MemoryGuardTest : public CliTest {
  protected:
    void SetUp() override {
#ifdef DELTAGI_TESTS_SANITIZED
        GTEST_SKIP() << "the sanitizers' shadow memory is part of every peak";
#endif
        CliTest::SetUp();
    }

    // The estimate and the peak of rendering the Cornell box example with these --set overrides.
    Memory measure(const std::vector<std::string>& overrides) {
        const std::string scene = (fs::path(kSourceDir) / "examples" / "cornell-box.json").string();
        std::string sets;
        for (const std::string& o : overrides) sets += " --set " + o;
        const CliResult info = run("info " + quote(scene) + " --json" + sets);
        EXPECT_EQ(info.exitCode, 0) << info.err;
        Memory memory;
        memory.estimate = json::parse(info.out).at("render_memory_bytes").get<double>();
        std::vector<std::string> args = {"render", scene, "-o", (dir_ / "out.exr").string(), "-q"};
        for (const std::string& o : overrides) args.insert(args.end(), {"--set", o});
        const pid_t pid = startCli(args, dir_);
        int status = 0;
        rusage usage{};
        EXPECT_EQ(wait4(pid, &status, 0, &usage), pid);
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << readText(dir_ / "stderr.txt");
        memory.peak = static_cast<double>(usage.ru_maxrss) * 1024.0;
        RecordProperty("estimate_mb", static_cast<int>(memory.estimate / 1e6));
        RecordProperty("peak_mb", static_cast<int>(memory.peak / 1e6));
        return memory;
    }

    // The estimate bounds the peak, and not by more than twice it (a guard that refuses what fits is no
    // help).
    static void expectBounds(const Memory& m) {
        EXPECT_GE(m.estimate, m.peak)
            << "estimate " << m.estimate / 1e6 << " MB, peak " << m.peak / 1e6 << " MB";
        EXPECT_LT(m.estimate, 2.0 * m.peak)
            << "estimate " << m.estimate / 1e6 << " MB, peak " << m.peak / 1e6 << " MB";
    }
};

const std::vector<std::string> kSmallVolumes = {"options.volume.resolution=16", "options.rsm.resolution=64"};

std::vector<std::string> with(std::vector<std::string> overrides, const std::vector<std::string>& more) {
    overrides.insert(overrides.end(), more.begin(), more.end());
    return overrides;
}

TEST_F(MemoryGuardTest, BoundsTheFrameImagesAtOneAndSixteenSamplesPerPixel) {
    expectBounds(measure(with(
        kSmallVolumes, {"camera.width=1024", "camera.height=1024", "options.render.samples_per_pixel=1"})));
    expectBounds(measure(with(
        kSmallVolumes, {"camera.width=512", "camera.height=512", "options.render.samples_per_pixel=16"})));
}

TEST_F(MemoryGuardTest, BoundsTheVolumes) {
    expectBounds(measure({"camera.width=64", "camera.height=64", "options.volume.resolution=128"}));
}

// A sphere of 1024 segments: a million triangles, about 270 MB as rendered.
TEST_F(MemoryGuardTest, CountsTheTrianglesOfShapes) {
    const std::vector<std::string> small = with(kSmallVolumes, {"camera.width=64", "camera.height=64"});
    const Memory sphere = measure(with(small, {"virtual.0.shape.segments=1024"}));
    expectBounds(sphere);
    const CliResult plain =
        run("info " + quote((fs::path(kSourceDir) / "examples" / "cornell-box.json").string()) +
            " --json --set camera.width=64 --set camera.height=64 --set options.volume.resolution=16 --set "
            "options.rsm.resolution=64");
    ASSERT_EQ(plain.exitCode, 0) << plain.err;
    EXPECT_GT(sphere.estimate - json::parse(plain.out).at("render_memory_bytes").get<double>(), 250e6);
}

}  // namespace
}  // namespace deltagi::test
