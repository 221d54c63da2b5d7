// The scene file's names of the options that choose a method, one table per enum, for reading and writing.
#pragma once

#include <string_view>

#include "deltagi/options.h"

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
    return {};
}

}  // namespace deltagi
