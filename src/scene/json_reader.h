// Reading JSON values with their path, so that every error names the file and the key:
//   scene.json: options.volume.resolution: expected a power of two in [4, 1024], got 100
// The scene file's "options" are read through them by option_table.h.
#pragma once

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/options.h"
#include "deltagi/scene.h"

namespace deltagi {

// An interval of allowed numbers, for messages such as "expected a number in (0, 180), got 200".
struct Interval {
    double lo, hi;
    bool loOpen = false, hiOpen = false;
    bool contains(double v) const { return (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi); }
    std::string str() const;  // "[0, 1]", "(0, 180)", "[0, inf)"
};
inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr Interval kAnyNumber{-kInf, kInf, true, true};
inline constexpr Interval kNonNegative{0.0, kInf, false, true};
inline constexpr Interval kPositive{0.0, kInf, true, true};
inline constexpr Interval kUnit{0.0, 1.0};
// The largest radiance or intensity a scene may give (a light's intensity times its colour, an emission, an
// environment map's pixels times its intensity). The renderer computes in 32-bit floats (at most 3.4e38):
// this leaves 18 orders of magnitude for the inverse square law, cosines and sums, where a light of 3e38
// overflowed to a black image. Compared as a float, so that 1e20 itself is allowed.
inline constexpr double kMaxRadiance = 1e20;

// A view of one JSON value together with where it is: the file (for messages) and its JSON path
// ("scene[2].material.albedo"). The value is referenced, not copied: the document must outlive the node.
class JsonNode {
  public:
    JsonNode(const nlohmann::json& value, std::string file, std::string path = {})
        : value_(&value), file_(std::move(file)), path_(std::move(path)) {}

    const nlohmann::json& value() const { return *value_; }
    const std::string& file() const { return file_; }
    const std::string& path() const { return path_; }
    // "file: path" (or "file" at the top level): the `where` of an InputError.
    std::string where() const;
    [[noreturn]] void fail(const std::string& what) const;

    // Objects. child() fails when the key is missing; find() returns nothing.
    void requireObject() const;
    bool has(std::string_view key) const;
    JsonNode child(std::string_view key) const;
    std::optional<JsonNode> find(std::string_view key) const;
    // Fails, naming the key's path, at the first key not in `allowed`.
    void allowKeys(std::span<const std::string_view> allowed) const;
    void allowKeys(std::initializer_list<std::string_view> allowed) const {
        allowKeys(std::span(allowed.begin(), allowed.size()));
    }
    // A path below this node that need not exist, for messages: "camera" -> "camera.fx".
    std::string childWhere(std::string_view key) const;

    // Arrays.
    void requireArray() const;
    size_t size() const { return value_->size(); }
    JsonNode element(size_t index) const;

    // Scalars. Numbers must be finite as a float; integers must be JSON integers (64 is, 64.0 is not).
    double number(const Interval& range = kAnyNumber) const;
    float floatNumber(const Interval& range = kAnyNumber) const { return static_cast<float>(number(range)); }
    int64_t integer64() const;
    int integer(int lo, int hi) const;
    bool boolean() const;
    std::string string() const;
    // [x, y, z], each component in `range`.
    glm::vec3 vec3(const Interval& range = kAnyNumber) const;
    // A colour: [r, g, b] or one number for grey.
    glm::vec3 colour(const Interval& range) const;
    // A 4x4 matrix written as 4 rows of 4 numbers (row-major, as printed); returned in glm's column-major.
    glm::mat4 matrix4() const;

  private:
    const nlohmann::json* value_;
    std::string file_;
    std::string path_;
};

// Parses JSON text strictly, for scene files and --set values: at most kMaxJsonDepth levels of nested arrays
// and objects, and no key twice in one object. Throws InputError naming `file` (and, for a syntax error or a
// number out of range, the line and column) and the JSON path of the key where the problem is.
inline constexpr size_t kMaxJsonDepth = 128;
nlohmann::json parseJson(const std::string& text, const std::string& file);

// Name of a JSON value's type for messages: "a string", "an array", "an integer", "a number", ...
std::string describeType(const nlohmann::json& value);
// The value itself, shortened for messages.
std::string describeValue(const nlohmann::json& value);

// A file named by `node` (a string), relative to the scene file's folder; it must exist (the message points
// at the project's shared data set when the path runs through a "shared" folder).
std::filesystem::path inputFile(const JsonNode& node, const std::filesystem::path& sceneFolder);

// Estimated peak memory of a render: the program itself, the four volumes with their mip chains, two cube
// RSMs per light (the scene's and the update with the objects) at the largest resolution
// options.rsm.resolution gives it (rsmResolutionCeiling: `lightCount` point and spot lights,
// `directionalCount` directional ones, the environment's included), the frame's images (per pixel and per
// sample) and the meshes' `triangles`; the constants are measured peaks of `deltagi render`, which the
// estimate bounds (tests/cli/memory_guard_test.cpp). checkRenderMemory fails, naming `file` and the key that
// dominates (volume or RSM resolution, the camera or the meshes), when the estimate exceeds
// `physicalMemoryBytes` (a parameter so that tests can lower it).
uint64_t estimateRenderMemory(const Options& options, const Camera& camera, size_t lightCount,
                              size_t directionalCount = 0, uint64_t triangles = 0);
void checkRenderMemory(const Options& options, const Camera& camera, size_t lightCount,
                       uint64_t physicalMemoryBytes, const std::string& file, size_t directionalCount = 0,
                       uint64_t triangles = 0);
// sysconf(_SC_PHYS_PAGES) * sysconf(_SC_PAGE_SIZE).
uint64_t physicalMemoryBytes();

// A lens distortion of `model` whose coefficients (k1..k4, p1, p2; 0 when absent) `coefficient(key)` reads:
// the scene file's camera.distortion and a transforms file's (globally or per frame) read them alike.
template <typename Coefficient>
LensDistortion lensDistortion(LensDistortion::Model model, Coefficient&& coefficient) {
    LensDistortion d;
    d.model = model;
    if (model == LensDistortion::Model::None) return d;
    d.k1 = coefficient("k1"), d.k2 = coefficient("k2"), d.k3 = coefficient("k3");
    if (model == LensDistortion::Model::OpenCV) d.p1 = coefficient("p1"), d.p2 = coefficient("p2");
    if (model == LensDistortion::Model::Fisheye) d.k4 = coefficient("k4");
    return d;
}

}  // namespace deltagi
