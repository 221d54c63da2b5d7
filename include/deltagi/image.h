// Images: linear float pixels, row-major, top row first, channels interleaved.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "deltagi/export.h"

DELTAGI_API_BEGIN
namespace deltagi {

class Image {
  public:
    Image() = default;
    Image(int width, int height, int channels, float fill = 0.0f)
        : width_(width),
          height_(height),
          channels_(channels),
          pixels_(static_cast<size_t>(width) * height * channels, fill) {}
    Image(const Image&) = default;  // images are values; copies are explicit at call sites that need them
    Image(Image&&) noexcept = default;
    Image& operator=(const Image&) = default;
    Image& operator=(Image&&) noexcept = default;

    int width() const { return width_; }
    int height() const { return height_; }
    int channels() const { return channels_; }
    bool empty() const { return pixels_.empty(); }
    size_t pixelCount() const { return static_cast<size_t>(width_) * height_; }

    float& at(int x, int y, int c) { return pixels_[(static_cast<size_t>(y) * width_ + x) * channels_ + c]; }
    float at(int x, int y, int c) const {
        return pixels_[(static_cast<size_t>(y) * width_ + x) * channels_ + c];
    }
    // RGB of a pixel (a 1-channel image repeats its value).
    glm::vec3 rgb(int x, int y) const;
    void setRgb(int x, int y, glm::vec3 v);

    std::span<float> data() { return pixels_; }
    std::span<const float> data() const { return pixels_; }

  private:
    int width_ = 0, height_ = 0, channels_ = 0;
    std::vector<float> pixels_;
};

// Reads PNG/JPEG (decoded from sRGB to linear), EXR and HDR (linear), as 3 linear channels (grey images are
// expanded, alpha is dropped). Throws InputError naming the file when it is missing or unreadable, and when a
// pixel is NaN or infinite.
Image readImage(const std::filesystem::path& path);

// The width and height an image file's header gives, without reading its pixels; nothing when it cannot be
// read (readImage() then says why).
std::optional<std::pair<int, int>> imageFileSize(const std::filesystem::path& path);

// readImage() without the check for NaN and infinite pixels, which it leaves as they are (for callers that
// repair them), and whether the file held float (linear) pixels rather than sRGB-encoded integers.
struct ImageFile {
    Image image;
    bool floatPixels = false;
};
ImageFile readImageFile(const std::filesystem::path& path);

// Writes by extension: .png (8-bit sRGB, clamped to [0,1]), .exr (32-bit float, linear), .hdr (linear).
// NaN/Inf pixels are written as 0. The file is replaced atomically (src/io/atomic_file.h): a reader, a kill
// or a failure never sees it half written. Throws InputError when the file cannot be written (its folder
// must exist).
void writeImage(const Image& image, const std::filesystem::path& path);

// The 8-bit sRGB bytes a PNG of `image` holds: each channel clamped to [0, 1] (NaN and infinities as 0),
// encoded with the sRGB transfer function (a 4th channel, alpha, stays linear), rounded.
std::vector<uint8_t> encodeSrgb8(const Image& image);

// One layer of a multi-layer OpenEXR file: its channels are named `name`.`channel` ("object.A",
// "depth.Z"), as compositors (Nuke, Blender, Natron) read them; `channels` names the image's channels in
// order.
struct ImageLayer {
    std::string name;
    const Image* image = nullptr;
    std::vector<std::string> channels;
};
// Writes the layers, all of one size, into one 32-bit float EXR (zip compressed), replaced atomically as by
// writeImage. NaN pixels are written as 0; infinities are kept (a depth with no surface). Throws InputError
// when the file is not .exr, the layers differ in size or the write fails.
void writeLayers(std::span<const ImageLayer> layers, const std::filesystem::path& path);
// Every layer of an EXR file, in file order: the channels named `layer`.`channel` grouped by `layer` (a
// channel without a dot makes a layer of its own name), with their channel names. Throws InputError.
struct NamedImage {
    std::string name;
    Image image;
    std::vector<std::string> channels;
};
std::vector<NamedImage> readLayers(const std::filesystem::path& path);

}  // namespace deltagi
DELTAGI_API_END
