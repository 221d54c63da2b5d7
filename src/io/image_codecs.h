// Decoding and encoding image files: PNG (libpng), JPEG (TurboJPEG), OpenEXR (OpenEXR) and Radiance HDR
// (stb), for image_io.cpp, scene/texture.cpp and the live session. Only these four formats are read and
// written.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace deltagi {

enum class ImageFormat { Png, Jpeg, Exr, Hdr };

// The formats deltagi reads, in words, for messages.
inline constexpr const char* kReadableImageFormats = "PNG, JPEG, OpenEXR (.exr) and Radiance HDR (.hdr)";

// The format an extension (".png", any case) names; nothing for any other.
std::optional<ImageFormat> imageFormatOfExtension(std::string_view extension);
// "PNG", "JPEG", "OpenEXR", "Radiance HDR".
const char* imageFormatName(ImageFormat format);

// What a decoder could not do, in words (no file name: the caller's InputError adds it).
class ImageCodecError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// An image's header, read before any pixel is decoded.
struct ImageHeader {
    int width = 0, height = 0;  // the pixels stored (an EXR's data window)
    int channels = 0;           // interleaved per pixel, in `channelNames`' order
    // 8 or 16: integer samples, sRGB-encoded by convention (PNG, JPEG); 32: linear float (EXR, HDR).
    int bits = 8;
    bool isFloat() const { return bits == 32; }
    // The display window (the image), and where the stored pixels' top left lies in it: only an EXR's differ.
    int fullWidth = 0, fullHeight = 0;
    int dataX = 0, dataY = 0;
    // EXR: the channels' names, RGBA first within each layer ("R", "G", "B", "A", then the others by name);
    // other formats: empty.
    std::vector<std::string> channelNames;
};

// A file or bytes opened for decoding: its header at once, its pixels on request (once).
class ImageDecoder {
  public:
    virtual ~ImageDecoder() = default;
    const ImageHeader& header() const { return header_; }
    // All pixels, rows top to bottom, header().channels per pixel. 8-bit images only.
    virtual void readUInt8(std::span<uint8_t> pixels) = 0;
    // All pixels as floats: integer samples scaled to [0, 1], float samples as stored.
    virtual void readFloat(std::span<float> pixels) = 0;

  protected:
    ImageHeader header_;
};

// Opens `path` by its extension (.png, .jpg, .jpeg, .exr, .hdr; any other: ImageCodecError naming the formats
// read). Reads the header only; a PNG's chunks are first checked against the file's size (pngChunkError).
// Throws ImageCodecError.
std::unique_ptr<ImageDecoder> openImageFile(const std::string& path);
// Decodes from `bytes`, which must outlive the decoder. Throws ImageCodecError.
std::unique_ptr<ImageDecoder> openImageBytes(std::span<const std::byte> bytes, ImageFormat format);

// Whether a PNG's chunks fit in its bytes: each chunk's declared length against the bytes left after it.
// libpng allocates and clears what a text chunk declares before reading it: a 351-byte PNG whose chunk
// claimed 1.7 GB took 6 s of page faults per open. `bytes` are the whole file, or its first part with
// `fileSize` the whole's. The problem in words ("its 'tEXt' chunk claims ... bytes, but ... are left"), or
// nothing; not a PNG: nothing.
std::optional<std::string> pngChunkError(std::span<const std::byte> bytes, uint64_t fileSize);

// Encoders, to bytes in memory; ImageCodecError when one fails.
// An 8-bit PNG of `channels` (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA) interleaved samples.
std::string encodePng8(std::span<const uint8_t> pixels, int width, int height, int channels);
// A baseline JPEG of RGB samples, quality 1 to 100, chroma subsampled 2x2.
std::string encodeJpeg8(std::span<const uint8_t> rgb, int width, int height, int quality);
// A zip-compressed OpenEXR file of 32-bit float channels named `channelNames` (interleaved in that order),
// with no attribute that varies between writes: identical pixels give identical bytes.
std::string encodeExr(std::span<const float> pixels, int width, int height,
                      std::span<const std::string> channelNames);
// A Radiance HDR (RGBE, run-length encoded) file of RGB floats (negative values are written as 0).
std::string encodeHdr(std::span<const float> rgb, int width, int height);

}  // namespace deltagi
