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
#include "scene/option_table.h"

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

void JsonNode::allowKeys(std::initializer_list<std::string_view> allowed) const {
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

// ---- options ----------------------------------------------------------------------------------------------

namespace {

bool isPowerOfTwo(int64_t v) {
    return v > 0 && (v & (v - 1)) == 0;
}

// The value of `table` that `node` names: InputError listing the names otherwise.
template <typename Enum, size_t N>
Enum readName(const JsonNode& node, const EnumName<Enum> (&table)[N]) {
    const std::string name = node.string();
    std::string expected;
    for (size_t i = 0; i < N; ++i) {
        if (table[i].name == name) return table[i].value;
        expected += fmt::format("{}\"{}\"", i == 0 ? "" : i + 1 == N ? " or " : ", ", table[i].name);
    }
    node.fail(fmt::format("expected {}, got \"{}\"", expected, name));
}

constexpr int kMinVolumeResolution = 4, kMaxVolumeResolution = 1024;

void readVolume(const JsonNode& node, VolumeOptions& volume) {
    node.allowKeys({"resolution", "extent_scale", "reach_scale", "center", "size", "viewpoint"});
    if (auto n = node.find("resolution")) {
        int64_t r = n->integer64();
        if (!isPowerOfTwo(r) || r < kMinVolumeResolution || r > kMaxVolumeResolution)
            n->fail(fmt::format("expected a power of two in [{}, {}], got {}", kMinVolumeResolution,
                                kMaxVolumeResolution, r));
        volume.resolution = static_cast<int>(r);
    }
    if (auto n = node.find("extent_scale")) volume.extentScale = n->floatNumber(kPositive);
    if (auto n = node.find("reach_scale")) volume.reachScale = n->floatNumber({0.0, 1024.0});
    // null means "not set", so that the output of optionsToJson() reads back.
    auto center = node.find("center"), size = node.find("size");
    if (center && !center->value().is_null()) volume.center = center->vec3();
    if (size && !size->value().is_null()) volume.size = size->floatNumber(kPositive);
    if (auto n = node.find("viewpoint"); n && !n->value().is_null()) volume.viewpoint = n->vec3();
    if (volume.center.has_value() != volume.size.has_value()) {
        if (volume.center) center->fail("given without options.volume.size; give both or neither");
        size->fail("given without options.volume.center; give both or neither");
    }
}

void readTrace(const JsonNode& node, TraceOptions& trace) {
    node.allowKeys({"step_scale", "start_offset", "max_occlusion", "normal_weight", "backface_weight",
                    "jitter", "accumulation"});
    if (auto n = node.find("step_scale")) trace.stepScale = n->floatNumber({0.05, 4.0});
    if (auto n = node.find("start_offset")) trace.startOffset = n->floatNumber({0.0, 16.0});
    if (auto n = node.find("max_occlusion")) trace.maxOcclusion = n->floatNumber({0.5, 1.0});
    if (auto n = node.find("normal_weight")) trace.normalWeight = n->floatNumber(kUnit);
    if (auto n = node.find("backface_weight")) trace.backfaceWeight = n->floatNumber(kUnit);
    if (auto n = node.find("jitter")) trace.jitter = n->floatNumber(kUnit);
    if (auto n = node.find("accumulation")) trace.accumulation = readName(*n, kConeAccumulationNames);
}

void readRender(const JsonNode& node, RenderOptions& render) {
    node.allowKeys({"samples_per_pixel", "indirect", "double_shadow_fix", "relight_indirect", "relight_cones",
                    "light_bounces", "denoise_radius", "relight_object_light", "layers", "temporal_frames"});
    if (auto n = node.find("samples_per_pixel")) {
        int spp = n->integer(1, 16);
        if (spp != 1 && spp != 4 && spp != 9 && spp != 16)
            n->fail(fmt::format("expected 1, 4, 9 or 16 (a square grid), got {}", spp));
        render.samplesPerPixel = spp;
    }
    if (auto n = node.find("indirect")) render.indirect = n->boolean();
    if (auto n = node.find("double_shadow_fix")) render.doubleShadowFix = n->boolean();
    if (auto n = node.find("relight_indirect")) render.relightIndirect = n->boolean();
    if (auto n = node.find("layers")) render.layers = n->boolean();
    if (auto n = node.find("denoise_radius")) render.denoiseRadius = n->integer(0, 8);
    if (auto n = node.find("light_bounces")) render.lightBounces = n->integer(1, 8);
    if (auto n = node.find("temporal_frames")) render.temporalFrames = n->integer(1, 8);
    if (auto n = node.find("relight_cones")) render.relightCones = readName(*n, kRelightConesNames);
    if (auto n = node.find("relight_object_light"))
        render.relightObjectLight = readName(*n, kRelightObjectLightNames);
}

// options.diffuse/shadow.(relight_)pixel_stride: "auto" (0) or a power of two up to 32.
int readPixelStride(const JsonNode& node) {
    if (node.value().is_string()) {
        if (node.string() != "auto")
            node.fail(fmt::format("expected \"auto\" or 1, 2, 4, 8, 16 or 32, got {}",
                                  describeValue(node.value())));
        return 0;
    }
    const int stride = node.integer(1, 32);
    if ((stride & (stride - 1)) != 0) node.fail("must be \"auto\" or 1, 2, 4, 8, 16 or 32");
    return stride;
}

void readEnvironmentOptions(const JsonNode& node, EnvironmentOptions& environment) {
    node.allowKeys({"light_count", "extraction", "sky", "max_light_aperture_deg"});
    if (auto n = node.find("light_count")) environment.lightCount = n->integer(0, 256);
    if (auto n = node.find("extraction")) environment.extraction = readName(*n, kExtractionMethodNames);
    if (auto n = node.find("sky")) environment.sky = n->boolean();
    if (auto n = node.find("max_light_aperture_deg"))
        environment.maxLightApertureDeg = n->floatNumber({0.0, 180.0, true, true});
}

}  // namespace

Options readOptions(const JsonNode& node) {
    node.allowKeys({"volume", "rsm", "diffuse", "specular", "shadow", "trace", "render", "environment"});
    Options options;
    if (auto n = node.find("volume")) readVolume(*n, options.volume);
    if (auto n = node.find("rsm")) {
        n->allowKeys({"resolution"});
        if (auto r = n->find("resolution")) {
            if (r->value().is_string()) {
                if (r->string() != "auto")
                    r->fail(fmt::format("expected \"auto\" or an integer in [16, 8192], got {}",
                                        describeValue(r->value())));
                options.rsm.resolution = 0;
            } else {
                options.rsm.resolution = r->integer(16, 8192);
            }
        }
    }
    if (auto n = node.find("diffuse")) {
        n->allowKeys({"count", "aperture_deg", "object_aperture_deg", "pixel_stride", "relight_pixel_stride",
                      "object_rays"});
        if (auto c = n->find("count")) options.diffuse.count = c->integer(1, 64);
        if (auto r = n->find("object_rays")) options.diffuse.objectRays = r->integer(0, 256);
        if (auto st = n->find("pixel_stride")) options.diffuse.pixelStride = readPixelStride(*st);
        if (auto st = n->find("relight_pixel_stride"))
            options.diffuse.relightPixelStride = readPixelStride(*st);
        if (auto a = n->find("aperture_deg"))
            options.diffuse.apertureDeg = a->floatNumber({0.0, 180.0, false, true});
        if (auto a = n->find("object_aperture_deg"))
            options.diffuse.objectApertureDeg = a->floatNumber({0.0, 180.0, false, true});
    }
    if (auto n = node.find("specular")) {
        n->allowKeys({"min_aperture_deg", "max_aperture_deg", "relight_pixel_stride"});
        if (auto st = n->find("relight_pixel_stride"))
            options.specular.relightPixelStride = readPixelStride(*st);
        constexpr Interval kAperture{0.0, 180.0, true, true};
        if (auto a = n->find("min_aperture_deg")) options.specular.minApertureDeg = a->floatNumber(kAperture);
        if (auto a = n->find("max_aperture_deg")) options.specular.maxApertureDeg = a->floatNumber(kAperture);
        if (options.specular.minApertureDeg > options.specular.maxApertureDeg)
            throw InputError(n->childWhere("min_aperture_deg"),
                             fmt::format("expected at most max_aperture_deg ({}), got {}",
                                         options.specular.maxApertureDeg, options.specular.minApertureDeg));
    }
    if (auto n = node.find("shadow")) {
        n->allowKeys({"method", "ray_samples", "area_ray_samples", "aperture_deg", "pixel_stride",
                      "relight_pixel_stride"});
        if (auto m = n->find("method")) options.shadow.method = readName(*m, kShadowMethodNames);
        if (auto r = n->find("ray_samples")) options.shadow.raySamples = r->integer(1, 256);
        if (auto r = n->find("area_ray_samples")) options.shadow.areaRaySamples = r->integer(1, 256);
        if (auto a = n->find("aperture_deg"))
            options.shadow.apertureDeg = a->floatNumber({0.0, 90.0, true, false});
        if (auto st = n->find("pixel_stride")) options.shadow.pixelStride = readPixelStride(*st);
        if (auto st = n->find("relight_pixel_stride"))
            options.shadow.relightPixelStride = readPixelStride(*st);
    }
    if (auto n = node.find("trace")) readTrace(*n, options.trace);
    if (auto n = node.find("render")) readRender(*n, options.render);
    if (auto n = node.find("environment")) readEnvironmentOptions(*n, options.environment);
    return options;
}

namespace {
json strideJson(int stride) {
    return stride == 0 ? json("auto") : json(stride);
}
}  // namespace

json optionsToJson(const Options& o) {
    json volume = {{"resolution", o.volume.resolution},
                   {"extent_scale", o.volume.extentScale},
                   {"reach_scale", o.volume.reachScale},
                   {"center", nullptr},
                   {"size", nullptr},
                   {"viewpoint", nullptr}};
    if (o.volume.center) volume["center"] = {o.volume.center->x, o.volume.center->y, o.volume.center->z};
    if (o.volume.size) volume["size"] = *o.volume.size;
    if (o.volume.viewpoint)
        volume["viewpoint"] = {o.volume.viewpoint->x, o.volume.viewpoint->y, o.volume.viewpoint->z};
    return {
        {"volume", volume},
        {"rsm", {{"resolution", o.rsm.resolution > 0 ? json(o.rsm.resolution) : json("auto")}}},
        {"diffuse",
         {{"count", o.diffuse.count},
          {"aperture_deg", o.diffuse.apertureDeg},
          {"object_aperture_deg", o.diffuse.objectApertureDeg},
          {"pixel_stride", strideJson(o.diffuse.pixelStride)},
          {"relight_pixel_stride", strideJson(o.diffuse.relightPixelStride)},
          {"object_rays", o.diffuse.objectRays}}},
        {"specular",
         {{"min_aperture_deg", o.specular.minApertureDeg},
          {"max_aperture_deg", o.specular.maxApertureDeg},
          {"relight_pixel_stride", strideJson(o.specular.relightPixelStride)}}},
        {"shadow",
         {{"method", nameOf(kShadowMethodNames, o.shadow.method)},
          {"ray_samples", o.shadow.raySamples},
          {"area_ray_samples", o.shadow.areaRaySamples},
          {"aperture_deg", o.shadow.apertureDeg},
          {"pixel_stride", strideJson(o.shadow.pixelStride)},
          {"relight_pixel_stride", strideJson(o.shadow.relightPixelStride)}}},
        {"trace",
         {{"step_scale", o.trace.stepScale},
          {"start_offset", o.trace.startOffset},
          {"max_occlusion", o.trace.maxOcclusion},
          {"normal_weight", o.trace.normalWeight},
          {"backface_weight", o.trace.backfaceWeight},
          {"jitter", o.trace.jitter},
          {"accumulation", nameOf(kConeAccumulationNames, o.trace.accumulation)}}},
        {"render",
         {{"samples_per_pixel", o.render.samplesPerPixel},
          {"indirect", o.render.indirect},
          {"double_shadow_fix", o.render.doubleShadowFix},
          {"relight_indirect", o.render.relightIndirect},
          {"relight_cones", nameOf(kRelightConesNames, o.render.relightCones)},
          {"relight_object_light", nameOf(kRelightObjectLightNames, o.render.relightObjectLight)},
          {"light_bounces", o.render.lightBounces},
          {"denoise_radius", o.render.denoiseRadius},
          {"temporal_frames", o.render.temporalFrames},
          {"layers", o.render.layers}}},
        {"environment",
         {{"light_count", o.environment.lightCount},
          {"extraction", nameOf(kExtractionMethodNames, o.environment.extraction)},
          {"sky", o.environment.sky},
          {"max_light_aperture_deg", o.environment.maxLightApertureDeg}}},
    };
}

// ---- memory estimate --------------------------------------------------------------------------------------

namespace {

constexpr int kVolumeCount = 4;                // two visibility and two light volumes
constexpr double kBytesPerVoxel = 16.0;        // 4 floats
constexpr double kMipChainFactor = 8.0 / 7.0;  // 1 + 1/8 + 1/64 + ...
constexpr double kRsmFaces = 6.0;              // a cube map per light (the worst case: point lights)
// Per light, the map of the scene alone and the update of its texels that meet the objects (in the worst
// case, all of them): about 155 MB per light at the default 512^2, as measured (issue 11).
constexpr double kRsmMapsPerLight = 2.0;
constexpr double kBytesPerRsmTexel = 48.0;       // position, normal, flux (3 floats each) and depth, padded
constexpr double kBytesPerGBufferSample = 64.0;  // position, normal, albedo, specular, roughness, ids
constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

struct MemoryParts {
    double volumes, rsms, gbuffer;
    double total() const { return volumes + rsms + gbuffer; }
};

MemoryParts memoryParts(const Options& options, const Camera& camera, size_t lightCount,
                        size_t directionalCount) {
    const double r = options.volume.resolution;
    // Each light's largest map: the importance of "auto" only makes some smaller.
    auto texels = [&](bool directional) {
        const double side =
            rsmResolutionCeiling(options.rsm.resolution, options.volume.resolution, directional);
        return side * side * kRsmFaces * kRsmMapsPerLight;
    };
    return {kVolumeCount * kBytesPerVoxel * r * r * r * kMipChainFactor,
            kBytesPerRsmTexel * (texels(false) * static_cast<double>(lightCount) +
                                 texels(true) * static_cast<double>(directionalCount)),
            static_cast<double>(camera.width) * camera.height * options.render.samplesPerPixel *
                kBytesPerGBufferSample};
}

}  // namespace

uint64_t estimateRenderMemory(const Options& options, const Camera& camera, size_t lightCount,
                              size_t directionalCount) {
    return static_cast<uint64_t>(memoryParts(options, camera, lightCount, directionalCount).total());
}

void checkRenderMemory(const Options& options, const Camera& camera, size_t lightCount,
                       uint64_t physicalMemoryBytes, const std::string& file, size_t directionalCount) {
    MemoryParts parts = memoryParts(options, camera, lightCount, directionalCount);
    if (parts.total() <= static_cast<double>(physicalMemoryBytes)) return;
    // Name what dominates: the G-buffer grows with the camera's resolution (and
    // options.render.samples_per_pixel).
    std::string key = parts.rsms > parts.volumes ? "options.rsm.resolution" : "options.volume.resolution";
    std::string what;
    if (parts.gbuffer > std::max(parts.rsms, parts.volumes)) {
        key = "camera";
        what = fmt::format("{}x{} pixels at {} samples per pixel: ", camera.width, camera.height,
                           options.render.samplesPerPixel);
    }
    throw InputError(
        file + ": " + key,
        what + fmt::format("the render needs about {:.1f} GiB (volumes {:.1f} GiB, reflective shadow maps "
                           "{:.1f} GiB, G-buffer {:.1f} GiB), more than the {:.1f} GiB of physical memory",
                           parts.total() / kGiB, parts.volumes / kGiB, parts.rsms / kGiB,
                           parts.gbuffer / kGiB, static_cast<double>(physicalMemoryBytes) / kGiB));
}

uint64_t physicalMemoryBytes() {
    long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || pageSize <= 0) return std::numeric_limits<uint64_t>::max();  // unknown: do not refuse
    return static_cast<uint64_t>(pages) * static_cast<uint64_t>(pageSize);
}

}  // namespace deltagi
