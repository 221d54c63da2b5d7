// The scene file's "options", one description per option (option_table.cpp): its key, the member of Options
// it sets, the values it takes, its unit and its doc. Its default is that of a default-constructed Options.
// readOptions and optionsToJson read and write the options through it, and the options tables of
// docs/scene-format.md are made from it (option_docs.cpp; tests/scene/option_table_test.cpp checks them).
#pragma once

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/options.h"
#include "scene/json_reader.h"

namespace deltagi {

// The scene file's name of each value of an option that chooses a method.
template <typename Enum>
struct EnumName {
    Enum value;
    std::string_view name;
};
inline constexpr EnumName<ShadowMethod> kShadowMethodNames[] = {{ShadowMethod::Rays, "rays"},
                                                                {ShadowMethod::Cones, "cones"}};
inline constexpr EnumName<ConeAccumulation> kConeAccumulationNames[] = {
    {ConeAccumulation::Paper, "paper"}, {ConeAccumulation::FrontToBack, "front_to_back"}};
inline constexpr EnumName<RelightCones> kRelightConesNames[] = {{RelightCones::Differential, "differential"},
                                                                {RelightCones::DeltaVolume, "delta_volume"}};
inline constexpr EnumName<RelightObjectLight> kRelightObjectLightNames[] = {
    {RelightObjectLight::Cones, "cones"}, {RelightObjectLight::Rays, "rays"}};
inline constexpr EnumName<ExtractionMethod> kExtractionMethodNames[] = {
    {ExtractionMethod::MedianCut, "median_cut"},
    {ExtractionMethod::VarianceMinimization, "variance_minimization"}};

// The name of `value` in `table`.
template <typename Enum, size_t N>
std::string_view nameOf(const EnumName<Enum> (&table)[N], Enum value) {
    for (const EnumName<Enum>& entry : table)
        if (entry.value == value) return entry.name;
    return {};  // not reached: every value has a name (tests/scene/option_table_test.cpp)
}

// One option: options.GROUP.KEY.
struct OptionInfo {
    std::string group, key;   // "render", "temporal_frames"
    std::string type;         // the values it takes, for the docs: "integer in [1, 8]", `"rays"` or `"cones"`
    std::string unit;         // "frames", "degrees"; empty for a ratio, a switch or a choice
    std::string defaultNote;  // what the default stands for where its value does not say: "8 at 640x480"
    std::string doc;          // one paragraph of markdown
    // Reads the option's value at `node` into `options`: InputError naming the key unless it is of the type
    // and in the range.
    std::function<void(const JsonNode& node, Options& options)> read;
    std::function<nlohmann::json(const Options& options)> write;
};

// The options of one object of "options" (options.render), in the order of the docs.
struct OptionGroup {
    std::string name;
    std::vector<OptionInfo> options;
    // Checks between the group's options once all are read (both or neither, at most), given the group's
    // object; empty where there are none.
    std::function<void(const JsonNode& node, const Options& options)> check;
};

// Every option, group by group.
const std::vector<OptionGroup>& optionTable();

// Reads the "options" object into Options: every key must be in optionTable(); the others keep their
// defaults.
Options readOptions(const JsonNode& node);

}  // namespace deltagi
