// OpenEXR files read and written with the OpenEXR library (image_codecs.h). Built apart from the rest of the
// library (CMakeLists.txt): only this file needs OpenEXR's and Imath's include folders.
#include "io/exr_codec.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <new>
#include <tuple>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <fmt/format.h>

namespace deltagi {

namespace {

// `bytes` as an OpenEXR input stream.
class MemoryIStream : public Imf::IStream {
  public:
    explicit MemoryIStream(std::span<const std::byte> bytes) : Imf::IStream("embedded.exr"), bytes_(bytes) {}
    bool read(char c[], int n) override {
        if (n < 0 || position_ + static_cast<uint64_t>(n) > bytes_.size())
            throw std::runtime_error("the data end before the image does");
        std::memcpy(c, bytes_.data() + position_, static_cast<size_t>(n));
        position_ += static_cast<uint64_t>(n);
        return position_ < bytes_.size();
    }
    uint64_t tellg() override { return position_; }
    void seekg(uint64_t position) override { position_ = position; }

  private:
    std::span<const std::byte> bytes_;
    uint64_t position_ = 0;
};

// An OpenEXR output stream into `bytes`.
class MemoryOStream : public Imf::OStream {
  public:
    explicit MemoryOStream(std::string& bytes) : Imf::OStream("image.exr"), bytes_(bytes) {}
    void write(const char c[], int n) override {
        if (position_ + n > bytes_.size()) bytes_.resize(position_ + n);
        std::memcpy(bytes_.data() + position_, c, static_cast<size_t>(n));
        position_ += static_cast<uint64_t>(n);
    }
    uint64_t tellp() override { return position_; }
    void seekp(uint64_t position) override { position_ = position; }

  private:
    std::string& bytes_;
    uint64_t position_ = 0;
};

// The order channels are given in: by layer (the name up to the last dot), then R, G, B, A, then the others
// by name. OpenEXR lists them by name only (B before G before R); readers take an image's first three as RGB.
std::tuple<std::string, int, std::string> channelOrder(const std::string& name) {
    const size_t dot = name.rfind('.');
    std::string layer = dot == std::string::npos ? std::string() : name.substr(0, dot);
    std::string channel = dot == std::string::npos ? name : name.substr(dot + 1);
    static constexpr const char* kFirst[] = {"R", "G", "B", "A"};
    int rank = 4;
    for (int i = 0; i < 4; ++i)
        if (channel == kFirst[i]) rank = i;
    return {std::move(layer), rank, std::move(channel)};
}

[[noreturn]] void rethrowAsCodecError(const std::exception& e) {
    throw ImageCodecError(fmt::format("invalid OpenEXR file: {}", e.what()));
}

class ExrDecoder : public ImageDecoder {
  public:
    // `stream` (may be null: read from `path`) must outlive the decoder.
    ExrDecoder(const std::string& path, std::unique_ptr<Imf::IStream> stream) : stream_(std::move(stream)) {
        try {
            file_ = stream_ ? std::make_unique<Imf::InputFile>(*stream_)
                            : std::make_unique<Imf::InputFile>(path.c_str());
            const Imf::Header& header = file_->header();
            const Imath::Box2i data = header.dataWindow(), display = header.displayWindow();
            header_.width = data.max.x - data.min.x + 1;
            header_.height = data.max.y - data.min.y + 1;
            header_.fullWidth = display.max.x - display.min.x + 1;
            header_.fullHeight = display.max.y - display.min.y + 1;
            header_.dataX = data.min.x - display.min.x;
            header_.dataY = data.min.y - display.min.y;
            header_.bits = 32;
            for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
                if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                    throw ImageCodecError(fmt::format(
                        "its channel '{}' is subsampled, which deltagi does not read", it.name()));
                header_.channelNames.emplace_back(it.name());
            }
            std::stable_sort(
                header_.channelNames.begin(), header_.channelNames.end(),
                [](const std::string& a, const std::string& b) { return channelOrder(a) < channelOrder(b); });
            header_.channels = static_cast<int>(header_.channelNames.size());
        } catch (const ImageCodecError&) {
            throw;
        } catch (const std::bad_alloc&) {
            throw;
        } catch (const std::exception& e) {
            rethrowAsCodecError(e);
        }
    }

    void readUInt8(std::span<uint8_t>) override {
        throw ImageCodecError("an OpenEXR file holds no 8-bit pixels");
    }

    void readFloat(std::span<float> pixels) override {
        const size_t channels = static_cast<size_t>(header_.channels);
        if (pixels.size() != static_cast<size_t>(header_.width) * header_.height * channels)
            throw ImageCodecError("the pixels' buffer is not the image's size");
        try {
            const Imath::Box2i data = file_->header().dataWindow();
            Imf::FrameBuffer frame;
            for (size_t c = 0; c < channels; ++c)
                frame.insert(header_.channelNames[c],
                             Imf::Slice::Make(Imf::FLOAT, pixels.data() + c, data, channels * sizeof(float),
                                              channels * sizeof(float) * header_.width));
            file_->setFrameBuffer(frame);
            file_->readPixels(data.min.y, data.max.y);
        } catch (const std::bad_alloc&) {
            throw;
        } catch (const std::exception& e) {
            rethrowAsCodecError(e);
        }
    }

  private:
    std::unique_ptr<Imf::IStream> stream_;
    std::unique_ptr<Imf::InputFile> file_;
};

}  // namespace

std::unique_ptr<ImageDecoder> openExrFile(const std::string& path) {
    return std::make_unique<ExrDecoder>(path, nullptr);
}

std::unique_ptr<ImageDecoder> openExrBytes(std::span<const std::byte> bytes) {
    return std::make_unique<ExrDecoder>(std::string(), std::make_unique<MemoryIStream>(bytes));
}

std::string encodeExr(std::span<const float> pixels, int width, int height,
                      std::span<const std::string> channelNames) {
    const size_t channels = channelNames.size();
    if (width <= 0 || height <= 0 || channels == 0 ||
        pixels.size() != static_cast<size_t>(width) * height * channels)
        throw ImageCodecError("cannot encode OpenEXR: the pixels are not the image's size");
    std::string bytes;
    try {
        // Imf::Header's attributes: the windows, aspect ratio, screen window, line order and compression,
        // none of which varies between writes.
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const std::string& name : channelNames) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
        Imf::FrameBuffer frame;
        for (size_t c = 0; c < channels; ++c)
            frame.insert(
                channelNames[c],
                Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(pixels.data() + c)),
                           channels * sizeof(float), channels * sizeof(float) * width));
        MemoryOStream stream(bytes);
        Imf::OutputFile file(stream, header);
        file.setFrameBuffer(frame);
        file.writePixels(height);
    } catch (const std::bad_alloc&) {
        throw;
    } catch (const std::exception& e) {
        throw ImageCodecError(fmt::format("cannot encode OpenEXR: {}", e.what()));
    }
    return bytes;
}

}  // namespace deltagi
