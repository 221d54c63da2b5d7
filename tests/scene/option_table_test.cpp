// The one description of each option (src/scene/option_table.cpp): every option reads back what
// optionsToJson writes, every name of a choice reads back as its value, and the options tables of
// docs/scene-format.md are the table's.
#include "scene/option_table.h"

#include <filesystem>
#include <set>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "test_errors.h"
#include "test_files.h"
#include "test_paths.h"

namespace deltagi {
namespace {

using nlohmann::json;
using test::expectContains;
using test::inputErrorOf;

Options readBack(const json& written) {
    return readOptions(JsonNode(written, "written", "options"));
}

// Every option away from its default, in range.
Options everyOptionChanged() {
    Options o;
    o.volume = {.resolution = 64,
                .extentScale = 3.0f,
                .reachScale = 0.0f,
                .center = glm::vec3(1, 2, 3),
                .size = 5.0f,
                .viewpoint = glm::vec3(-1, 0.5f, 2)};
    o.rsm.resolution = 300;
    o.diffuse = {.count = 16,
                 .apertureDeg = 60.0f,
                 .objectApertureDeg = 0.0f,
                 .pixelStride = 2,
                 .relightPixelStride = 32,
                 .objectRays = 0,
                 .objectRayPixelStride = 4,
                 .objectGatherRays = 0};
    o.specular = {.minApertureDeg = 10.0f, .maxApertureDeg = 45.0f, .relightPixelStride = 1};
    o.shadow = {.method = ShadowMethod::Cones,
                .raySamples = 9,
                .areaRaySamples = 1,
                .apertureDeg = 90.0f,
                .pixelStride = 4,
                .relightPixelStride = 8};
    o.trace = {.stepScale = 0.25f,
               .startOffset = 0.0f,
               .maxOcclusion = 0.5f,
               .normalWeight = 0.5f,
               .backfaceWeight = 0.0f,
               .jitter = 0.25f,
               .accumulation = ConeAccumulation::Paper};
    o.render = {.samplesPerPixel = 16,
                .indirect = false,
                .doubleShadowFix = false,
                .relightIndirect = false,
                .temporalFrames = 1,
                .relightCones = RelightCones::DeltaVolume,
                .relightObjectLight = RelightObjectLight::Cones,
                .layers = true,
                .lightBounces = 8,
                .bounceTail = false,
                .bounceCones = 7,
                .bounceRays = 9,
                .denoiseRadius = 0,
                .relightDenoiseRadius = 3,
                .refineBudget = 0.05f};
    o.environment = {.lightCount = 0,
                     .extraction = ExtractionMethod::VarianceMinimization,
                     .sky = false,
                     .maxLightApertureDeg = 179.0f};
    return o;
}

TEST(OptionTable, EveryOptionReadsBackWhatIsWritten) {
    const Options changed = everyOptionChanged(), defaults;
    // everyOptionChanged() changes every option of the table: a new option needs a value there too.
    for (const OptionGroup& group : optionTable())
        for (const OptionInfo& option : group.options)
            EXPECT_NE(option.write(changed), option.write(defaults))
                << "options." << group.name << "." << option.key << " is not changed by everyOptionChanged()";
    // A member of Options without its option in the table would come back with its default.
    EXPECT_TRUE(readBack(optionsToJson(changed)) == changed) << optionsToJson(changed).dump();
    EXPECT_TRUE(readBack(optionsToJson(defaults)) == defaults);
    EXPECT_TRUE(readBack(json::object()) == defaults);
}

TEST(OptionTable, EachOptionIsDescribedOnce) {
    std::set<std::string> groups, paths;
    size_t count = 0;
    for (const OptionGroup& group : optionTable()) {
        EXPECT_TRUE(groups.insert(group.name).second) << group.name;
        for (const OptionInfo& option : group.options) {
            const std::string path = group.name + "." + option.key;
            EXPECT_EQ(option.group, group.name);
            EXPECT_TRUE(paths.insert(path).second) << path << " is described twice";
            EXPECT_FALSE(option.type.empty() || option.doc.empty()) << path;
            // One row of a markdown table: no line break and no column separator.
            for (const std::string& text : {option.type, option.unit, option.defaultNote, option.doc})
                EXPECT_EQ(text.find_first_of("|\n"), std::string::npos) << path << ": " << text;
            ++count;
        }
    }
    EXPECT_EQ(count, 50u);  // the fields of the 8 structs of options.h
}

// options.render.refine_budget: "auto" (written as such) or a share of the pixels in [0, 0.25]; anything else
// is refused with the key and what it takes.
TEST(OptionTable, TheRefineBudgetIsAutoOrAShareOfThePixels) {
    EXPECT_LT(readBack({{"render", {{"refine_budget", "auto"}}}}).render.refineBudget, 0.0f);
    EXPECT_EQ(optionsToJson(Options{})["render"]["refine_budget"], "auto");
    EXPECT_EQ(readBack({{"render", {{"refine_budget", 0.02}}}}).render.refineBudget, 0.02f);
    EXPECT_EQ(readBack({{"render", {{"refine_budget", 0}}}}).render.refineBudget, 0.0f);
    for (const json& bad : {json("more"), json(-0.1), json(0.5), json(true)})
        expectContains(inputErrorOf([&] {
                           readBack({{"render", {{"refine_budget", bad}}}});
                       }),
                       {"written: options.render.refine_budget: expected"});
}

// options.diffuse.object_gather_rays: "auto" (written as such, the default; a still's 36 rays, a session
// frame's 32), 0 (the cones) or a count up to 256.
TEST(OptionTable, TheObjectsGatherRaysAreAutoOrACount) {
    EXPECT_EQ(optionsToJson(Options{})["diffuse"]["object_gather_rays"], "auto");
    const DiffuseConeOptions automatic = readBack({{"diffuse", {{"object_gather_rays", "auto"}}}}).diffuse;
    EXPECT_LT(automatic.objectGatherRays, 0);
    EXPECT_EQ(objectGatherRaysFor(automatic, true), kAutoStillObjectGatherRays);
    EXPECT_EQ(objectGatherRaysFor(automatic, false), kAutoObjectGatherRays);
    for (int rays : {0, 64}) {
        const DiffuseConeOptions given = readBack({{"diffuse", {{"object_gather_rays", rays}}}}).diffuse;
        EXPECT_EQ(objectGatherRaysFor(given, true), rays);
        EXPECT_EQ(objectGatherRaysFor(given, false), rays);
        EXPECT_EQ(optionsToJson(Options{.diffuse = given})["diffuse"]["object_gather_rays"], rays);
    }
    for (const json& bad : {json("many"), json(-1), json(257), json(2.5)})
        expectContains(inputErrorOf([&] {
                           readBack({{"diffuse", {{"object_gather_rays", bad}}}});
                       }),
                       {"written: options.diffuse.object_gather_rays: expected"});
}

// Each name of `names` reads back as its value and is written as itself, and each value of the enum (in
// order, 0 to N - 1) has one.
template <typename Enum, size_t N, typename Member>
void expectNamesReadBack(const EnumName<Enum> (&names)[N], const std::string& group, const std::string& key,
                         Member member) {
    for (size_t i = 0; i < N; ++i) {
        EXPECT_EQ(names[i].value, static_cast<Enum>(i)) << group << "." << key << ": " << names[i].name;
        const Options read = readBack({{group, {{key, names[i].name}}}});
        EXPECT_EQ(member(read), names[i].value) << names[i].name;
        EXPECT_EQ(optionsToJson(read)[group][key], names[i].name);
        EXPECT_EQ(nameOf(names, names[i].value), names[i].name);
    }
    const std::string message = inputErrorOf([&] { readBack({{group, {{key, "none_of_them"}}}}); });
    expectContains(message, {"written: options." + group + "." + key + ": expected", "got \"none_of_them\""});
    for (const EnumName<Enum>& name : names) expectContains(message, fmt::format("\"{}\"", name.name));
}

TEST(OptionTable, EachNameOfAChoiceReadsBack) {
    expectNamesReadBack(kShadowMethodNames, "shadow", "method",
                        [](const Options& o) { return o.shadow.method; });
    expectNamesReadBack(kConeAccumulationNames, "trace", "accumulation",
                        [](const Options& o) { return o.trace.accumulation; });
    expectNamesReadBack(kRelightConesNames, "render", "relight_cones",
                        [](const Options& o) { return o.render.relightCones; });
    expectNamesReadBack(kRelightObjectLightNames, "render", "relight_object_light",
                        [](const Options& o) { return o.render.relightObjectLight; });
    expectNamesReadBack(kExtractionMethodNames, "environment", "extraction",
                        [](const Options& o) { return o.environment.extraction; });
}

// The first line where `a` and `b` differ, both shown; "" when they are the same.
std::string firstDifference(const std::string& a, const std::string& b) {
    std::istringstream inA(a), inB(b);
    std::string lineA, lineB;
    for (int line = 1;; ++line) {
        const bool moreA = static_cast<bool>(std::getline(inA, lineA)),
                   moreB = static_cast<bool>(std::getline(inB, lineB));
        if (!moreA && !moreB) return a == b ? "" : "the files' ends differ";
        if (!moreA || !moreB || lineA != lineB)
            return fmt::format("line {}:\n  docs: {}\n  code: {}", line, moreA ? lineA : "(end)",
                               moreB ? lineB : "(end)");
    }
}

TEST(OptionTable, DocsTablesAreTheCodesTables) {
    const std::filesystem::path file = std::filesystem::path(test::kSourceDir) / "docs" / "scene-format.md";
    const std::string docs = test::readText(file);
    ASSERT_FALSE(docs.empty()) << file;
    EXPECT_EQ(firstDifference(docs, withOptionTables(docs, file.string())), "")
        << "docs/scene-format.md's options tables differ from src/scene/option_table.cpp: "
           "scripts/update-options-doc.sh makes them anew";
}

// The check above can fail: a wrong default, a table left out, a group that does not exist.
TEST(OptionTable, DocsCheckFindsWhatDiffers) {
    const std::string docs = "# Options\n\n" + optionTablesMarkdown();
    EXPECT_EQ(withOptionTables(docs, "docs.md"), docs);

    const std::string count = fmt::format("| cones | `{}` |", Options{}.diffuse.count);
    std::string wrong = docs;
    wrong.replace(wrong.find(count), count.size(),
                  fmt::format("| cones | `{}` |", Options{}.diffuse.count + 1));
    EXPECT_NE(firstDifference(wrong, withOptionTables(wrong, "docs.md")), "");

    const std::string render = "<!-- options table: render -->";
    std::string missing = docs;
    missing.erase(missing.find(render), render.size());
    expectContains(inputErrorOf([&] { withOptionTables(missing, "docs.md"); }),
                   {"docs.md", "no table of options.render"});
    std::string unknown = docs;
    unknown.replace(unknown.find(render), render.size(), "<!-- options table: lighting -->");
    expectContains(inputErrorOf([&] { withOptionTables(unknown, "docs.md"); }),
                   {"docs.md: line", "no options group 'lighting'"});
    const std::string end = "<!-- end of options table -->";
    std::string open = docs;
    open.erase(open.rfind(end), end.size());
    expectContains(inputErrorOf([&] { withOptionTables(open, "docs.md"); }),
                   {"docs.md: line", "options.environment has no"});
    expectContains(inputErrorOf([&] { withOptionTables(docs + docs, "docs.md"); }),
                   {"a second table of options.volume"});
}

}  // namespace
}  // namespace deltagi
