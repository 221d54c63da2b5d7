// PNG (libpng), JPEG (TurboJPEG) and Radiance HDR (stb_image, stb_image_write) decoders and encoders, and
// the choice of decoder by extension; OpenEXR's are in exr_codec.cpp. The libraries' errors become
// ImageCodecError: nothing is printed.
#include "io/image_codecs.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <new>

#include <sys/stat.h>

#include <fmt/format.h>
#include <png.h>
#include <turbojpeg.h>

// Debian's libstb-dev headers, compiled here with only the Radiance HDR reader, their functions private to
// this file.
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_HDR
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include "io/exr_codec.h"
#include "io/file_names.h"

namespace deltagi {

std::optional<ImageFormat> imageFormatOfExtension(std::string_view extension) {
    std::string ext(extension);
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".png") return ImageFormat::Png;
    if (ext == ".jpg" || ext == ".jpeg") return ImageFormat::Jpeg;
    if (ext == ".exr") return ImageFormat::Exr;
    if (ext == ".hdr") return ImageFormat::Hdr;
    return std::nullopt;
}

const char* imageFormatName(ImageFormat format) {
    switch (format) {
        case ImageFormat::Png:
            return "PNG";
        case ImageFormat::Jpeg:
            return "JPEG";
        case ImageFormat::Exr:
            return "OpenEXR";
        case ImageFormat::Hdr:
            return "Radiance HDR";
    }
    return "?";
}

// --- PNG chunks -----------------------------------------------------------------------------------------

namespace {

constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

uint32_t bigEndian32(const std::byte* p) {
    return (static_cast<uint32_t>(p[0]) << 24) | (static_cast<uint32_t>(p[1]) << 16) |
           (static_cast<uint32_t>(p[2]) << 8) | static_cast<uint32_t>(p[3]);
}

// Walks a PNG's chunk headers (the signature checked by the caller), `size` the file's bytes: each chunk's
// length and type from readHeader(at, header) (false: no more to read), its data and CRC skipped.
template <typename ReadHeader>
std::optional<std::string> walkPngChunks(uint64_t size, ReadHeader readHeader) {
    uint64_t at = 8;
    std::byte chunk[8];
    while (at + 8 <= size && readHeader(at, chunk)) {
        const uint64_t length = bigEndian32(chunk);
        const std::string type(reinterpret_cast<const char*>(chunk + 4), 4);
        const uint64_t left = size - at - 8;
        if (length + 4 > left)
            return fmt::format(
                "it is truncated or corrupt: its '{}' chunk claims {} bytes, but {} are left in the "
                "file",
                type, length, left >= 4 ? left - 4 : 0);
        if (type == "IEND") break;
        at += 8 + length + 4;
    }
    return std::nullopt;
}

std::optional<std::string> pngFileChunkError(std::FILE* file) {
    if (std::fseek(file, 0, SEEK_END) != 0) return std::nullopt;
    const long end = std::ftell(file);
    std::rewind(file);
    if (end < 0) return std::nullopt;
    unsigned char signature[8];
    if (std::fread(signature, 1, 8, file) != 8 || std::memcmp(signature, kPngSignature, 8) != 0)
        return std::nullopt;  // libpng says why
    auto error = walkPngChunks(static_cast<uint64_t>(end), [&](uint64_t at, std::byte* header) {
        return std::fseek(file, static_cast<long>(at), SEEK_SET) == 0 && std::fread(header, 1, 8, file) == 8;
    });
    std::rewind(file);
    return error;
}

}  // namespace

std::optional<std::string> pngChunkError(std::span<const std::byte> bytes, uint64_t fileSize) {
    if (bytes.size() < 8 || std::memcmp(bytes.data(), kPngSignature, 8) != 0) return std::nullopt;
    return walkPngChunks(fileSize, [&](uint64_t at, std::byte* header) {
        if (at + 8 > bytes.size()) return false;
        std::memcpy(header, bytes.data() + at, 8);
        return true;
    });
}

namespace {

struct FileCloser {
    void operator()(std::FILE* file) const { std::fclose(file); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

FilePtr openForReading(const std::string& path) {
    FilePtr file(std::fopen(path.c_str(), "rb"));
    if (!file) throw ImageCodecError(fmt::format("cannot open the file: {}", std::strerror(errno)));
    struct stat status {};
    if (fstat(fileno(file.get()), &status) == 0 && S_ISDIR(status.st_mode))
        throw ImageCodecError("it is a folder, not a file");
    return file;
}

// --- PNG (libpng 1.6) -----------------------------------------------------------------------------------

// libpng reports an error by calling its error function, which must not return: as its manual says, it
// longjmp()s back to the setjmp() of the call into libpng (readInfo, readRows, encodePng8's writeRows).
// Those functions hold no object with a destructor.
struct PngErrors {
    std::jmp_buf jump;
    char message[256] = {};
};

void pngError(png_structp png, png_const_charp message) {
    auto* errors = static_cast<PngErrors*>(png_get_error_ptr(png));
    std::snprintf(errors->message, sizeof errors->message, "%s", message);
    std::longjmp(errors->jump, 1);
}

void pngWarning(png_structp, png_const_charp) {}  // libpng's default prints them

class PngDecoder : public ImageDecoder {
  public:
    // From `file` (owned) or, without one, from `bytes`.
    PngDecoder(FilePtr file, std::span<const std::byte> bytes)
        : file_(std::move(file)),
          bytes_(bytes),
          structs_(&errors_),
          png_(structs_.png),
          info_(structs_.info) {
        png_set_read_fn(png_, this, readData);
        if (!readInfo()) fail();
        header_.width = static_cast<int>(png_get_image_width(png_, info_));
        header_.height = static_cast<int>(png_get_image_height(png_, info_));
        header_.channels = png_get_channels(png_, info_);
        header_.bits = png_get_bit_depth(png_, info_);
        header_.fullWidth = header_.width;
        header_.fullHeight = header_.height;
    }

    void readUInt8(std::span<uint8_t> pixels) override {
        if (header_.bits != 8) throw ImageCodecError("not an 8-bit PNG");
        readInto(pixels.data(), pixels.size());
    }

    void readFloat(std::span<float> pixels) override {
        const size_t count = static_cast<size_t>(header_.width) * header_.height * header_.channels;
        if (pixels.size() != count) throw ImageCodecError("the pixels' buffer is not the image's size");
        if (header_.bits == 8) {
            std::vector<uint8_t> bytes(count);
            readInto(bytes.data(), count);
            for (size_t i = 0; i < count; ++i) pixels[i] = static_cast<float>(bytes[i]) / 255.0f;
            return;
        }
        std::vector<uint16_t> samples(count);
        readInto(reinterpret_cast<uint8_t*>(samples.data()), count * 2);
        for (size_t i = 0; i < count; ++i) pixels[i] = static_cast<float>(samples[i]) / 65535.0f;
    }

  private:
    // The header, and the transforms that give 8 or 16-bit grey, grey + alpha, RGB or RGBA samples (16 bits
    // in the machine's byte order).
    bool readInfo() {
        if (setjmp(errors_.jump)) return false;
        png_set_user_limits(png_, 0x7fffffff, 0x7fffffff);  // the callers check the size, with a message
        png_read_info(png_, info_);
        png_set_expand(png_);  // palette to RGB, grey of 1, 2 or 4 bits to 8, tRNS to alpha
        if (png_get_bit_depth(png_, info_) == 16) png_set_swap(png_);
        png_set_interlace_handling(png_);
        png_read_update_info(png_, info_);
        return true;
    }

    bool readRows(png_bytepp rows) {
        if (setjmp(errors_.jump)) return false;
        png_read_image(png_, rows);
        return true;
    }

    void readInto(uint8_t* pixels, size_t size) {
        const size_t rowBytes = png_get_rowbytes(png_, info_);
        if (read_ || size != rowBytes * header_.height)
            throw ImageCodecError("the pixels' buffer is not the image's size");
        read_ = true;
        std::vector<png_bytep> rows(header_.height);
        for (int y = 0; y < header_.height; ++y) rows[y] = pixels + rowBytes * y;
        if (!readRows(rows.data())) fail();
    }

    [[noreturn]] void fail() const {
        throw ImageCodecError(fmt::format("invalid PNG file: {}", errors_.message));
    }

    static void readData(png_structp png, png_bytep data, size_t length) {
        auto* self = static_cast<PngDecoder*>(png_get_io_ptr(png));
        if (self->file_) {
            if (std::fread(data, 1, length, self->file_.get()) != length)
                png_error(png, "the file ends before the image does");
            return;
        }
        if (length > self->bytes_.size() - self->at_) png_error(png, "the data end before the image does");
        std::memcpy(data, self->bytes_.data() + self->at_, length);
        self->at_ += length;
    }

    // libpng's read and info structures, freed also when the constructor throws.
    struct Structs {
        png_structp png = nullptr;
        png_infop info = nullptr;
        explicit Structs(PngErrors* errors) {
            png = png_create_read_struct(PNG_LIBPNG_VER_STRING, errors, pngError, pngWarning);
            if (png != nullptr) info = png_create_info_struct(png);
            if (png == nullptr || info == nullptr) {
                png_destroy_read_struct(&png, &info, nullptr);
                throw std::bad_alloc();
            }
        }
        ~Structs() { png_destroy_read_struct(&png, &info, nullptr); }
        Structs(const Structs&) = delete;
        Structs& operator=(const Structs&) = delete;
    };

    FilePtr file_;
    std::span<const std::byte> bytes_;
    size_t at_ = 0;
    PngErrors errors_;
    Structs structs_;
    png_structp png_;
    png_infop info_;
    bool read_ = false;
};

// --- JPEG (TurboJPEG) -----------------------------------------------------------------------------------

struct TjHandle {
    tjhandle handle;
    explicit TjHandle(tjhandle h) : handle(h) {
        if (handle == nullptr) throw ImageCodecError(fmt::format("TurboJPEG: {}", tjGetErrorStr2(nullptr)));
    }
    ~TjHandle() { tjDestroy(handle); }
    TjHandle(const TjHandle&) = delete;
    TjHandle& operator=(const TjHandle&) = delete;
};

// The first line of TurboJPEG's message.
std::string tjMessage(tjhandle handle) {
    std::string text = tjGetErrorStr2(handle);
    text = text.substr(0, text.find('\n'));
    while (!text.empty() && (text.back() == '\r' || text.back() == ' ')) text.pop_back();
    return text;
}

class JpegDecoder : public ImageDecoder {
  public:
    // The JPEG in `owned`, or without it in `bytes`.
    JpegDecoder(std::vector<std::byte> owned, std::span<const std::byte> bytes)
        : owned_(std::move(owned)), bytes_(owned_.empty() ? bytes : owned_), tj_(tjInitDecompress()) {
        int width = 0, height = 0, subsampling = 0, colorspace = 0;
        if (tjDecompressHeader3(tj_.handle, data(), static_cast<unsigned long>(bytes_.size()), &width,
                                &height, &subsampling, &colorspace) != 0)
            throw ImageCodecError(fmt::format("invalid JPEG file: {}", tjMessage(tj_.handle)));
        if (width <= 0 || height <= 0)  // tables only: the data end before the frame's header
            throw ImageCodecError("invalid JPEG file: it holds no image (is it truncated?)");
        header_.width = header_.fullWidth = width;
        header_.height = header_.fullHeight = height;
        header_.channels = colorspace == TJCS_GRAY ? 1 : 3;
        header_.bits = 8;
    }

    void readUInt8(std::span<uint8_t> pixels) override {
        if (pixels.size() != static_cast<size_t>(header_.width) * header_.height * header_.channels)
            throw ImageCodecError("the pixels' buffer is not the image's size");
        // A warning (data that end early, a corrupt marker) leaves the image decoded as far as it goes, as
        // libjpeg's own programs do; an error leaves none.
        if (tjDecompress2(tj_.handle, data(), static_cast<unsigned long>(bytes_.size()), pixels.data(),
                          header_.width, 0, header_.height, header_.channels == 1 ? TJPF_GRAY : TJPF_RGB,
                          0) != 0 &&
            tjGetErrorCode(tj_.handle) != TJERR_WARNING)
            throw ImageCodecError(fmt::format("invalid JPEG file: {}", tjMessage(tj_.handle)));
    }

    void readFloat(std::span<float> pixels) override {
        std::vector<uint8_t> bytes(pixels.size());
        readUInt8(bytes);
        for (size_t i = 0; i < bytes.size(); ++i) pixels[i] = static_cast<float>(bytes[i]) / 255.0f;
    }

  private:
    const unsigned char* data() const { return reinterpret_cast<const unsigned char*>(bytes_.data()); }

    std::vector<std::byte> owned_;
    std::span<const std::byte> bytes_;
    TjHandle tj_;
};

std::vector<std::byte> readWholeFile(const std::string& path) {
    FilePtr file = openForReading(path);
    std::vector<std::byte> bytes;
    std::byte buffer[1 << 16];
    size_t n;
    while ((n = std::fread(buffer, 1, sizeof buffer, file.get())) > 0)
        bytes.insert(bytes.end(), buffer, buffer + n);
    if (std::ferror(file.get())) throw ImageCodecError("cannot read the file");
    return bytes;
}

// --- Radiance HDR (stb_image) ---------------------------------------------------------------------------

// What in a Radiance HDR file's run-length encoded scanlines (from `file`, the whole file) stb_image would
// loop on for ever: its decoder reads zeros past the end, and a dump of length 0 never ends a scanline. The
// scanlines are walked as stb_image decodes them; the problem in words, or nothing (a flat file, and any
// other fault stb_image reports itself).
std::optional<std::string> hdrScanlineError(std::span<const uint8_t> file, int width, int height) {
    // The header ends with an empty line, then the resolution line.
    const std::string_view text(reinterpret_cast<const char*>(file.data()), file.size());
    const size_t blank = text.find("\n\n");
    if (blank == std::string_view::npos) return std::nullopt;
    const size_t resolutionEnd = text.find('\n', blank + 2);
    if (resolutionEnd == std::string_view::npos) return std::nullopt;
    if (width < 8 || width >= 32768) return std::nullopt;  // stored flat
    size_t at = resolutionEnd + 1;
    auto ended = [&](int row) { return fmt::format("the data end in row {} of {}", row + 1, height); };
    for (int row = 0; row < height; ++row) {
        if (file.size() - at < 4) return ended(row);
        if (file[at] != 2 || file[at + 1] != 2 || (file[at + 2] & 0x80))
            return std::nullopt;  // flat from here
        if (((file[at + 2] << 8) | file[at + 3]) != width) return std::nullopt;
        at += 4;
        for (int component = 0; component < 4; ++component)
            for (int filled = 0; filled < width;) {
                if (at >= file.size()) return ended(row);
                int count = file[at++];
                if (count > 128) {
                    count -= 128;
                    ++at;  // the run's value
                } else {
                    if (count == 0) return fmt::format("row {} holds a run of length 0", row + 1);
                    at += static_cast<size_t>(count);
                }
                if (at > file.size()) return ended(row);
                if (count > width - filled) return std::nullopt;
                filled += count;
            }
    }
    return std::nullopt;
}

class HdrDecoder : public ImageDecoder {
  public:
    // From `path` or, without one, from `bytes`.
    HdrDecoder(const std::string& path, std::span<const std::byte> bytes) : path_(path), bytes_(bytes) {
        int width = 0, height = 0, channels = 0;
        const bool ok = path_.empty() ? stbi_info_from_memory(data(), size(), &width, &height, &channels) != 0
                                      : stbi_info(path_.c_str(), &width, &height, &channels) != 0;
        if (!ok) throw ImageCodecError(fmt::format("invalid Radiance HDR file: {}", stbi_failure_reason()));
        header_.width = header_.fullWidth = width;
        header_.height = header_.fullHeight = height;
        header_.channels = 3;
        header_.bits = 32;
    }

    void readUInt8(std::span<uint8_t>) override {
        throw ImageCodecError("a Radiance HDR file holds no 8-bit pixels");
    }

    void readFloat(std::span<float> pixels) override {
        if (pixels.size() != static_cast<size_t>(header_.width) * header_.height * 3)
            throw ImageCodecError("the pixels' buffer is not the image's size");
        // The file's bytes, checked before stb_image decodes them (hdrScanlineError).
        std::vector<std::byte> fileBytes;
        std::span<const std::byte> bytes = bytes_;
        if (!path_.empty()) {
            fileBytes = readWholeFile(path_);
            bytes = fileBytes;
        }
        if (const auto error =
                hdrScanlineError(std::span(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()),
                                 header_.width, header_.height))
            throw ImageCodecError(fmt::format("invalid Radiance HDR file: {}", *error));
        if (bytes.size() > static_cast<size_t>(INT32_MAX))
            throw ImageCodecError("a Radiance HDR image of more than 2 GiB");
        int width = 0, height = 0, channels = 0;
        float* rgb = stbi_loadf_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                            static_cast<int>(bytes.size()), &width, &height, &channels, 3);
        if (rgb == nullptr)
            throw ImageCodecError(fmt::format("invalid Radiance HDR file: {}", stbi_failure_reason()));
        const std::unique_ptr<float, void (*)(void*)> owned(rgb, stbi_image_free);
        if (width != header_.width || height != header_.height)
            throw ImageCodecError("invalid Radiance HDR file: its size changed while it was read");
        std::memcpy(pixels.data(), rgb, pixels.size() * sizeof(float));
    }

  private:
    const stbi_uc* data() const { return reinterpret_cast<const stbi_uc*>(bytes_.data()); }
    int size() const {
        if (bytes_.size() > static_cast<size_t>(INT32_MAX))
            throw ImageCodecError("a Radiance HDR image of more than 2 GiB in memory");
        return static_cast<int>(bytes_.size());
    }

    std::string path_;
    std::span<const std::byte> bytes_;
};

}  // namespace

std::unique_ptr<ImageDecoder> openImageFile(const std::string& path) {
    const std::optional<ImageFormat> format = imageFormatOfExtension(lowerExtension(path));
    if (!format)
        throw ImageCodecError(fmt::format("unsupported image format '{}'; deltagi reads {}",
                                          lowerExtension(path), kReadableImageFormats));
    switch (*format) {
        case ImageFormat::Png: {
            FilePtr file = openForReading(path);
            if (std::optional<std::string> chunks = pngFileChunkError(file.get()))
                throw ImageCodecError(*chunks);
            return std::make_unique<PngDecoder>(std::move(file), std::span<const std::byte>());
        }
        case ImageFormat::Jpeg:
            return std::make_unique<JpegDecoder>(readWholeFile(path), std::span<const std::byte>());
        case ImageFormat::Exr:
            openForReading(path);
            return openExrFile(path);
        case ImageFormat::Hdr:
            openForReading(path);
            return std::make_unique<HdrDecoder>(path, std::span<const std::byte>());
    }
    throw ImageCodecError("unknown image format");
}

std::unique_ptr<ImageDecoder> openImageBytes(std::span<const std::byte> bytes, ImageFormat format) {
    switch (format) {
        case ImageFormat::Png:
            if (std::optional<std::string> chunks = pngChunkError(bytes, bytes.size()))
                throw ImageCodecError(*chunks);
            return std::make_unique<PngDecoder>(nullptr, bytes);
        case ImageFormat::Jpeg:
            return std::make_unique<JpegDecoder>(std::vector<std::byte>(), bytes);
        case ImageFormat::Exr:
            return openExrBytes(bytes);
        case ImageFormat::Hdr:
            return std::make_unique<HdrDecoder>(std::string(), bytes);
    }
    throw ImageCodecError("unknown image format");
}

// --- Encoders -------------------------------------------------------------------------------------------

namespace {

struct PngWriter {
    std::string bytes;
    bool outOfMemory = false;
    static void write(png_structp png, png_bytep data, size_t length) {
        auto* self = static_cast<PngWriter*>(png_get_io_ptr(png));
        try {
            self->bytes.append(reinterpret_cast<const char*>(data), length);
        } catch (const std::bad_alloc&) {
            self->outOfMemory = true;
            png_error(png, "out of memory");
        }
    }
    static void flush(png_structp) {}
};

bool writePng(png_structp png, png_infop info, PngErrors& errors, png_bytepp rows, int width, int height,
              int colorType) {
    if (setjmp(errors.jump)) return false;
    png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, colorType,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    return true;
}

}  // namespace

std::string encodePng8(std::span<const uint8_t> pixels, int width, int height, int channels) {
    static constexpr int kColorTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                          PNG_COLOR_TYPE_RGB_ALPHA};
    if (channels < 1 || channels > 4 || width <= 0 || height <= 0 ||
        pixels.size() != static_cast<size_t>(width) * height * channels)
        throw ImageCodecError(
            fmt::format("cannot encode PNG: {}x{} pixels of {} channels", width, height, channels));
    PngErrors errors;
    PngWriter writer;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errors, pngError, pngWarning);
    png_infop info = png == nullptr ? nullptr : png_create_info_struct(png);
    struct Destroy {
        png_structp& png;
        png_infop& info;
        ~Destroy() { png_destroy_write_struct(&png, &info); }
    } destroy{png, info};
    if (png == nullptr || info == nullptr) throw std::bad_alloc();
    png_set_write_fn(png, &writer, PngWriter::write, PngWriter::flush);
    std::vector<png_bytep> rows(height);
    const size_t rowBytes = static_cast<size_t>(width) * channels;
    for (int y = 0; y < height; ++y) rows[y] = const_cast<png_bytep>(pixels.data() + rowBytes * y);
    if (!writePng(png, info, errors, rows.data(), width, height, kColorTypes[channels - 1])) {
        if (writer.outOfMemory) throw std::bad_alloc();
        throw ImageCodecError(fmt::format("cannot encode PNG: {}", errors.message));
    }
    return std::move(writer.bytes);
}

std::string encodeJpeg8(std::span<const uint8_t> rgb, int width, int height, int quality) {
    if (width <= 0 || height <= 0 || rgb.size() != static_cast<size_t>(width) * height * 3)
        throw ImageCodecError(
            fmt::format("cannot encode JPEG: {}x{} RGB pixels in {} bytes", width, height, rgb.size()));
    TjHandle tj(tjInitCompress());
    unsigned char* jpeg = nullptr;
    unsigned long size = 0;
    const int status = tjCompress2(tj.handle, rgb.data(), width, 0, height, TJPF_RGB, &jpeg, &size,
                                   TJSAMP_420, std::clamp(quality, 1, 100), 0);
    const std::unique_ptr<unsigned char, void (*)(unsigned char*)> owned(jpeg, tjFree);
    if (status != 0) throw ImageCodecError(fmt::format("cannot encode JPEG: {}", tjMessage(tj.handle)));
    return std::string(reinterpret_cast<const char*>(jpeg), size);
}

std::string encodeHdr(std::span<const float> rgb, int width, int height) {
    if (width <= 0 || height <= 0 || rgb.size() != static_cast<size_t>(width) * height * 3)
        throw ImageCodecError(fmt::format("cannot encode Radiance HDR: {}x{} RGB pixels in {} floats", width,
                                          height, rgb.size()));
    std::vector<float> clamped(rgb.begin(), rgb.end());
    for (float& v : clamped) v = v > 0.0f ? v : 0.0f;  // RGBE has no sign (and NaN is written as 0)
    std::string bytes;
    auto append = [](void* context, void* data, int size) {
        static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<size_t>(size));
    };
    if (stbi_write_hdr_to_func(append, &bytes, width, height, 3, clamped.data()) == 0)
        throw ImageCodecError("cannot encode Radiance HDR");
    return bytes;
}

}  // namespace deltagi
