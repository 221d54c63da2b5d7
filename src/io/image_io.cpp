// Image pixels and image files (PNG, JPEG, OpenEXR, Radiance HDR: io/image_codecs.h). Files hold sRGB-encoded
// 8/16-bit or linear float pixels; in memory every image is linear float.
#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

#include <unistd.h>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "io/atomic_file.h"
#include "io/file_names.h"
#include "io/image_codecs.h"
#include "io/image_encode.h"
#include "io/image_output.h"

namespace deltagi {

glm::vec3 Image::rgb(int x, int y) const {
    if (channels_ < 3) return glm::vec3(at(x, y, 0));
    return {at(x, y, 0), at(x, y, 1), at(x, y, 2)};
}

// A 1-channel image stores the mean of the three (the inverse of rgb() for grey values).
void Image::setRgb(int x, int y, glm::vec3 v) {
    if (channels_ < 3) {
        at(x, y, 0) = (v.x + v.y + v.z) / 3.0f;
        return;
    }
    at(x, y, 0) = v.x;
    at(x, y, 1) = v.y;
    at(x, y, 2) = v.z;
}

namespace {

// The sRGB transfer functions (IEC 61966-2-1), exact piecewise forms.
float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
float linearToSrgb(float c) {
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

const std::array<float, 256>& srgb8ToLinearTable() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[i] = srgbToLinear(static_cast<float>(i) / 255.0f);
        return t;
    }();
    return table;
}

// Copies `channels` interleaved channels to 3, expanding grey (1 or 2 channels: grey + alpha) and dropping
// alpha and any further channels.
Image toRgb(std::span<const float> pixels, int width, int height, int channels) {
    Image image(width, height, 3);
    std::span<float> out = image.data();
    for (size_t p = 0; p < image.pixelCount(); ++p) {
        const float* in = &pixels[p * channels];
        for (int c = 0; c < 3; ++c) out[p * 3 + c] = channels >= 3 ? in[c] : in[0];
    }
    return image;
}

// The decoder of `path`, its header read; InputError naming the file when it cannot be opened.
std::unique_ptr<ImageDecoder> openImage(const std::filesystem::path& path) {
    try {
        return openImageFile(path.string());
    } catch (const ImageCodecError& e) {
        throw InputError(path.string(), std::string("cannot read image: ") + e.what());
    }
}

}  // namespace

std::optional<std::pair<int, int>> imageFileSize(const std::filesystem::path& path) {
    try {
        const ImageHeader header = openImageFile(path.string())->header();  // the display window, as read
        return std::pair{header.fullWidth, header.fullHeight};
    } catch (const ImageCodecError&) {
        return std::nullopt;
    }
}

ImageFile readImageFile(const std::filesystem::path& path) {
    std::unique_ptr<ImageDecoder> input = openImage(path);
    const ImageHeader spec = input->header();  // a copy: the decoder is closed before the window is read
    int width = spec.width, height = spec.height, channels = spec.channels;
    if (width <= 0 || height <= 0 || channels <= 0)
        throw InputError(path.string(), fmt::format("cannot read image: it is {}x{} with {} channels", width,
                                                    height, channels));
    // The header's size, checked before anything is allocated: a 138-byte PNG may declare 100,000 x 100,000.
    const double needed = static_cast<double>(width) * height * (channels * 5.0 + 12.0);
    const double memory =
        static_cast<double>(sysconf(_SC_PHYS_PAGES)) * static_cast<double>(sysconf(_SC_PAGESIZE));
    if (memory > 0.0 && needed > memory / 2.0)
        throw InputError(
            path.string(),
            fmt::format("cannot read image: it declares {}x{} pixels, which need about {:.1f} GiB, "
                        "more than half of the {:.1f} GiB of physical memory",
                        width, height, needed / (1 << 30), memory / (1 << 30)));
    size_t count = static_cast<size_t>(width) * height * channels;
    std::vector<float> pixels(count);
    // Integer pixels are sRGB-encoded (PNG, JPEG); float pixels are linear (EXR, HDR).
    try {
        if (spec.bits == 8) {
            std::vector<uint8_t> bytes(count);
            input->readUInt8(bytes);
            const auto& table = srgb8ToLinearTable();
            for (size_t i = 0; i < count; ++i) pixels[i] = table[bytes[i]];
        } else {
            input->readFloat(pixels);
            if (!spec.isFloat())
                for (float& v : pixels) v = srgbToLinear(v);
        }
    } catch (const ImageCodecError& e) {
        throw InputError(path.string(), std::string("cannot read image: ") + e.what());
    }
    input.reset();
    Image rgb = toRgb(pixels, width, height, channels);
    // The display window is the image (an EXR's data window may be offset within it, or smaller: pixels
    // outside it are 0); the common case, both the same, is returned as read.
    const int fullWidth = spec.fullWidth, fullHeight = spec.fullHeight;
    const int dx = spec.dataX, dy = spec.dataY;
    const bool isFloat = spec.isFloat();
    if (dx == 0 && dy == 0 && fullWidth == width && fullHeight == height) return {std::move(rgb), isFloat};
    const double fullBytes = static_cast<double>(fullWidth) * fullHeight * 12.0;
    if (fullWidth <= 0 || fullHeight <= 0 || (memory > 0.0 && fullBytes > memory / 2.0))
        throw InputError(path.string(), fmt::format("cannot read image: its display window is {}x{}",
                                                    fullWidth, fullHeight));
    Image full(fullWidth, fullHeight, 3, 0.0f);
    for (int y = std::max(0, -dy); y < height && y + dy < fullHeight; ++y)
        for (int x = std::max(0, -dx); x < width && x + dx < fullWidth; ++x)
            for (int c = 0; c < 3; ++c) full.at(x + dx, y + dy, c) = rgb.at(x, y, c);
    return {std::move(full), isFloat};
}

Image readImage(const std::filesystem::path& path) {
    Image image = readImageFile(path).image;
    size_t bad = 0;
    for (size_t p = 0; p < image.pixelCount(); ++p) {
        const float* v = &image.data()[p * 3];
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) ++bad;
    }
    if (bad > 0)
        throw InputError(path.string(),
                         fmt::format("{} of {} pixels are NaN or infinite", bad, image.pixelCount()));
    return image;
}

namespace {

float finiteOrZero(float v) {
    return std::isfinite(v) ? v : 0.0f;
}

// OpenEXR's names for an image's channels: Y (grey), or R, G, B, A, then "channel4" on.
std::vector<std::string> exrChannelNames(int channels) {
    if (channels == 1) return {"Y"};
    static const char* const kNames[] = {"R", "G", "B", "A"};
    std::vector<std::string> names;
    for (int c = 0; c < channels; ++c) names.emplace_back(c < 4 ? kNames[c] : fmt::format("channel{}", c));
    return names;
}

}  // namespace

std::vector<uint8_t> encodeSrgb8(const Image& image) {
    std::vector<uint8_t> bytes(image.data().size());
    for (size_t i = 0; i < bytes.size(); ++i) {
        const float value = image.data()[i];
        const bool isAlpha = image.channels() == 4 && i % 4 == 3;  // alpha is stored linear
        bytes[i] =
            isAlpha ? static_cast<uint8_t>(std::lround(std::clamp(finiteOrZero(value), 0.0f, 1.0f) * 255.0f))
                    : linearToSrgb8(value);
    }
    return bytes;
}

namespace {

// The 8-bit code of a linear value as the exact encoding rounds it.
uint8_t exactSrgb8(float linear) {
    return static_cast<uint8_t>(std::lround(linearToSrgb(linear) * 255.0f));
}

// Where each 8-bit code begins: the smallest float in [0, 1] that exactSrgb8 rounds to it or above (the
// encoding is non-decreasing, so a bisection over the floats' bit patterns, which are ordered like the
// floats, finds it; checked over every float in [0, 1]); and the code at the start of each of kBins equal
// bins of [0, 1].
struct Srgb8Table {
    static constexpr int kBins = 4096;
    std::array<float, 257> codeStart{};  // codeStart[256] = infinity, a guard
    std::array<uint8_t, kBins + 1> binCode{};
    Srgb8Table() {
        const uint32_t one = std::bit_cast<uint32_t>(1.0f);
        codeStart[0] = 0.0f;
        for (int k = 1; k < 256; ++k) {
            uint32_t lo = 0, hi = one;  // exactSrgb8(lo) < k <= exactSrgb8(hi)
            while (hi - lo > 1) {
                const uint32_t mid = lo + (hi - lo) / 2;
                (exactSrgb8(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
            }
            codeStart[k] = std::bit_cast<float>(hi);
        }
        codeStart[256] = std::numeric_limits<float>::infinity();
        for (int b = 0; b <= kBins; ++b) binCode[b] = exactSrgb8(static_cast<float>(b) / kBins);
    }
};

}  // namespace

uint8_t linearToSrgb8(float linear) {
    static const Srgb8Table table;
    const float v = std::clamp(finiteOrZero(linear), 0.0f, 1.0f);
    // The bin's first code, then on past the codes that begin at or before v (one or two steps at most).
    int k = table.binCode[static_cast<int>(v * static_cast<float>(Srgb8Table::kBins))];
    while (v >= table.codeStart[k + 1]) ++k;
    return static_cast<uint8_t>(k);
}

float linearToSrgbValue(float linear) {
    return linearToSrgb(linear);
}

float srgbToLinearValue(float encoded) {
    return srgbToLinear(encoded);
}

const std::array<float, 256>& srgb8ToLinearValues() {
    return srgb8ToLinearTable();
}

namespace {

void checkImagePath(const Image& image, const std::filesystem::path& path) {
    std::string ext = lowerExtension(path);
    if (ext != ".png" && ext != ".exr" && ext != ".hdr")
        throw InputError(
            path.string(),
            fmt::format("cannot write image: unsupported extension '{}'; use .png, .exr or .hdr", ext));
    if (image.empty()) throw InputError(path.string(), "cannot write image: the image is empty");
}

// The folder of an output named by its path must exist: its temporary is made there (AtomicFile).
void checkOutputFolder(const std::filesystem::path& path) {
    std::filesystem::path folder = path.parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder))
        throw InputError(path.string(),
                         fmt::format("cannot write image: folder '{}' does not exist", folder.string()));
}

}  // namespace

std::string encodePngBytes(const Image& image, const std::string& where) {
    try {
        return encodePng8(encodeSrgb8(image), image.width(), image.height(), image.channels());
    } catch (const ImageCodecError& e) {
        throw InputError(where, std::string("cannot write image: ") + e.what());
    }
}

void writeImage(const Image& image, const std::filesystem::path& path) {
    checkImagePath(image, path);
    checkOutputFolder(path);
    AtomicFile file(path);
    writeImage(image, file);
    file.commit();
}

void writeImage(const Image& image, AtomicFile& file) {
    const std::filesystem::path& path = file.destination();
    checkImagePath(image, path);
    const std::string ext = lowerExtension(path);

    // Radiance HDR holds RGB only: grey is expanded and alpha dropped.
    Image rgbForHdr;
    const Image* source = &image;
    if (ext == ".hdr" && image.channels() != 3) {
        rgbForHdr = toRgb(image.data(), image.width(), image.height(), image.channels());
        source = &rgbForHdr;
    }
    // Encoded in memory and written by AtomicFile, which checks every write (a full disk is an error, not
    // an empty file).
    if (ext == ".png") {
        file.write(encodePngBytes(*source, path.string()));
        file.close();
        return;
    }
    std::vector<float> pixels(source->data().begin(), source->data().end());
    for (float& v : pixels) v = finiteOrZero(v);
    try {
        file.write(ext == ".hdr" ? encodeHdr(pixels, source->width(), source->height())
                                 : encodeExr(pixels, source->width(), source->height(),
                                             exrChannelNames(source->channels())));
    } catch (const ImageCodecError& e) {
        throw InputError(path.string(), std::string("cannot write image: ") + e.what());
    }
    file.close();
}

void writeLayers(std::span<const ImageLayer> layers, const std::filesystem::path& path) {
    checkOutputFolder(path);
    AtomicFile file(path);
    writeLayers(layers, file);
    file.commit();
}

void writeLayers(std::span<const ImageLayer> layers, AtomicFile& file) {
    const std::filesystem::path& path = file.destination();
    if (lowerExtension(path) != ".exr")
        throw InputError(path.string(), "cannot write layers: they are written to OpenEXR files (.exr) only");
    if (layers.empty() || !layers[0].image || layers[0].image->empty())
        throw InputError(path.string(), "cannot write layers: there are none");
    const int width = layers[0].image->width(), height = layers[0].image->height();
    std::vector<std::string> names;
    for (const ImageLayer& layer : layers) {
        if (!layer.image || layer.image->width() != width || layer.image->height() != height ||
            static_cast<int>(layer.channels.size()) != layer.image->channels())
            throw InputError(path.string(), fmt::format("cannot write layers: layer '{}' is {}x{} with {} "
                                                        "channels, not {}x{} with {}",
                                                        layer.name, layer.image ? layer.image->width() : 0,
                                                        layer.image ? layer.image->height() : 0,
                                                        layer.image ? layer.image->channels() : 0, width,
                                                        height, layer.channels.size()));
        for (const std::string& channel : layer.channels) names.push_back(layer.name + "." + channel);
    }
    const int channels = static_cast<int>(names.size());
    // Interleaved, layer after layer within each pixel.
    std::vector<float> pixels(static_cast<size_t>(width) * height * channels);
    for (size_t p = 0, c0 = 0; p < static_cast<size_t>(width) * height; ++p) {
        c0 = p * channels;
        for (const ImageLayer& layer : layers) {
            const int n = layer.image->channels();
            for (int k = 0; k < n; ++k) {
                const float v = layer.image->data()[p * n + k];
                pixels[c0++] = std::isnan(v) ? 0.0f : v;
            }
        }
    }
    try {
        file.write(encodeExr(pixels, width, height, names));
    } catch (const ImageCodecError& e) {
        throw InputError(path.string(), std::string("cannot write layers: ") + e.what());
    }
    file.close();
}

std::vector<NamedImage> readLayers(const std::filesystem::path& path) {
    std::unique_ptr<ImageDecoder> input = openImage(path);
    const ImageHeader spec = input->header();
    const int width = spec.width, height = spec.height, channels = spec.channels;
    if (width <= 0 || height <= 0 || channels <= 0)
        throw InputError(path.string(), "cannot read image: it has no pixels");
    std::vector<float> pixels(static_cast<size_t>(width) * height * channels);
    try {
        input->readFloat(pixels);
    } catch (const ImageCodecError& e) {
        throw InputError(path.string(), std::string("cannot read image: ") + e.what());
    }
    input.reset();
    // Channel c's layer and name.
    std::vector<NamedImage> layers;
    std::vector<std::pair<size_t, int>> where(channels);  // (layer, channel within it)
    for (int c = 0; c < channels; ++c) {
        const std::string full =
            c < static_cast<int>(spec.channelNames.size()) ? spec.channelNames[c] : fmt::format("{}", c);
        const size_t dot = full.rfind('.');
        const std::string layer = dot == std::string::npos ? full : full.substr(0, dot);
        const std::string channel = dot == std::string::npos ? full : full.substr(dot + 1);
        auto it =
            std::find_if(layers.begin(), layers.end(), [&](const NamedImage& l) { return l.name == layer; });
        if (it == layers.end()) it = layers.insert(layers.end(), NamedImage{layer, Image(), {}});
        where[c] = {static_cast<size_t>(it - layers.begin()), static_cast<int>(it->channels.size())};
        it->channels.push_back(channel);
    }
    for (NamedImage& layer : layers)
        layer.image = Image(width, height, static_cast<int>(layer.channels.size()));
    for (size_t p = 0; p < static_cast<size_t>(width) * height; ++p)
        for (int c = 0; c < channels; ++c) {
            NamedImage& layer = layers[where[c].first];
            layer.image.data()[p * layer.channels.size() + where[c].second] = pixels[p * channels + c];
        }
    return layers;
}

}  // namespace deltagi
