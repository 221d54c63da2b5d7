// Textures of materials: validation, the mip chain, decoding files and embedded images (io/image_codecs.h),
// and the filtered lookup with glTF 2.0's sampler state (wrap modes, filters).
#include "deltagi/texture.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <new>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <fmt/format.h>

#include "deltagi/error.h"
#include "io/image_codecs.h"
#include "io/image_encode.h"

namespace deltagi {

namespace {

// The largest width or height accepted (from a file or the constructor): guards against absurd sizes in
// corrupt or hostile headers before anything is allocated. 16384 is the limit of most GPUs' 2D textures; a
// texture at the limit in both directions holds 2^28 texels, 4 GiB of linear RGBA floats (1 GiB as 8 bits).
constexpr int kMaxTextureSide = 16384;

std::string sizeProblem(int width, int height) {
    if (width <= 0 || height <= 0)
        return fmt::format("texture size {}x{}: width and height must be positive", width, height);
    if (width > kMaxTextureSide || height > kMaxTextureSide)
        return fmt::format("texture size {}x{}: more than {} texels per side", width, height,
                           kMaxTextureSide);
    return {};
}

// --- 8-bit texels ---------------------------------------------------------------------------------------

uint32_t packTexel(uint8_t r, uint8_t g, uint8_t b, uint8_t a) {
    return static_cast<uint32_t>(r) | static_cast<uint32_t>(g) << 8 | static_cast<uint32_t>(b) << 16 |
           static_cast<uint32_t>(a) << 24;
}

// i / 255 for every 8-bit value: the linear decoding (the same floats as a division).
const std::array<float, 256>& unorm8Values() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[i] = static_cast<float>(i) / 255.0f;
        return t;
    }();
    return table;
}

// An 8-bit texel's linear RGBA values: RGB through the encoding's table (sRGB or linear), alpha linear.
struct TexelDecoder {
    const float* rgb;
    const float* alpha;
    glm::vec4 operator()(uint32_t t) const {
        return {rgb[t & 0xffu], rgb[(t >> 8) & 0xffu], rgb[(t >> 16) & 0xffu], alpha[t >> 24]};
    }
};
// The two decoders, made once (not at every lookup).
const TexelDecoder& decoderFor(TextureEncoding encoding) {
    static const TexelDecoder srgb{srgb8ToLinearValues().data(), unorm8Values().data()};
    static const TexelDecoder linear{unorm8Values().data(), unorm8Values().data()};
    return encoding == TextureEncoding::Srgb ? srgb : linear;
}

// The nearest 8-bit code of a linear value in [0, 1] (clamped), sRGB-encoded for colour.
uint8_t encodeChannel(float linear, bool srgb) {
    const float clamped = std::clamp(linear, 0.0f, 1.0f);
    return static_cast<uint8_t>(std::lround((srgb ? linearToSrgbValue(clamped) : clamped) * 255.0f));
}

uint32_t encodeTexel(glm::vec4 linear, TextureEncoding encoding) {
    const bool srgb = encoding == TextureEncoding::Srgb;
    return packTexel(encodeChannel(linear.x, srgb), encodeChannel(linear.y, srgb),
                     encodeChannel(linear.z, srgb), encodeChannel(linear.w, false));
}

// --- The mip chain --------------------------------------------------------------------------------------

// One destination texel of a box filter from `srcSize` texels to `dstSize` (dstSize <= srcSize): the source
// texels it covers and their weights, which sum to 1.
struct BoxTaps {
    int first = 0;
    int count = 0;
    std::array<float, 4> weight{};
};

// Each destination texel i covers the source interval [i * r, (i + 1) * r), r = srcSize / dstSize, and
// weighs every source texel by the length of its overlap with that interval (divided by r). An even size
// halves to the familiar 2-texel average; an odd size 2n + 1 -> n spreads every texel over intervals of
// 2 + 1/n texels (3 for 3 -> 1, fractional at the ends otherwise). Every source texel's weights sum to
// dstSize / srcSize, so the mean of a level is exactly the mean of the one above (up to float rounding).
// r lies in [2, 3) apart from sizes 1 (r = 1) and 3 (r = 3), so an interval touches at most 4 texels.
std::vector<BoxTaps> boxTaps(int srcSize, int dstSize) {
    std::vector<BoxTaps> taps(dstSize);
    double ratio = static_cast<double>(srcSize) / dstSize;
    for (int i = 0; i < dstSize; ++i) {
        double begin = i * ratio, end = (i + 1) * ratio;
        int first = static_cast<int>(std::floor(begin));
        int last = std::min(srcSize, static_cast<int>(std::ceil(end))) - 1;
        BoxTaps& t = taps[i];
        t.first = first;
        for (int j = first; j <= last; ++j) {
            double overlap = std::min(end, j + 1.0) - std::max(begin, static_cast<double>(j));
            if (overlap <= 0.0) continue;  // an interval ending exactly on a texel edge
            assert(j - first < 4);
            t.weight[j - first] = static_cast<float>(overlap / ratio);
            t.count = j - first + 1;
        }
    }
    return taps;
}

// The next mip level: floor(size / 2) but at least 1 in each direction, box filtered (boxTaps), separably:
// rows first, then columns.
std::vector<glm::vec4> downsample(std::span<const glm::vec4> src, int width, int height, int dstWidth,
                                  int dstHeight) {
    std::vector<BoxTaps> tapsX = boxTaps(width, dstWidth), tapsY = boxTaps(height, dstHeight);
    std::vector<glm::vec4> rows(static_cast<size_t>(dstWidth) * height);
    for (int y = 0; y < height; ++y) {
        const glm::vec4* in = &src[static_cast<size_t>(y) * width];
        glm::vec4* out = &rows[static_cast<size_t>(y) * dstWidth];
        for (int x = 0; x < dstWidth; ++x) {
            const BoxTaps& t = tapsX[x];
            glm::vec4 sum(0.0f);
            for (int k = 0; k < t.count; ++k) sum += t.weight[k] * in[t.first + k];
            out[x] = sum;
        }
    }
    std::vector<glm::vec4> dst(static_cast<size_t>(dstWidth) * dstHeight);
    for (int y = 0; y < dstHeight; ++y) {
        const BoxTaps& t = tapsY[y];
        glm::vec4* out = &dst[static_cast<size_t>(y) * dstWidth];
        for (int x = 0; x < dstWidth; ++x) {
            glm::vec4 sum(0.0f);
            for (int k = 0; k < t.count; ++k)
                sum += t.weight[k] * rows[static_cast<size_t>(t.first + k) * dstWidth + x];
            out[x] = sum;
        }
    }
    return dst;
}

// --- Lookups --------------------------------------------------------------------------------------------

// floor(x) through a truncating conversion, exact for |x| < 2^31 (texel coordinates, levels of detail).
// Without SSE4.1's rounding instruction the build's std::floor adds a branch on |x| and keeps the sign of
// zero; a lookup takes up to seven: `BM_MaterialLookups/3` 12.2 -> 11.6 ms with this (the same texels).
inline float floorOf(float x) {
    const float t = static_cast<float>(static_cast<int>(x));
    return t > x ? t - 1.0f : t;
}
// floor(x) for any x: floorOf where it is exact.
inline float floorOfAny(float x) {
    return std::abs(x) < 2147483648.0f ? floorOf(x) : std::floor(x);
}

// Brings a coordinate (uv units) into one period of its wrap mode, so that texel indices computed from it
// fit an int whatever the uv (1e30 included); the indices are wrapped again (wrapIndex), which makes the
// reduction exact for Repeat and MirroredRepeat and harmless for ClampToEdge.
[[gnu::always_inline]] inline float reduceCoordinate(float u, TextureWrap wrap) {
    switch (wrap) {
        case TextureWrap::Repeat:
            return u - floorOfAny(u);
        case TextureWrap::MirroredRepeat:
            return u - 2.0f * floorOfAny(0.5f * u);
        case TextureWrap::ClampToEdge:
            break;
    }
    return std::clamp(u, -1.0f, 2.0f);
}

// glTF's wrap modes on a texel index (OpenGL 4.6, section 8.14.2): Repeat takes it modulo the size,
// MirroredRepeat reflects every other period (-1 -> 0, n -> n - 1), ClampToEdge clamps to the edge texels.
int wrapIndex(int i, int size, TextureWrap wrap) {
    if (i >= 0 && i < size) return i;  // nearly every lookup: no division
    switch (wrap) {
        case TextureWrap::Repeat:
            i %= size;
            return i < 0 ? i + size : i;
        case TextureWrap::MirroredRepeat: {
            int period = 2 * size;
            i %= period;
            if (i < 0) i += period;
            return i < size ? i : period - 1 - i;
        }
        case TextureWrap::ClampToEdge:
            break;
    }
    return std::clamp(i, 0, size - 1);
}

// --- Decoding -------------------------------------------------------------------------------------------

std::string lowercase(std::string_view s) {
    std::string out(s);
    std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
    return out;
}

bool startsWith(std::span<const std::byte> bytes, std::string_view magic, size_t offset = 0) {
    if (bytes.size() < offset + magic.size()) return false;
    for (size_t i = 0; i < magic.size(); ++i)
        if (bytes[offset + i] != static_cast<std::byte>(magic[i])) return false;
    return true;
}

// The format of an image in memory by its signature (magic bytes); nothing when unknown.
std::optional<ImageFormat> sniffFormat(std::span<const std::byte> bytes) {
    using namespace std::string_view_literals;
    if (startsWith(bytes, "\x89PNG\r\n\x1a\n"sv)) return ImageFormat::Png;
    if (startsWith(bytes, "\xff\xd8\xff"sv)) return ImageFormat::Jpeg;
    if (startsWith(bytes, "\x76\x2f\x31\x01"sv)) return ImageFormat::Exr;
    if (startsWith(bytes, "#?RADIANCE"sv) || startsWith(bytes, "#?RGBE"sv)) return ImageFormat::Hdr;
    return std::nullopt;
}

// The format a container's hint names: a file extension (with or without the dot) or a MIME type; nothing
// when it names no format read here.
std::optional<ImageFormat> formatFromHint(std::string_view hint) {
    std::string h = lowercase(hint);
    if (!h.empty() && h.front() == '.') h.erase(0, 1);
    static constexpr std::pair<std::string_view, ImageFormat> kMimeTypes[] = {
        {"image/png", ImageFormat::Png},          {"image/jpeg", ImageFormat::Jpeg},
        {"image/jpg", ImageFormat::Jpeg},         {"image/x-exr", ImageFormat::Exr},
        {"image/vnd.radiance", ImageFormat::Hdr},
    };
    for (auto [mime, format] : kMimeTypes)
        if (h == mime) return format;
    return imageFormatOfExtension("." + h);
}

// Reads the first image of an opened file as linear RGBA texels: 8/16-bit colour channels sRGB-decoded for
// TextureEncoding::Srgb, alpha always linear; float files as they are. Grey repeats to RGB (grey + alpha
// keeps its alpha), missing alpha is 1, channels past the fourth are ignored. Throws InputError(where, ...),
// the message starting with `what`.
std::shared_ptr<const Texture> readTexels(ImageDecoder& input, TextureEncoding encoding,
                                          const std::string& where, const std::string& what,
                                          const std::string& name) {
    const ImageHeader& spec = input.header();
    int width = spec.width, height = spec.height;
    if (std::string problem = sizeProblem(width, height); !problem.empty())
        throw InputError(where, what + problem);
    if (spec.channels <= 0) throw InputError(where, what + "the image has no channels");
    const int fileChannels = spec.channels;
    int channels = std::min(fileChannels, 4);
    int alpha = channels == 2 ? 1 : channels == 4 ? 3 : -1;
    bool floatFile = spec.isFloat();
    bool srgb = encoding == TextureEncoding::Srgb && !floatFile;
    size_t texelCount = static_cast<size_t>(width) * height;
    auto make = [&](auto&&... texels) {
        try {
            return std::make_shared<const Texture>(width, height, std::move(texels)..., name);
        } catch (const InputError& e) {
            throw InputError(where, what + e.message());
        }
    };
    try {
        if (spec.bits == 8) {  // kept as 8 bits (RGBA)
            std::vector<uint8_t> bytes(texelCount * fileChannels);
            input.readUInt8(bytes);
            std::vector<uint8_t> rgba(texelCount * 4);
            for (size_t p = 0; p < texelCount; ++p) {
                const uint8_t* v = &bytes[p * fileChannels];
                uint8_t* out = &rgba[p * 4];
                out[0] = v[0];
                out[1] = channels >= 3 ? v[1] : v[0];
                out[2] = channels >= 3 ? v[2] : v[0];
                out[3] = alpha >= 0 ? v[alpha] : 255;
            }
            bytes = {};
            return make(std::move(rgba), srgb ? TextureEncoding::Srgb : TextureEncoding::Linear);
        }
        std::vector<float> values(texelCount * fileChannels);
        input.readFloat(values);  // 16-bit samples scaled to [0, 1]
        if (srgb)
            for (size_t i = 0; i < values.size(); ++i)
                if (static_cast<int>(i % fileChannels) != alpha) values[i] = srgbToLinearValue(values[i]);
        std::vector<glm::vec4> texels(texelCount);
        for (size_t p = 0; p < texelCount; ++p) {
            const float* v = &values[p * fileChannels];
            glm::vec3 rgb = channels >= 3 ? glm::vec3(v[0], v[1], v[2]) : glm::vec3(v[0]);
            texels[p] = glm::vec4(rgb, alpha >= 0 ? v[alpha] : 1.0f);
        }
        values = {};
        return make(std::move(texels));
    } catch (const ImageCodecError& e) {
        throw InputError(where, what + "cannot read the pixels: " + e.what());
    } catch (const std::bad_alloc&) {
        throw InputError(
            where, what + fmt::format("a texture of {}x{} texels does not fit in memory", width, height));
    }
}

}  // namespace

// --- Texture --------------------------------------------------------------------------------------------

Texture::Texture(int width, int height, std::vector<glm::vec4> texels, std::string name)
    : width_(width), height_(height), name_(std::move(name)) {
    if (std::string problem = sizeProblem(width, height); !problem.empty()) throw InputError(name_, problem);
    size_t count = static_cast<size_t>(width) * height;
    if (texels.size() != count)
        throw InputError(name_, fmt::format("texture size {}x{} needs {} texels, got {}", width, height,
                                            count, texels.size()));
    for (size_t i = 0; i < count; ++i) {
        const glm::vec4& t = texels[i];
        if (!std::isfinite(t.x) || !std::isfinite(t.y) || !std::isfinite(t.z) || !std::isfinite(t.w))
            throw InputError(name_, fmt::format("texel ({}, {}) is not finite", i % width, i / width));
    }
    levels_.push_back({width, height, std::move(texels), {}});
    buildMipChain();
}

Texture::Texture(int width, int height, std::vector<uint8_t> rgba8, TextureEncoding encoding,
                 std::string name)
    : width_(width),
      height_(height),
      eightBit_(true),
      encoding_(encoding),
      rgbValues_(decoderFor(encoding).rgb),
      alphaValues_(decoderFor(encoding).alpha),
      name_(std::move(name)) {
    if (std::string problem = sizeProblem(width, height); !problem.empty()) throw InputError(name_, problem);
    size_t count = static_cast<size_t>(width) * height;
    if (rgba8.size() != count * 4)
        throw InputError(name_, fmt::format("texture size {}x{} needs {} bytes (RGBA), got {}", width, height,
                                            count * 4, rgba8.size()));
    try {
        std::vector<uint32_t> packed(count);
        for (size_t i = 0; i < count; ++i)
            packed[i] = packTexel(rgba8[4 * i], rgba8[4 * i + 1], rgba8[4 * i + 2], rgba8[4 * i + 3]);
        rgba8 = {};
        levels_.push_back({width, height, {}, std::move(packed)});
    } catch (const std::bad_alloc&) {
        throw InputError(name_,
                         fmt::format("a texture of {}x{} texels does not fit in memory", width, height));
    }
    buildMipChain();
}

void Texture::buildMipChain() {
    try {
        while (levels_.back().width > 1 || levels_.back().height > 1) {
            const Level& above = levels_.back();
            int w = std::max(1, above.width / 2), h = std::max(1, above.height / 2);
            if (!eightBit_) {
                std::vector<glm::vec4> next = downsample(above.texels, above.width, above.height, w, h);
                levels_.push_back({w, h, std::move(next), {}});
                continue;
            }
            // Filtered in linear values (as a float texture is), then stored as 8 bits again.
            const TexelDecoder& decoder = decoderFor(encoding_);
            std::vector<glm::vec4> linear(above.packed.size());
            for (size_t i = 0; i < linear.size(); ++i) linear[i] = decoder(above.packed[i]);
            const std::vector<glm::vec4> next = downsample(linear, above.width, above.height, w, h);
            std::vector<uint32_t> packed(next.size());
            for (size_t i = 0; i < next.size(); ++i) packed[i] = encodeTexel(next[i], encoding_);
            levels_.push_back({w, h, {}, std::move(packed)});
        }
    } catch (const std::bad_alloc&) {
        throw InputError(name_,
                         fmt::format("a texture of {}x{} texels does not fit in memory", width_, height_));
    }
}

std::shared_ptr<const Texture> Texture::load(const std::filesystem::path& file, TextureEncoding encoding,
                                             const std::string& where) {
    std::string path = file.string();
    std::string location = where.empty() ? path : where;
    // The file is named in the message unless it is already `where`.
    std::string what = where.empty() || where == path ? "" : "texture '" + path + "': ";
    std::error_code error;
    if (!std::filesystem::exists(file, error)) throw InputError(location, what + "no such file");
    if (!std::filesystem::is_regular_file(file, error))
        throw InputError(location, what + "not a regular file");
    if (std::filesystem::file_size(file, error) == 0 || error)
        throw InputError(location, what + "the file is empty");
    std::unique_ptr<ImageDecoder> input;
    try {
        input = openImageFile(path);
    } catch (const ImageCodecError& e) {
        throw InputError(location, what + "cannot read image: " + e.what());
    }
    return readTexels(*input, encoding, location, what, path);
}

std::shared_ptr<const Texture> Texture::decode(std::span<const std::byte> encoded,
                                               std::string_view formatHint, TextureEncoding encoding,
                                               const std::string& where) {
    std::string location = where.empty() ? "embedded texture" : where;
    std::string what = where.empty() ? "" : "embedded texture: ";
    if (encoded.empty()) throw InputError(location, what + "no image data (0 bytes)");
    // The bytes' signature wins over the hint: containers mislabel images (a JPEG declared image/png).
    std::optional<ImageFormat> format = sniffFormat(encoded);
    if (!format) format = formatFromHint(formatHint);
    if (!format)
        throw InputError(
            location,
            what + (formatHint.empty()
                        ? fmt::format("not an image format this program reads ({})", kReadableImageFormats)
                        : fmt::format("unsupported image format '{}'; deltagi reads {}", formatHint,
                                      kReadableImageFormats)));
    const std::string name = lowercase(imageFormatName(*format));
    std::unique_ptr<ImageDecoder> input;
    try {
        input = openImageBytes(encoded, *format);
    } catch (const ImageCodecError& e) {
        throw InputError(location, what + fmt::format("cannot decode the {} image: {}", name, e.what()));
    }
    return readTexels(*input, encoding, location, what, location);
}

glm::vec4 Texture::average() const {
    return texel(levels() - 1, 0, 0);
}

glm::vec4 Texture::texel(int level, int x, int y) const {
    assert(level >= 0 && level < levels());
    const Level& l = levels_[level];
    assert(x >= 0 && x < l.width && y >= 0 && y < l.height);
    const size_t i = static_cast<size_t>(y) * l.width + x;
    return eightBit_ ? decoderFor(encoding_)(l.packed[i]) : l.texels[i];
}

namespace {

// A texel's four channels in one SSE register where there is one, else a glm::vec4: a lookup blends up to
// eight texels, and the four channels of each go through the same operations. Both builds compute the same
// values in the same order (glm::mix's x (1 - a) + y a).
#if defined(__SSE2__)
struct Lanes {
    __m128 v;
    static Lanes of(const glm::vec4& t) { return {_mm_loadu_ps(&t.x)}; }
    static Lanes of(float r, float g, float b, float a) { return {_mm_setr_ps(r, g, b, a)}; }
    // An 8-bit texel's four codes as floats (0 to 255).
    static Lanes codes(uint32_t t) {
        const __m128i zero = _mm_setzero_si128();
        const __m128i bytes = _mm_cvtsi32_si128(static_cast<int>(t));
        return {_mm_cvtepi32_ps(_mm_unpacklo_epi16(_mm_unpacklo_epi8(bytes, zero), zero))};
    }
    Lanes dividedBy(float d) const { return {_mm_div_ps(v, _mm_set1_ps(d))}; }
    glm::vec4 value() const {
        glm::vec4 out;
        _mm_storeu_ps(&out.x, v);
        return out;
    }
    friend Lanes mix(Lanes x, Lanes y, float a) {
        return {_mm_add_ps(_mm_mul_ps(x.v, _mm_set1_ps(1.0f - a)), _mm_mul_ps(y.v, _mm_set1_ps(a)))};
    }
};
#else
struct Lanes {
    glm::vec4 v;
    static Lanes of(const glm::vec4& t) { return {t}; }
    static Lanes of(float r, float g, float b, float a) { return {glm::vec4(r, g, b, a)}; }
    static Lanes codes(uint32_t t) {
        return {glm::vec4(static_cast<float>(t & 0xffu), static_cast<float>((t >> 8) & 0xffu),
                          static_cast<float>((t >> 16) & 0xffu), static_cast<float>(t >> 24))};
    }
    Lanes dividedBy(float d) const { return {v / d}; }
    glm::vec4 value() const { return v; }
    friend Lanes mix(Lanes x, Lanes y, float a) { return {glm::mix(x.v, y.v, a)}; }
};
#endif

// The four texels around (u, v) (reduced, reduceCoordinate) of a level `width` x `height` and the bilinear
// weights along x and y. Texel centres lie at (i + 0.5) / size.
[[gnu::always_inline]] inline void locateBilinear(int width, int height, float u, float v,
                                                  const TextureSampler& sampler, std::array<size_t, 4>& index,
                                                  float& fx, float& fy) {
    const float s = u * width - 0.5f, t = v * height - 0.5f;
    const float x0 = floorOf(s), y0 = floorOf(t);
    fx = s - x0, fy = t - y0;
    const int x = static_cast<int>(x0), y = static_cast<int>(y0);
    // Inside the level (nearly every lookup) the neighbours are the next column and row; at its edges each of
    // the two columns and rows is wrapped once (not each of the four texels' indices).
    size_t left = static_cast<size_t>(x), right = left + 1;
    if (x < 0 || x + 1 >= width) {
        left = static_cast<size_t>(wrapIndex(x, width, sampler.wrapS));
        right = static_cast<size_t>(wrapIndex(x + 1, width, sampler.wrapS));
    }
    size_t top = static_cast<size_t>(y), bottom = top + 1;
    if (y < 0 || y + 1 >= height) {
        top = static_cast<size_t>(wrapIndex(y, height, sampler.wrapT));
        bottom = static_cast<size_t>(wrapIndex(y + 1, height, sampler.wrapT));
    }
    top *= static_cast<size_t>(width);
    bottom *= static_cast<size_t>(width);
    index = {top + left, top + right, bottom + left, bottom + right};
}

// The texel of a level `width` x `height` that (u, v) (reduced) lies in.
size_t locateNearest(int width, int height, float u, float v, const TextureSampler& sampler) {
    const int x = wrapIndex(static_cast<int>(floorOf(u * width)), width, sampler.wrapS);
    const int y = wrapIndex(static_cast<int>(floorOf(v * height)), height, sampler.wrapT);
    return static_cast<size_t>(y) * width + x;
}

// The texels of a lookup's (at most two) levels as Lanes, texel `i` of the level in `slot`: linear floats,
struct FloatTexels {
    std::array<const glm::vec4*, 2> level;
    [[gnu::always_inline]] Lanes operator()(int slot, size_t i) const { return Lanes::of(level[slot][i]); }
};
// 8-bit sRGB texels: decoded through the sRGB decoder's tables before they are blended (sRGB is not linear
// in its codes),
struct SrgbTexels {
    std::array<const uint32_t*, 2> level;
    const float* rgb;
    const float* alpha;
    [[gnu::always_inline]] Lanes operator()(int slot, size_t i) const {
        const uint32_t t = level[slot][i];
        return Lanes::of(rgb[t & 0xffu], rgb[(t >> 8) & 0xffu], rgb[(t >> 16) & 0xffu], alpha[t >> 24]);
    }
};
// or linear 8-bit texels: their codes (0 to 255), blended as they are and divided by 255 after the blend
// (for the same values to rounding, with neither a table nor a division per texel).
struct CodeTexels {
    std::array<const uint32_t*, 2> level;
    [[gnu::always_inline]] Lanes operator()(int slot, size_t i) const { return Lanes::codes(level[slot][i]); }
};

// The blend a Lookup describes of `texels`: bilinear within each level, then between the levels. Inlined
// with the texel reads (a call per texel cost the textured benchmark frame's lookups a tenth of their time).
template <typename Texels>
[[gnu::always_inline]] inline Lanes blendLevel(const Texture::Lookup& lookup, const Texels& texels,
                                               int slot) {
    const std::array<size_t, 4>& i = lookup.index[slot];
    if (!lookup.bilinear) return texels(slot, i[0]);
    const float fx = lookup.fx[slot], fy = lookup.fy[slot];
    return mix(mix(texels(slot, i[0]), texels(slot, i[1]), fx),
               mix(texels(slot, i[2]), texels(slot, i[3]), fx), fy);
}
template <typename Texels>
[[gnu::always_inline]] inline Lanes blendTexels(const Texture::Lookup& lookup, const Texels& texels) {
    const Lanes fine = blendLevel(lookup, texels, 0);
    return lookup.levels == 2 ? mix(fine, blendLevel(lookup, texels, 1), lookup.levelBlend) : fine;
}

// Fills slot `slot` of `lookup` (its filter decided) for a level `width` x `height`.
[[gnu::always_inline]] inline void locateInLevel(Texture::Lookup& lookup, int slot, int width, int height,
                                                 float u, float v, const TextureSampler& sampler) {
    if (lookup.bilinear)
        locateBilinear(width, height, u, v, sampler, lookup.index[slot], lookup.fx[slot], lookup.fy[slot]);
    else
        lookup.index[slot][0] = locateNearest(width, height, u, v, sampler);
}

}  // namespace

Texture::Lookup Texture::locate(glm::vec2 uv, float footprint, const TextureSampler& sampler) const {
    Lookup lookup;
    locate(uv, footprint, sampler, lookup);
    return lookup;
}

void Texture::locate(glm::vec2 uv, float footprint, const TextureSampler& sampler, Lookup& lookup) const {
    lookup.average = false;
    lookup.bilinear = true;
    lookup.levels = 1;
    lookup.levelBlend = 0.0f;
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
        lookup.average = true;
        return;
    }
    const float u = reduceCoordinate(uv.x, sampler.wrapS), v = reduceCoordinate(uv.y, sampler.wrapT);
    auto atLevel = [&](int slot, int level) __attribute__((always_inline)) {
        lookup.level[slot] = level;
        locateInLevel(lookup, slot, levels_[level].width, levels_[level].height, u, v, sampler);
    };
    // The level of detail: log2 of the footprint in texels of level 0 (OpenGL 4.6, section 8.14.1, with the
    // larger side's scale). Magnification at or below 0; a NaN footprint counts as 0.
    float lod =
        footprint > 0.0f ? std::log2(footprint * static_cast<float>(std::max(width_, height_))) : 0.0f;
    if (!(lod > 0.0f) || !sampler.mipmaps) {  // level 0
        lookup.bilinear = (lod > 0.0f ? sampler.minFilter : sampler.magFilter) == TextureFilter::Linear;
        atLevel(0, 0);
        return;
    }
    const int last = levels() - 1;
    lod = std::min(lod, static_cast<float>(last));
    if (sampler.minFilter == TextureFilter::Nearest) {
        // NEAREST_MIPMAP_NEAREST: the level nearest lod (OpenGL's ceil(lod + 0.5) - 1, 0.5 rounding down).
        lookup.bilinear = false;
        atLevel(0, std::clamp(static_cast<int>(std::ceil(lod + 0.5f)) - 1, 0, last));
        return;
    }
    // LINEAR_MIPMAP_LINEAR: bilinear lookups of the two levels around lod, blended (trilinear).
    const int level = static_cast<int>(floorOf(lod));
    const float blend = lod - static_cast<float>(level);
    atLevel(0, level);
    if (level < last && blend > 0.0f) {
        lookup.levels = 2;
        lookup.levelBlend = blend;
        atLevel(1, level + 1);
    }
}

glm::vec4 Texture::read(const Lookup& lookup) const {
    if (lookup.average) return average();
    const Level& first = levels_[lookup.level[0]];
    const Level* second = lookup.levels == 2 ? &levels_[lookup.level[1]] : nullptr;
    if (!eightBit_)
        return blendTexels(lookup,
                           FloatTexels{{first.texels.data(), second ? second->texels.data() : nullptr}})
            .value();
    const std::array<const uint32_t*, 2> packed = {first.packed.data(),
                                                   second ? second->packed.data() : nullptr};
    if (encoding_ == TextureEncoding::Linear)
        return blendTexels(lookup, CodeTexels{packed}).dividedBy(255.0f).value();
    return blendTexels(lookup, SrgbTexels{packed, rgbValues_, alphaValues_}).value();
}

glm::vec4 Texture::sample(glm::vec2 uv, float footprint, const TextureSampler& sampler) const {
    return read(locate(uv, footprint, sampler));
}

}  // namespace deltagi
