#include "scene/json_reader.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"

namespace deltagi {

using nlohmann::json;

std::string Interval::str() const {
    auto bound = [](double v) {
        return std::isinf(v) ? std::string(v < 0 ? "-inf" : "inf") : fmt::format("{}", v);
    };
    return fmt::format("{}{}, {}{}", loOpen ? '(' : '[', bound(lo), bound(hi), hiOpen ? ')' : ']');
}

// ---- parsing ----------------------------------------------------------------------------------------------

namespace {

// nlohmann's DOM builder behind a SAX filter that tracks the JSON path of the value being read, so that
// errors can name the key, and that refuses deep nesting and repeated keys.
class StrictJsonSax {
  public:
    StrictJsonSax(json& result, const std::string& file)
        : dom_(result, /*allow_exceptions=*/true), file_(file) {}

    bool null() { return value(dom_.null()); }
    bool boolean(bool v) { return value(dom_.boolean(v)); }
    bool number_integer(json::number_integer_t v) { return value(dom_.number_integer(v)); }
    bool number_unsigned(json::number_unsigned_t v) { return value(dom_.number_unsigned(v)); }
    bool number_float(json::number_float_t v, const json::string_t& text) {
        return value(dom_.number_float(v, text));
    }
    bool string(json::string_t& v) { return value(dom_.string(v)); }
    bool binary(json::binary_t& v) { return value(dom_.binary(v)); }
    bool start_object(std::size_t size) {
        enter(false);
        return dom_.start_object(size);
    }
    bool key(json::string_t& key) {
        Frame& frame = frames_.back();
        frame.key = key;
        if (!frame.keys.insert(key).second)
            throw InputError(where(), "duplicate key: each key may appear only once in an object");
        return dom_.key(key);
    }
    bool end_object() {
        frames_.pop_back();
        return value(dom_.end_object());
    }
    bool start_array(std::size_t size) {
        enter(true);
        return dom_.start_array(size);
    }
    bool end_array() {
        frames_.pop_back();
        return value(dom_.end_array());
    }
    // `position` is the lexer's position_t (line and column) when called by the parser.
    template <typename Position, typename Exception>
    bool parse_error(const Position& position, const std::string& token, const Exception& error) {
        std::string at;
        if constexpr (requires { position.lines_read; })
            at = fmt::format("{}: line {}, column {}", file_, position.lines_read + 1,
                             position.chars_read_current_line);
        else
            at = fmt::format("{}: byte {}", file_, position);
        if (error.id == 406) {  // a number that overflows a double, e.g. 1e999
            std::string path = this->path();
            throw InputError(path.empty() ? at : at + ": " + path,
                             fmt::format("the number {} is out of range: expected a finite number",
                                         token.substr(0, kMaxTokenChars)));
        }
        // nlohmann's message reads "[json.exception.parse_error.101] parse error at line 3, column 5:
        // <what>". Found without std::regex, whose matching recurses once per character: a long token in the
        // message (an unterminated string of megabytes) overflowed the stack.
        std::string message = error.what();
        if (const size_t line = message.find("at line "); line != std::string::npos)
            if (const size_t column = message.find(", column ", line); column != std::string::npos)
                if (const size_t colon = message.find(": ", column); colon != std::string::npos)
                    message = message.substr(colon + 2);
        throw InputError(at, message);
    }

  private:
    static constexpr size_t kMaxTokenChars = 40;
    struct Frame {
        bool array;
        size_t index = 0;  // arrays: the element being read
        std::string key;   // objects: the key being read
        std::unordered_set<std::string> keys;
    };

    void enter(bool array) {
        if (frames_.size() >= kMaxJsonDepth)
            throw InputError(where(), fmt::format("arrays and objects are nested more than {} levels deep",
                                                  kMaxJsonDepth));
        frames_.push_back(Frame{array, 0, {}, {}});
    }
    // A value is complete: the next element of an array has the next index.
    bool value(bool keepGoing) {
        if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
        return keepGoing;
    }
    std::string path() const {
        std::string result;
        for (const Frame& frame : frames_) {
            if (frame.array)
                result += fmt::format("[{}]", frame.index);
            else if (!frame.keys.empty())
                result += (result.empty() ? "" : ".") + frame.key;
            if (result.size() > 60) return result.substr(0, 57) + "...";
        }
        return result;
    }
    std::string where() const {
        std::string path = this->path();
        return path.empty() ? file_ : file_ + ": " + path;
    }

    nlohmann::detail::json_sax_dom_parser<json> dom_;
    const std::string& file_;
    std::vector<Frame> frames_;
};

}  // namespace

json parseJson(const std::string& text, const std::string& file) {
    json result;
    StrictJsonSax sax(result, file);
    json::sax_parse(text, &sax);
    return result;
}

std::string describeType(const json& value) {
    switch (value.type()) {
        case json::value_t::null:
            return "null";
        case json::value_t::boolean:
            return "a boolean";
        case json::value_t::number_integer:
        case json::value_t::number_unsigned:
            return "an integer";
        case json::value_t::number_float:
            return "a number";
        case json::value_t::string:
            return "a string";
        case json::value_t::array:
            return "an array";
        case json::value_t::object:
            return "an object";
        default:
            return "an unsupported value";
    }
}

std::string describeValue(const json& value) {
    constexpr size_t kMaxChars = 40;  // keep messages on one readable line
    std::string text = value.dump();
    if (text.size() > kMaxChars) text = text.substr(0, kMaxChars - 3) + "...";
    return describeType(value) + " " + text;
}

std::string JsonNode::where() const {
    return path_.empty() ? file_ : file_ + ": " + path_;
}

void JsonNode::fail(const std::string& what) const {
    throw InputError(where(), what);
}

std::string JsonNode::childWhere(std::string_view key) const {
    return file_ + ": " + (path_.empty() ? std::string(key) : path_ + "." + std::string(key));
}

void JsonNode::requireObject() const {
    if (!value_->is_object()) fail("expected an object {...}, got " + describeValue(*value_));
}

bool JsonNode::has(std::string_view key) const {
    requireObject();
    return value_->contains(key);
}

JsonNode JsonNode::child(std::string_view key) const {
    if (!has(key)) throw InputError(childWhere(key), "required key is missing");
    return *find(key);
}

std::optional<JsonNode> JsonNode::find(std::string_view key) const {
    requireObject();
    auto it = value_->find(key);
    if (it == value_->end()) return std::nullopt;
    return JsonNode(*it, file_, path_.empty() ? std::string(key) : path_ + "." + std::string(key));
}

void JsonNode::allowKeys(std::span<const std::string_view> allowed) const {
    requireObject();
    for (const auto& item : value_->items()) {
        if (std::find(allowed.begin(), allowed.end(), item.key()) != allowed.end()) continue;
        std::string list;
        for (std::string_view key : allowed) list += (list.empty() ? "" : ", ") + std::string(key);
        throw InputError(childWhere(item.key()), "unknown key; expected one of: " + list);
    }
}

void JsonNode::requireArray() const {
    if (!value_->is_array()) fail("expected an array [...], got " + describeValue(*value_));
}

JsonNode JsonNode::element(size_t index) const {
    requireArray();
    return JsonNode((*value_)[index], file_, fmt::format("{}[{}]", path_, index));
}

double JsonNode::number(const Interval& range) const {
    if (!value_->is_number()) fail("expected a number, got " + describeValue(*value_));
    double v = value_->get<double>();
    // The renderer works in float: a value that overflows a float is as unusable as an infinite one.
    if (!std::isfinite(v) || std::abs(v) > std::numeric_limits<float>::max())
        fail("expected a finite number (within the range of a 32-bit float), got " + value_->dump());
    if (!range.contains(v)) fail(fmt::format("expected a number in {}, got {}", range.str(), v));
    // ... and as the float it becomes: 1e-320 is > 0, but 0 as a float.
    const double asFloat = static_cast<float>(v);
    if (!range.contains(asFloat))
        fail(fmt::format("expected a number in {}, got {}, which is {} as a 32-bit float", range.str(), v,
                         asFloat));
    return v;
}

int64_t JsonNode::integer64() const {
    if (value_->is_number_float())
        fail("expected an integer (written without a fraction or exponent), got " + value_->dump());
    if (!value_->is_number_integer()) fail("expected an integer, got " + describeValue(*value_));
    if (value_->is_number_unsigned() && value_->get<uint64_t>() > uint64_t{INT64_MAX})
        fail("expected an integer, got " + value_->dump() + ", which is too large");
    return value_->get<int64_t>();
}

int JsonNode::integer(int lo, int hi) const {
    int64_t v = integer64();
    if (v < lo || v > hi) fail(fmt::format("expected an integer in [{}, {}], got {}", lo, hi, v));
    return static_cast<int>(v);
}

bool JsonNode::boolean() const {
    if (!value_->is_boolean()) fail("expected true or false, got " + describeValue(*value_));
    return value_->get<bool>();
}

std::string JsonNode::string() const {
    if (!value_->is_string()) fail("expected a string, got " + describeValue(*value_));
    return value_->get<std::string>();
}

glm::vec3 JsonNode::vec3(const Interval& range) const {
    if (!value_->is_array() || value_->size() != 3)
        fail("expected an array of 3 numbers [x, y, z], got " + describeValue(*value_));
    return {element(0).floatNumber(range), element(1).floatNumber(range), element(2).floatNumber(range)};
}

glm::vec3 JsonNode::colour(const Interval& range) const {
    if (value_->is_number()) return glm::vec3(floatNumber(range));
    if (!value_->is_array() || value_->size() != 3)
        fail("expected [r, g, b] or one number, got " + describeValue(*value_));
    return vec3(range);
}

glm::mat4 JsonNode::matrix4() const {
    auto isRow = [](const json& row) { return row.is_array() && row.size() == 4; };
    if (!value_->is_array() || value_->size() != 4 || !std::all_of(value_->begin(), value_->end(), isRow))
        fail("expected a 4x4 matrix as 4 rows of 4 numbers, got " + describeValue(*value_));
    glm::mat4 m(1.0f);
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col)
            m[col][row] = element(row).element(col).floatNumber();  // glm: m[col]
    return m;
}

// ---- memory estimate --------------------------------------------------------------------------------------

namespace {

// Per voxel of the volumes' finest level: the three volumes stored whole with their mip chains take 27 bytes
// (3 x 4 bfloat16 x 8/7), but a render's peak holds about 95-105 (measured at 128^3 and 256^3: the real
// scene's area and injected light in floats, its occupancy, the packed light its bounce gathers from and the
// packed full and delta volumes beside the volumes), rounded up.
constexpr double kBytesPerVoxel = 112.0;
constexpr double kRsmFaces = 6.0;  // a cube map per light (the worst case: point lights)
// Per light, the map of the scene alone and the update of its texels that meet the objects (in the worst
// case, all of them): about 155 MB per light at the default 512^2, as measured (issue 11).
constexpr double kRsmMapsPerLight = 2.0;
constexpr double kBytesPerRsmTexel = 48.0;  // position, normal, flux (3 floats each) and depth, padded
// The frame's images, measured as peaks of `deltagi render` (tests/cli/memory_guard_test.cpp): about 505
// bytes per pixel at 1 sample per pixel (the G-buffers of the scene with and without the objects, the cone
// tracing's and the filters' images, the layers and the outputs), 7-9 more per further sample (the objects'
// sub-pixel surfaces, 96 bytes each, kept for the pixels that show them: the Cornell box's ball and ring),
// rounded up.
constexpr double kBytesPerPixel = 512.0;
constexpr double kBytesPerSample = 12.0;
// A triangle as rendered, measured alike (about 250 bytes): the mesh, its object-space copy, Embree's BVH.
constexpr double kBytesPerTriangle = 256.0;
// The program, its libraries, its threads and the images of a small frame.
constexpr double kBaseBytes = 200.0e6;
constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

struct MemoryParts {
    double volumes, rsms, gbuffer, meshes;
    double total() const { return kBaseBytes + volumes + rsms + gbuffer + meshes; }
};

MemoryParts memoryParts(const Options& options, const Camera& camera, size_t lightCount,
                        size_t directionalCount, uint64_t triangles) {
    const double r = options.volume.resolution;
    // Each light's largest map: the importance of "auto" only makes some smaller.
    auto texels = [&](bool directional) {
        const double side =
            rsmResolutionCeiling(options.rsm.resolution, options.volume.resolution, directional);
        return side * side * kRsmFaces * kRsmMapsPerLight;
    };
    return {kBytesPerVoxel * r * r * r,
            kBytesPerRsmTexel * (texels(false) * static_cast<double>(lightCount) +
                                 texels(true) * static_cast<double>(directionalCount)),
            static_cast<double>(camera.width) * camera.height *
                (kBytesPerPixel + kBytesPerSample * options.render.samplesPerPixel),
            static_cast<double>(triangles) * kBytesPerTriangle};
}

}  // namespace

uint64_t estimateRenderMemory(const Options& options, const Camera& camera, size_t lightCount,
                              size_t directionalCount, uint64_t triangles) {
    return static_cast<uint64_t>(
        memoryParts(options, camera, lightCount, directionalCount, triangles).total());
}

void checkRenderMemory(const Options& options, const Camera& camera, size_t lightCount,
                       uint64_t physicalMemoryBytes, const std::string& file, size_t directionalCount,
                       uint64_t triangles) {
    MemoryParts parts = memoryParts(options, camera, lightCount, directionalCount, triangles);
    if (parts.total() <= static_cast<double>(physicalMemoryBytes)) return;
    // Name what dominates: the G-buffer grows with the camera's resolution (and
    // options.render.samples_per_pixel).
    std::string key = parts.rsms > parts.volumes ? "options.rsm.resolution" : "options.volume.resolution";
    std::string what;
    if (parts.gbuffer > std::max({parts.rsms, parts.volumes, parts.meshes})) {
        key = "camera";
        what = fmt::format("{}x{} pixels at {} samples per pixel: ", camera.width, camera.height,
                           options.render.samplesPerPixel);
    } else if (parts.meshes > std::max(parts.rsms, parts.volumes)) {
        key = "meshes";
        what = fmt::format("{} triangles: ", triangles);
    }
    throw InputError(
        file + ": " + key,
        what +
            fmt::format("the render needs about {:.1f} GiB (volumes {:.1f} GiB, reflective shadow maps "
                        "{:.1f} GiB, frame images {:.1f} GiB, meshes {:.1f} GiB), more than the {:.1f} GiB "
                        "of physical memory",
                        parts.total() / kGiB, parts.volumes / kGiB, parts.rsms / kGiB, parts.gbuffer / kGiB,
                        parts.meshes / kGiB, static_cast<double>(physicalMemoryBytes) / kGiB));
}

uint64_t physicalMemoryBytes() {
    long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || pageSize <= 0) return std::numeric_limits<uint64_t>::max();  // unknown: do not refuse
    return static_cast<uint64_t>(pages) * static_cast<uint64_t>(pageSize);
}

}  // namespace deltagi
