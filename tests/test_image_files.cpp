// Test image files written with libpng and OpenEXR directly (test_image_files.h). A library of its own
// (tests/CMakeLists.txt): only this file needs OpenEXR's include folders.
#include "test_image_files.h"

#include <csetjmp>
#include <cstdio>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <png.h>

namespace deltagi::test {

namespace {

void pngError(png_structp png, png_const_charp) {
    std::longjmp(png_jmpbuf(png), 1);
}

// libpng's calls, with no object to destroy between setjmp() and the longjmp() of an error.
// `palette` (RGB triples) and `alphas` for a palette image, else empty.
bool writePngRows(png_structp png, png_infop info, std::FILE* file, png_bytepp rows, int width, int height,
                  int bits, int colorType, std::span<const uint8_t> palette,
                  std::span<const uint8_t> alphas) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, file);
    png_set_IHDR(png, info, width, height, bits, colorType, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    std::vector<png_color> colors(palette.size() / 3);
    for (size_t i = 0; i < colors.size(); ++i)
        colors[i] = {palette[3 * i], palette[3 * i + 1], palette[3 * i + 2]};
    if (!colors.empty()) png_set_PLTE(png, info, colors.data(), static_cast<int>(colors.size()));
    if (!alphas.empty()) png_set_tRNS(png, info, alphas.data(), static_cast<int>(alphas.size()), nullptr);
    png_write_info(png, info);
    if (bits == 16)
        png_set_swap(png);  // the samples are in the machine's (little-endian) order; PNG's are big-endian
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    return true;
}

}  // namespace

void writePng16(const std::filesystem::path& path, std::span<const uint16_t> samples, int width, int height,
                int channels) {
    static constexpr int kColorTypes[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                          PNG_COLOR_TYPE_RGB_ALPHA};
    if (channels < 1 || channels > 4 || samples.size() != static_cast<size_t>(width) * height * channels)
        throw std::invalid_argument("writePng16: samples and size disagree");
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"), std::fclose);
    if (!file) throw std::runtime_error("writePng16: cannot create " + path.string());
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, pngError, nullptr);
    png_infop info = png_create_info_struct(png);
    std::vector<png_bytep> rows(height);
    for (int y = 0; y < height; ++y)
        rows[y] = reinterpret_cast<png_bytep>(const_cast<uint16_t*>(samples.data()) +
                                              static_cast<size_t>(y) * width * channels);
    const bool ok = writePngRows(png, info, file.get(), rows.data(), width, height, 16,
                                 kColorTypes[channels - 1], {}, {});
    png_destroy_write_struct(&png, &info);
    if (!ok) throw std::runtime_error("writePng16: libpng failed on " + path.string());
}

void writePngPalette(const std::filesystem::path& path, std::span<const uint8_t> indices, int width,
                     int height, std::span<const uint8_t> palette, std::span<const uint8_t> alphas) {
    if (indices.size() != static_cast<size_t>(width) * height || palette.size() % 3 != 0)
        throw std::invalid_argument("writePngPalette: indices and size disagree");
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"), std::fclose);
    if (!file) throw std::runtime_error("writePngPalette: cannot create " + path.string());
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, pngError, nullptr);
    png_infop info = png_create_info_struct(png);
    std::vector<png_bytep> rows(height);
    for (int y = 0; y < height; ++y)
        rows[y] = const_cast<png_bytep>(indices.data() + static_cast<size_t>(y) * width);
    const bool ok = writePngRows(png, info, file.get(), rows.data(), width, height, 8, PNG_COLOR_TYPE_PALETTE,
                                 palette, alphas);
    png_destroy_write_struct(&png, &info);
    if (!ok) throw std::runtime_error("writePngPalette: libpng failed on " + path.string());
}

void writeExrInWindow(const std::filesystem::path& path, std::span<const float> rgb, int width, int height,
                      int dataX, int dataY, int fullWidth, int fullHeight) {
    const Imath::Box2i display({0, 0}, {fullWidth - 1, fullHeight - 1});
    const Imath::Box2i data({dataX, dataY}, {dataX + width - 1, dataY + height - 1});
    Imf::Header header(display, data);
    Imf::FrameBuffer frame;
    const char* names[] = {"R", "G", "B"};
    for (int c = 0; c < 3; ++c) {
        header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        frame.insert(names[c], Imf::Slice::Make(Imf::FLOAT, rgb.data() + c, data, 3 * sizeof(float),
                                                3 * sizeof(float) * width));
    }
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(height);
}

}  // namespace deltagi::test
