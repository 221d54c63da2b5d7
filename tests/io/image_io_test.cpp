// Image files: round trips, sRGB decoding, and the errors for missing files and non-finite pixels.
#include <fcntl.h>
#include <sys/mount.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "io/image_codecs.h"
#include "io/image_encode.h"
#include "io/image_output.h"
#include "test_errors.h"
#include "test_image_files.h"
#include "test_paths.h"

namespace deltagi {
namespace {

using test::expectContains;
using test::inputErrorOf;

namespace fs = std::filesystem;

class ImageIoTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ =
            fs::temp_directory_path() / ("deltagi_image_io_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

// The sRGB encoding (IEC 61966-2-1), written out independently of the implementation.
double encodeSrgb(double linear) {
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

// A ramp over [0, 1] in every channel, different per channel.
Image ramp(int width, int height, int channels) {
    Image image(width, height, channels);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < channels; ++c)
                image.at(x, y, c) = static_cast<float>((x + y * width + 37 * c) % (width * height)) /
                                    static_cast<float>(width * height - 1);
    return image;
}

TEST_F(ImageIoTest, PngRoundTripWithinOneCodeValue) {
    Image image = ramp(16, 16, 3);
    image.at(0, 0, 0) = 2.0f;   // clamped to 1
    image.at(1, 0, 0) = -1.0f;  // clamped to 0
    writeImage(image, dir_ / "ramp.png");
    Image back = readImage(dir_ / "ramp.png");
    ASSERT_EQ(back.width(), 16);
    ASSERT_EQ(back.height(), 16);
    ASSERT_EQ(back.channels(), 3);
    EXPECT_FLOAT_EQ(back.at(0, 0, 0), 1.0f);
    EXPECT_FLOAT_EQ(back.at(1, 0, 0), 0.0f);
    // Compared in the encoded domain: rounding to 8 bits moves a value by at most half a code value.
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                if (y == 0 && x < 2 && c == 0) continue;
                EXPECT_NEAR(encodeSrgb(back.at(x, y, c)), encodeSrgb(image.at(x, y, c)), 0.5 / 255 + 1e-6);
            }
}

TEST_F(ImageIoTest, PngDecodesWithTheExactSrgbCurve) {
    // Code values 0..255 decoded must match the piecewise sRGB EOTF.
    Image codes(256, 1, 1);
    for (int i = 0; i < 256; ++i) {
        double v = i / 255.0;
        codes.at(i, 0, 0) = static_cast<float>(v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4));
    }
    writeImage(codes, dir_ / "codes.png");
    Image back = readImage(dir_ / "codes.png");
    ASSERT_EQ(back.channels(), 3);  // grey expanded
    for (int i = 0; i < 256; ++i) {
        EXPECT_NEAR(back.at(i, 0, 0), codes.at(i, 0, 0), 1e-6f) << "code " << i;
        EXPECT_EQ(back.at(i, 0, 2), back.at(i, 0, 0));
    }
    EXPECT_NEAR(back.at(128, 0, 0), 0.2158605f, 1e-6f);  // the textbook value for code 128
}

// The table-driven encoder gives the exact encoding's rounded byte: at every code's first float and the
// floats beside it, over a sweep of the floats in [0, 1], and for values out of range. (All 1.07e9 floats in
// [0, 1] were compared once; this checks the same at the places where it could fail.)
TEST(Srgb8Test, TheTablesGiveTheExactEncodingsByte) {
    auto exact = [](float v) { return static_cast<int>(std::lround(255.0f * linearToSrgbValue(v))); };
    const uint32_t one = std::bit_cast<uint32_t>(1.0f);
    int checked = 0;
    for (uint32_t b = 0; b <= one; b += 997, ++checked) {
        const float v = std::bit_cast<float>(b);
        ASSERT_EQ(linearToSrgb8(v), exact(v)) << "at " << v;
    }
    EXPECT_GT(checked, 1000000);
    // Around each code's boundary (found by bisection here, independently of the tables).
    for (int k = 1; k < 256; ++k) {
        uint32_t lo = 0, hi = one;
        while (hi - lo > 1) {
            const uint32_t mid = lo + (hi - lo) / 2;
            (exact(std::bit_cast<float>(mid)) >= k ? hi : lo) = mid;
        }
        for (uint32_t b = hi - std::min<uint32_t>(hi, 4); b <= std::min(one, hi + 4); ++b) {
            const float v = std::bit_cast<float>(b);
            ASSERT_EQ(linearToSrgb8(v), exact(v)) << "code " << k << " at " << v;
        }
    }
    EXPECT_EQ(linearToSrgb8(-1.0f), 0);
    EXPECT_EQ(linearToSrgb8(2.0f), 255);
    EXPECT_EQ(linearToSrgb8(std::nanf("")), 0);
    EXPECT_EQ(linearToSrgb8(std::numeric_limits<float>::infinity()), 0);
    EXPECT_EQ(linearToSrgb8(std::numeric_limits<float>::denorm_min()), 0);
}

TEST_F(ImageIoTest, ExrRoundTripIsExact) {
    for (int channels : {1, 3, 4}) {
        Image image = ramp(8, 5, channels);
        image.at(2, 3, 0) = -0.75f;  // negative and large values survive (deltas, HDR)
        image.at(3, 3, 0) = 12345.678f;
        fs::path file = dir_ / ("ramp" + std::to_string(channels) + ".exr");
        writeImage(image, file);
        Image back = readImage(file);
        ASSERT_EQ(back.width(), 8);
        ASSERT_EQ(back.height(), 5);
        ASSERT_EQ(back.channels(), 3);
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 8; ++x)
                for (int c = 0; c < 3; ++c)
                    EXPECT_EQ(back.at(x, y, c), image.at(x, y, channels >= 3 ? c : 0));
    }
}

std::string fileBytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Files of the same pixels written in different seconds must be the same bytes (a render run twice, a cache
// compared by checksum): no time of writing in the header (OpenEXR's "capDate", OpenImageIO's "DateTime").
TEST_F(ImageIoTest, ExrFilesOfTheSamePixelsAreTheSameBytes) {
    const Image image = ramp(8, 5, 3);
    const ImageLayer layers[] = {{"composite", &image, {"R", "G", "B"}}, {"delta", &image, {"R", "G", "B"}}};
    for (const char* name : {"a", "b"}) {
        writeImage(image, dir_ / (std::string(name) + ".exr"));
        writeLayers(layers, dir_ / (std::string(name) + "_layers.exr"));
        if (name[0] == 'a') usleep(1'100'000);  // into the next second of the clock
    }
    EXPECT_EQ(fileBytes(dir_ / "a.exr"), fileBytes(dir_ / "b.exr"));
    EXPECT_EQ(fileBytes(dir_ / "a_layers.exr"), fileBytes(dir_ / "b_layers.exr"));
    for (const char* file : {"a.exr", "a_layers.exr"}) {
        const std::string bytes = fileBytes(dir_ / file);
        ASSERT_NE(bytes.find("dataWindow"), std::string::npos) << file;  // an EXR header's attribute names
        EXPECT_EQ(bytes.find("capDate"), std::string::npos) << file;
        EXPECT_EQ(bytes.find("DateTime"), std::string::npos) << file;
    }
}

TEST_F(ImageIoTest, HdrRoundTripWithinRgbePrecision) {
    Image image(4, 2, 3);
    for (size_t i = 0; i < image.data().size(); ++i) image.data()[i] = 0.1f + 3.7f * static_cast<float>(i);
    writeImage(image, dir_ / "x.hdr");
    Image back = readImage(dir_ / "x.hdr");
    ASSERT_EQ(back.width(), 4);
    // RGBE keeps 8 mantissa bits per channel relative to the largest channel of the pixel.
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            float largest = std::max({image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2)});
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(back.at(x, y, c), image.at(x, y, c), largest / 128.0f);
        }
}

TEST_F(ImageIoTest, NonFinitePixelsAreWrittenAsZero) {
    Image image(3, 1, 3, 0.5f);
    image.at(0, 0, 1) = NAN;
    image.at(1, 0, 0) = INFINITY;
    image.at(2, 0, 2) = -INFINITY;
    for (const char* name : {"nan.exr", "nan.png", "nan.hdr"}) {
        writeImage(image, dir_ / name);
        Image back = readImage(dir_ / name);  // would throw if a NaN had been written
        EXPECT_EQ(back.at(0, 0, 1), 0.0f) << name;
        EXPECT_EQ(back.at(1, 0, 0), 0.0f) << name;
        EXPECT_EQ(back.at(2, 0, 2), 0.0f) << name;
        EXPECT_NEAR(back.at(0, 0, 0), 0.5f, 0.01f) << name;
    }
}

// A PFM (portable float map) written by hand, since writeImage never writes NaN.
// An EXR of the floats as they are (writeImage writes non-finite values as 0).
void writeRawExr(const fs::path& path, int width, int height, const std::vector<float>& rgb) {
    const std::string names[] = {"R", "G", "B"};
    std::ofstream(path, std::ios::binary) << encodeExr(rgb, width, height, names);
}

TEST_F(ImageIoTest, ReadingNonFinitePixelsIsAnError) {
    std::vector<float> pixels(4 * 2 * 3, 0.25f);
    pixels[0] = NAN;
    pixels[1] = NAN;  // the same pixel: counted once
    pixels[7] = INFINITY;
    writeRawExr(dir_ / "bad.exr", 4, 2, pixels);
    std::string message = inputErrorOf([&] { readImage(dir_ / "bad.exr"); });
    expectContains(message, "bad.exr");
    expectContains(message, "2 of 8 pixels are NaN or infinite");
}

TEST_F(ImageIoTest, MissingAndUnwritableFilesAreErrors) {
    std::string message = inputErrorOf([&] { readImage(dir_ / "missing.png"); });
    expectContains(message, "missing.png");
    expectContains(message, "cannot read image");

    message = inputErrorOf([&] { writeImage(Image(2, 2, 3), dir_ / "x.tiff"); });
    expectContains(message, "x.tiff");
    expectContains(message, ".png, .exr or .hdr");

    message = inputErrorOf([&] { writeImage(Image(2, 2, 3), dir_ / "no-such-folder" / "x.png"); });
    expectContains(message, "no-such-folder");
    expectContains(message, "does not exist");
    EXPECT_FALSE(fs::exists(dir_ / "no-such-folder"));
}

// Only PNG, JPEG, OpenEXR and Radiance HDR are read: another format is one error naming the file and those.
TEST_F(ImageIoTest, OtherFormatsAreErrorsNamingTheFormatsRead) {
    std::ofstream(dir_ / "photo.tif", std::ios::binary) << "II*";
    const std::string message = inputErrorOf([&] { readImage(dir_ / "photo.tif"); });
    expectContains(message, {"photo.tif", "unsupported image format '.tif'", "PNG, JPEG, OpenEXR"});
    EXPECT_EQ(imageFileSize(dir_ / "photo.tif"), std::nullopt);
}

// A palette PNG is read as its colours, sRGB-decoded; alpha from tRNS is dropped.
TEST_F(ImageIoTest, PalettePngIsReadAsItsColours) {
    const uint8_t palette[] = {255, 0, 0, 0, 51, 255};
    const uint8_t alphas[] = {128};
    const uint8_t indices[] = {0, 1, 1, 0};
    test::writePngPalette(dir_ / "palette.png", indices, 2, 2, palette, alphas);
    const Image image = readImage(dir_ / "palette.png");
    ASSERT_EQ(image.width(), 2);
    ASSERT_EQ(image.height(), 2);
    ASSERT_EQ(image.channels(), 3);
    EXPECT_EQ(image.rgb(0, 0), glm::vec3(1.0f, 0.0f, 0.0f));
    EXPECT_EQ(image.rgb(1, 0), glm::vec3(0.0f, srgbToLinearValue(51 / 255.0f), 1.0f));
    EXPECT_EQ(image.rgb(0, 1), image.rgb(1, 0));
    EXPECT_EQ(image.rgb(1, 1), image.rgb(0, 0));
}

TEST(ImageTest, RgbOfGreyAndColourImages) {
    Image grey(2, 1, 1, 0.25f);
    EXPECT_EQ(grey.rgb(1, 0), glm::vec3(0.25f));
    grey.setRgb(0, 0, glm::vec3(0.1f, 0.2f, 0.3f));
    EXPECT_FLOAT_EQ(grey.at(0, 0, 0), 0.2f);
    Image colour(2, 1, 4, 1.0f);
    colour.setRgb(1, 0, {0.1f, 0.2f, 0.3f});
    EXPECT_EQ(colour.rgb(1, 0), glm::vec3(0.1f, 0.2f, 0.3f));
    EXPECT_EQ(colour.at(1, 0, 3), 1.0f);  // alpha untouched
}

TEST(ImageIoSharedDataTest, VeniceSunsetHdrMean) {
    fs::path file = fs::path(test::kSharedDataDir) / "envmaps" / "venice_sunset_1k.hdr";
    if (!fs::exists(file)) GTEST_SKIP() << "shared data set not found: " << file << " (see ../shared/data)";
    Image image = readImage(file);
    ASSERT_EQ(image.width(), 1024);
    ASSERT_EQ(image.height(), 512);
    glm::dvec3 sum(0.0);
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x) sum += glm::dvec3(image.rgb(x, y));
    glm::dvec3 mean = sum / static_cast<double>(image.pixelCount());
    // The data set's README gives the mean to 3 digits.
    EXPECT_NEAR(mean.x, 0.525, 0.0015);
    EXPECT_NEAR(mean.y, 0.561, 0.0015);
    EXPECT_NEAR(mean.z, 0.662, 0.0015);
}

// A full disk (a 256 KiB tmpfs, filled; mounting needs root, skipped otherwise): an image that does not fit
// fails with one error naming the file, and the previous file stays as it was, whatever the format.
TEST(ImageWrite, AFullDiskKeepsThePreviousFile) {
    if (geteuid() != 0) GTEST_SKIP() << "mounting a tmpfs needs root";
    const fs::path dir = fs::temp_directory_path() / ("deltagi-full-disk-" + std::to_string(getpid()));
    fs::create_directories(dir);
    if (mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=256k") != 0) {
        const std::string why = std::strerror(errno);
        fs::remove_all(dir);
        GTEST_SKIP() << "cannot mount a tmpfs here: " << why;
    }
    Image noise(160, 120, 3);
    uint32_t state = 12345;
    for (float& v : noise.data()) {
        state = state * 1664525u + 1013904223u;
        v = static_cast<float>(state >> 8) / 16777216.0f;
    }
    for (const char* name : {"x.png", "x.exr", "x.hdr"}) {
        std::ofstream(dir / name) << "previous";
    }
    const int fill = ::open((dir / "fill").c_str(), O_WRONLY | O_CREAT, 0644);
    const std::string block(4096, 'f');
    while (::write(fill, block.data(), block.size()) > 0) {
    }
    ::close(fill);
    for (const char* name : {"x.png", "x.exr", "x.hdr"}) {
        try {
            writeImage(noise, dir / name);
            ADD_FAILURE() << name << " was written on a full disk";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
        }
        std::ifstream in(dir / name);
        EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "previous") << name;
    }
    size_t files = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++files;
    EXPECT_EQ(files, 4u) << "a temporary was left";
    umount(dir.c_str());
    fs::remove_all(dir);
}

// An EXR whose data window is offset within a larger display window is read as the display window, its
// pixels in their place and the rest 0 (it was read as the data window alone, shifted to the corner).
TEST(ImageRead, AnExrIsItsDisplayWindow) {
    const fs::path file = fs::temp_directory_path() / ("deltagi-window-" + std::to_string(getpid()) + ".exr");
    std::vector<float> pixels(4 * 2 * 3);
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = 1.0f + static_cast<float>(i);
    test::writeExrInWindow(file, pixels, 4, 2, 3, 1, 8, 5);
    const Image image = readImage(file);
    ASSERT_EQ(image.width(), 8);
    ASSERT_EQ(image.height(), 5);
    EXPECT_EQ(imageFileSize(file), (std::pair{8, 5}));
    EXPECT_EQ(image.at(0, 0, 0), 0.0f);
    EXPECT_EQ(image.at(3, 1, 0), 1.0f);  // the data window's first pixel
    EXPECT_EQ(image.at(6, 2, 2), pixels.back());
    EXPECT_EQ(image.at(7, 4, 1), 0.0f);
    fs::remove(file);
}

// A PNG's chunks are checked against its bytes before libpng reads them: a chunk longer than what is left (a
// cut file, a text chunk claiming gigabytes) is named; a whole PNG passes, and so does what is not a PNG.
TEST(PngChunkTest, AChunkLongerThanTheFileIsNamed) {
    Image image(8, 4, 3, 0.5f);
    const std::string png = encodePngBytes(image, "test.png");
    const auto bytes = [](const std::string& s) { return std::as_bytes(std::span(s.data(), s.size())); };
    EXPECT_FALSE(pngChunkError(bytes(png), png.size()));
    EXPECT_FALSE(pngChunkError(bytes("not a png at all"), 16));
    // Cut inside the IDAT chunk.
    const std::string cut = png.substr(0, png.find("IDAT") + 10);
    const std::optional<std::string> truncated = pngChunkError(bytes(cut), cut.size());
    ASSERT_TRUE(truncated);
    expectContains(*truncated, {"truncated or corrupt", "'IDAT' chunk claims"});
    // The first chunk after the header claims 1.7 GB.
    std::string huge = png;
    const size_t length = png.find("IDAT") - 4;
    huge.replace(length, 4, std::string("\x68\x00\x00\x70", 4));
    const std::optional<std::string> claims = pngChunkError(bytes(huge), huge.size());
    ASSERT_TRUE(claims);
    expectContains(*claims, {"'IDAT' chunk claims 1744830576 bytes"});
    // As a file: refused by openImageFile before libpng reads it.
    const std::filesystem::path file = std::filesystem::temp_directory_path() / "deltagi_png_chunk_test.png";
    std::ofstream(file, std::ios::binary) << huge;
    std::string error;
    try {
        openImageFile(file.string());
    } catch (const ImageCodecError& e) {
        error = e.what();
    }
    expectContains(error, {"'IDAT' chunk claims 1744830576 bytes"});
    std::filesystem::remove(file);
}

}  // namespace
}  // namespace deltagi
