// Textures: decoding files and embedded images (sRGB, linear, channel expansion), the mip chain (it keeps
// the mean, any size), glTF's wrap modes and filters against hand-computed texels, and bad input.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/texture.h"
#include "io/image_codecs.h"
#include "test_errors.h"
#include "test_image_files.h"

namespace deltagi {
namespace {

using test::expectContains;
using test::inputErrorOf;

namespace fs = std::filesystem;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// The sRGB decoding (IEC 61966-2-1), written out independently of the implementation.
double decodeSrgb(double encoded) {
    return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

// The exact sRGB encoding of a linear value in [0, 1] (IEC 61966-2-1).
double encodeSrgb(double linear) {
    return linear <= 0.0031308 ? linear * 12.92 : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

void expectNear(glm::vec4 actual, glm::vec4 expected, float tolerance, const std::string& what = "") {
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(actual[c], expected[c], tolerance) << what << ", channel " << c;
}

void expectEqual(glm::vec4 actual, glm::vec4 expected, const std::string& what = "") {
    for (int c = 0; c < 4; ++c) EXPECT_EQ(actual[c], expected[c]) << what << ", channel " << c;
}

// Writes `values` (width * height * channels, interleaved) as an image file: 8-bit samples as a PNG or a
// JPEG (by the extension), 16-bit ones as a PNG, floats as an OpenEXR file.
template <typename T>
void writeImage(const fs::path& path, int width, int height, int channels, const std::vector<T>& values) {
    if constexpr (std::is_same_v<T, uint16_t>) {
        test::writePng16(path, values, width, height, channels);
        return;
    }
    std::string bytes;
    if constexpr (std::is_same_v<T, uint8_t>)
        bytes = path.extension() == ".jpg" ? encodeJpeg8(values, width, height, 90)
                                           : encodePng8(values, width, height, channels);
    if constexpr (std::is_same_v<T, float>) {
        std::vector<std::string> names = {"R", "G", "B", "A"};
        names.resize(channels);
        bytes = encodeExr(values, width, height, names);
    }
    std::ofstream(path, std::ios::binary) << bytes;
}

std::vector<std::byte> readBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::byte> bytes(chars.size());
    for (size_t i = 0; i < chars.size(); ++i) bytes[i] = static_cast<std::byte>(chars[i]);
    return bytes;
}

void writeBytes(const fs::path& path, const std::vector<std::byte>& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

class TextureFileTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::path(::testing::TempDir()) /
               ("deltagi_texture_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

// A 2x1 RGBA PNG: (0, 128, 255, 64) and (10, 200, 40, 255).
const std::vector<uint8_t> kRgba8 = {0, 128, 255, 64, 10, 200, 40, 255};

TEST_F(TextureFileTest, SrgbPngIsDecodedAndAlphaStaysLinear) {
    fs::path file = dir_ / "colour.png";
    writeImage(file, 2, 1, 4, kRgba8);
    auto texture = Texture::load(file, TextureEncoding::Srgb, "");
    ASSERT_EQ(texture->width(), 2);
    ASSERT_EQ(texture->height(), 1);
    EXPECT_EQ(texture->name(), file.string());
    for (int x = 0; x < 2; ++x) {
        const uint8_t* v = &kRgba8[x * 4];
        glm::vec4 expected(decodeSrgb(v[0] / 255.0), decodeSrgb(v[1] / 255.0), decodeSrgb(v[2] / 255.0),
                           v[3] / 255.0);
        expectNear(texture->texel(0, x, 0), expected, 1e-6f, "texel " + std::to_string(x));
    }
    // A value that decodes far from itself: 128 / 255 = 0.502 is 0.216 linear.
    EXPECT_NEAR(texture->texel(0, 0, 0).y, 0.2158605f, 1e-6f);
}

TEST_F(TextureFileTest, LinearDataTexturesAreNotDecoded) {
    fs::path file = dir_ / "data.png";
    writeImage(file, 2, 1, 4, kRgba8);
    auto texture = Texture::load(file, TextureEncoding::Linear, "");
    for (int x = 0; x < 2; ++x) {
        const uint8_t* v = &kRgba8[x * 4];
        glm::vec4 expected(v[0] / 255.0f, v[1] / 255.0f, v[2] / 255.0f, v[3] / 255.0f);
        expectNear(texture->texel(0, x, 0), expected, 1e-7f, "texel " + std::to_string(x));
    }
}

TEST_F(TextureFileTest, SixteenBitPngIsDecodedToo) {
    fs::path file = dir_ / "deep.png";
    writeImage(file, 1, 1, 3, std::vector<uint16_t>{0, 32768, 65535});
    glm::vec4 srgb = Texture::load(file, TextureEncoding::Srgb, "")->texel(0, 0, 0);
    expectNear(srgb, glm::vec4(0.0f, decodeSrgb(32768.0 / 65535.0), 1.0f, 1.0f), 1e-6f);
    glm::vec4 linear = Texture::load(file, TextureEncoding::Linear, "")->texel(0, 0, 0);
    expectNear(linear, glm::vec4(0.0f, 32768.0f / 65535.0f, 1.0f, 1.0f), 1e-6f);
}

TEST_F(TextureFileTest, FloatFilesAreLinearWhateverTheEncoding) {
    fs::path file = dir_ / "radiance.exr";
    writeImage(file, 1, 1, 3, std::vector<float>{0.5f, 2.0f, 0.25f});
    glm::vec4 texel = Texture::load(file, TextureEncoding::Srgb, "")->texel(0, 0, 0);
    expectEqual(texel, glm::vec4(0.5f, 2.0f, 0.25f, 1.0f));
}

TEST_F(TextureFileTest, GreyAndMissingAlphaAreExpanded) {
    fs::path grey = dir_ / "grey.png", greyAlpha = dir_ / "grey_alpha.png", rgb = dir_ / "rgb.png";
    writeImage(grey, 1, 1, 1, std::vector<uint8_t>{51});
    writeImage(greyAlpha, 1, 1, 2, std::vector<uint8_t>{51, 102});
    writeImage(rgb, 1, 1, 3, std::vector<uint8_t>{51, 102, 153});
    float g = 51 / 255.0f;
    expectNear(Texture::load(grey, TextureEncoding::Linear, "")->texel(0, 0, 0), {g, g, g, 1.0f}, 1e-7f,
               "grey");
    expectNear(Texture::load(greyAlpha, TextureEncoding::Linear, "")->texel(0, 0, 0), {g, g, g, 102 / 255.0f},
               1e-7f, "grey + alpha");
    expectNear(Texture::load(rgb, TextureEncoding::Linear, "")->texel(0, 0, 0),
               {g, 102 / 255.0f, 153 / 255.0f, 1.0f}, 1e-7f, "rgb");
    // sRGB decodes grey, never alpha.
    float greySrgb = static_cast<float>(decodeSrgb(51 / 255.0));
    expectNear(Texture::load(greyAlpha, TextureEncoding::Srgb, "")->texel(0, 0, 0),
               {greySrgb, greySrgb, greySrgb, 102 / 255.0f}, 1e-6f, "grey + alpha, sRGB");
}

void expectSameTexels(const Texture& a, const Texture& b) {
    ASSERT_EQ(a.width(), b.width());
    ASSERT_EQ(a.height(), b.height());
    for (int y = 0; y < a.height(); ++y)
        for (int x = 0; x < a.width(); ++x) expectEqual(a.texel(0, x, y), b.texel(0, x, y));
}

TEST_F(TextureFileTest, DecodingFromMemoryEqualsLoadingTheFile) {
    std::vector<uint8_t> pixels;
    for (int i = 0; i < 5 * 3 * 4; ++i) pixels.push_back(static_cast<uint8_t>(i * 37 % 256));
    fs::path png = dir_ / "image.png", jpeg = dir_ / "image.jpg";
    writeImage(png, 5, 3, 4, pixels);
    std::vector<uint8_t> rgb;
    for (size_t i = 0; i < pixels.size(); ++i)
        if (i % 4 != 3) rgb.push_back(pixels[i]);
    writeImage(jpeg, 5, 3, 3, rgb);

    auto fromFile = Texture::load(png, TextureEncoding::Srgb, "");
    std::vector<std::byte> bytes = readBytes(png);
    // The hint as an extension, a MIME type, none (the signature), and a wrong one (the signature wins).
    for (std::string hint : {"png", ".PNG", "image/png", "", "image/jpeg"}) {
        SCOPED_TRACE("hint '" + hint + "'");
        auto fromMemory = Texture::decode(bytes, hint, TextureEncoding::Srgb, "scene.glb: images[0]");
        EXPECT_EQ(fromMemory->name(), "scene.glb: images[0]");
        expectSameTexels(*fromMemory, *fromFile);
    }
    auto jpegFromFile = Texture::load(jpeg, TextureEncoding::Srgb, "");
    auto jpegFromMemory = Texture::decode(readBytes(jpeg), "", TextureEncoding::Srgb, "");
    EXPECT_EQ(jpegFromMemory->name(), "embedded texture");
    expectSameTexels(*jpegFromMemory, *jpegFromFile);
}

// A w x h texture whose texel (x, y) is (x, y, x + 10 y, 1).
Texture indexTexture(int width, int height) {
    std::vector<glm::vec4> texels;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) texels.emplace_back(x, y, x + 10 * y, 1.0f);
    return Texture(width, height, std::move(texels), "index");
}

TextureSampler samplerOf(TextureWrap wrapS, TextureWrap wrapT, TextureFilter filter) {
    TextureSampler sampler;
    sampler.wrapS = wrapS;
    sampler.wrapT = wrapT;
    sampler.magFilter = sampler.minFilter = filter;
    return sampler;
}

TEST(TextureSample, WrapModesOnNearestTexels) {
    // Four texels in u, centres at 0.125, 0.375, 0.625, 0.875; each u below is a texel centre.
    Texture texture = indexTexture(4, 1);
    struct Case {
        float u;
        float repeat, clamp, mirror;
    };
    const Case cases[] = {
        {0.375f, 1, 1, 1},        // inside
        {-0.125f, 3, 0, 0},       // texel -1
        {-0.375f, 2, 0, 1},       // texel -2
        {1.125f, 0, 3, 3},        // texel 4
        {1.375f, 1, 3, 2},        // texel 5
        {2.125f, 0, 3, 0},        // texel 8: a whole mirrored period on
        {-1.125f, 3, 0, 3},       // texel -5: mirrored twice
        {1000000.125f, 0, 3, 0},  // far away (exactly representable)
    };
    for (const Case& c : cases) {
        SCOPED_TRACE("u = " + std::to_string(c.u));
        glm::vec2 uv(c.u, 0.5f);
        auto at = [&](TextureWrap wrap) {
            return texture.sample(uv, 0.0f, samplerOf(wrap, TextureWrap::Repeat, TextureFilter::Nearest)).x;
        };
        EXPECT_EQ(at(TextureWrap::Repeat), c.repeat);
        EXPECT_EQ(at(TextureWrap::ClampToEdge), c.clamp);
        EXPECT_EQ(at(TextureWrap::MirroredRepeat), c.mirror);
    }
}

TEST(TextureSample, WrapModesUnderBilinearFiltering) {
    // u = -0.25 lies halfway between texels -2 and -1, u = 1.25 between texels 4 and 5.
    Texture texture = indexTexture(4, 1);
    auto at = [&](float u, TextureWrap wrap) {
        return texture.sample({u, 0.5f}, 0.0f, samplerOf(wrap, TextureWrap::Repeat, TextureFilter::Linear)).x;
    };
    EXPECT_FLOAT_EQ(at(-0.25f, TextureWrap::Repeat), 2.5f);          // texels 2 and 3
    EXPECT_FLOAT_EQ(at(-0.25f, TextureWrap::ClampToEdge), 0.0f);     // texel 0 twice
    EXPECT_FLOAT_EQ(at(-0.25f, TextureWrap::MirroredRepeat), 0.5f);  // texels 1 and 0
    EXPECT_FLOAT_EQ(at(1.25f, TextureWrap::Repeat), 0.5f);           // texels 0 and 1
    EXPECT_FLOAT_EQ(at(1.25f, TextureWrap::ClampToEdge), 3.0f);      // texel 3 twice
    EXPECT_FLOAT_EQ(at(1.25f, TextureWrap::MirroredRepeat), 2.5f);   // texels 3 and 2
    // The left edge: Repeat blends the last texel and the first, ClampToEdge keeps the first.
    EXPECT_FLOAT_EQ(at(0.0f, TextureWrap::Repeat), 1.5f);
    EXPECT_FLOAT_EQ(at(0.0f, TextureWrap::ClampToEdge), 0.0f);
    EXPECT_FLOAT_EQ(at(0.0f, TextureWrap::MirroredRepeat), 0.0f);
}

TEST(TextureSample, WrapSAndWrapTAreIndependent) {
    Texture texture = indexTexture(4, 4);
    TextureSampler sampler =
        samplerOf(TextureWrap::Repeat, TextureWrap::MirroredRepeat, TextureFilter::Nearest);
    // u: texel 4 -> 0 (Repeat); v: texel -2 -> 1 (mirrored).
    glm::vec4 texel = texture.sample({1.125f, -0.375f}, 0.0f, sampler);
    EXPECT_EQ(texel.x, 0.0f);
    EXPECT_EQ(texel.y, 1.0f);
    sampler = samplerOf(TextureWrap::ClampToEdge, TextureWrap::Repeat, TextureFilter::Nearest);
    texel = texture.sample({1.125f, -0.375f}, 0.0f, sampler);
    EXPECT_EQ(texel.x, 3.0f);
    EXPECT_EQ(texel.y, 2.0f);
}

TEST(TextureSample, BilinearIsExactAtTexelCentresAndAveragesHalfway) {
    // 4 x 2 texels: every centre ((x + 0.5) / 4, (y + 0.5) / 2) is exact in float.
    std::vector<glm::vec4> texels = {{0.1f, 0.7f, 0.3f, 1.0f},   {0.9f, 0.2f, 0.5f, 0.5f},
                                     {0.4f, 0.4f, 0.8f, 0.0f},   {0.3f, 0.6f, 0.1f, 0.25f},
                                     {0.75f, 0.05f, 0.6f, 0.5f}, {0.2f, 0.9f, 0.35f, 1.0f},
                                     {0.0f, 1.0f, 0.5f, 0.75f},  {0.6f, 0.3f, 0.45f, 0.5f}};
    Texture texture(4, 2, texels, "bilinear");
    auto at = [&](int x, int y) { return texels[y * 4 + x]; };
    for (TextureWrap wrap : {TextureWrap::Repeat, TextureWrap::ClampToEdge, TextureWrap::MirroredRepeat})
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 4; ++x)
                expectEqual(texture.sample({(x + 0.5f) / 4.0f, (y + 0.5f) / 2.0f}, 0.0f,
                                           samplerOf(wrap, wrap, TextureFilter::Linear)),
                            at(x, y), "centre");
    // Halfway between horizontal neighbours, vertical neighbours, and the point between four.
    expectNear(texture.sample({0.25f, 0.25f}, 0.0f), (at(0, 0) + at(1, 0)) * 0.5f, 1e-6f, "horizontal");
    expectNear(texture.sample({3.5f / 4.0f, 0.5f}, 0.0f), (at(3, 0) + at(3, 1)) * 0.5f, 1e-6f, "vertical");
    expectNear(texture.sample({0.5f, 0.5f}, 0.0f), (at(1, 0) + at(2, 0) + at(1, 1) + at(2, 1)) * 0.25f, 1e-6f,
               "four");
    // A quarter of the way: weights 3/4 and 1/4.
    expectNear(texture.sample({0.75f / 4.0f, 0.25f}, 0.0f), at(0, 0) * 0.75f + at(1, 0) * 0.25f, 1e-6f,
               "quarter");
}

Texture checker() {
    glm::vec4 black(0, 0, 0, 1), white(1, 1, 1, 1);
    return Texture(2, 2, {black, white, white, black}, "checker");
}

TEST(TextureSample, MipLevelFollowsTheFootprint) {
    Texture texture = checker();
    ASSERT_EQ(texture.levels(), 2);
    expectEqual(texture.average(), glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
    glm::vec2 blackCentre(0.25f, 0.25f), whiteCentre(0.75f, 0.25f);
    // One texel (0.5 of the image): the finest level, the texel itself.
    expectEqual(texture.sample(blackCentre, 0.5f), glm::vec4(0, 0, 0, 1), "one texel");
    expectEqual(texture.sample(whiteCentre, 0.5f), glm::vec4(1, 1, 1, 1), "one texel");
    expectEqual(texture.sample(whiteCentre, 0.0f), glm::vec4(1, 1, 1, 1), "no footprint");
    // The whole image and more: the 1x1 level, grey.
    for (float footprint : {1.0f, 4.0f, 1e6f, kInf})
        expectNear(texture.sample(whiteCentre, footprint), glm::vec4(0.5f, 0.5f, 0.5f, 1.0f), 1e-6f,
                   "footprint " + std::to_string(footprint));
    // In between: trilinear, lod = log2(0.75 * 2).
    float blend = std::log2(1.5f);
    expectNear(texture.sample(whiteCentre, 0.75f), glm::vec4(glm::vec3(1.0f - 0.5f * blend), 1.0f), 1e-6f,
               "trilinear");
}

TEST(TextureSample, NearestFiltersAndNoMipmaps) {
    Texture texture = checker();
    TextureSampler nearest = samplerOf(TextureWrap::Repeat, TextureWrap::Repeat, TextureFilter::Nearest);
    // Magnification off the centre: the texel, not a blend.
    expectEqual(texture.sample({0.45f, 0.05f}, 0.1f, nearest), glm::vec4(0, 0, 0, 1), "magnified");
    expectEqual(texture.sample({0.55f, 0.05f}, 0.1f, nearest), glm::vec4(1, 1, 1, 1), "magnified");
    // NEAREST_MIPMAP_NEAREST: lod 0.4 rounds to level 0, lod 0.7 to level 1.
    expectEqual(texture.sample({0.55f, 0.05f}, std::exp2(0.4f) / 2.0f, nearest), glm::vec4(1, 1, 1, 1),
                "lod 0.4");
    expectNear(texture.sample({0.55f, 0.05f}, std::exp2(0.7f) / 2.0f, nearest),
               glm::vec4(0.5f, 0.5f, 0.5f, 1), 1e-6f, "lod 0.7");
    // Without mipmaps minification reads level 0: bilinear at a centre gives the texel, Nearest the texel.
    TextureSampler flat;
    flat.mipmaps = false;
    expectEqual(texture.sample({0.75f, 0.25f}, 4.0f, flat), glm::vec4(1, 1, 1, 1), "linear, no mipmaps");
    nearest.mipmaps = false;
    expectEqual(texture.sample({0.55f, 0.05f}, 4.0f, nearest), glm::vec4(1, 1, 1, 1), "nearest, no mipmaps");
    // A Nearest magFilter with a Linear minFilter: minification still blends.
    TextureSampler mixed;
    mixed.magFilter = TextureFilter::Nearest;
    expectNear(texture.sample({0.75f, 0.25f}, 4.0f, mixed), glm::vec4(0.5f, 0.5f, 0.5f, 1), 1e-6f, "mixed");
}

TEST(TextureSample, NonFiniteCoordinatesGiveTheAverage) {
    Texture texture = indexTexture(3, 2);
    for (glm::vec2 uv :
         {glm::vec2(kNaN, 0.5f), glm::vec2(0.5f, kNaN), glm::vec2(kInf, 0.5f), glm::vec2(0.5f, -kInf)})
        expectEqual(texture.sample(uv, 0.0f), texture.average());
    // A NaN footprint counts as none: the finest level.
    expectEqual(texture.sample({0.5f, 0.25f}, kNaN), glm::vec4(1, 0, 1, 1));
    // Huge coordinates stay finite under every wrap mode.
    for (TextureWrap wrap : {TextureWrap::Repeat, TextureWrap::ClampToEdge, TextureWrap::MirroredRepeat}) {
        glm::vec4 v = texture.sample({1e30f, -3e38f}, 0.01f, samplerOf(wrap, wrap, TextureFilter::Linear));
        for (int c = 0; c < 4; ++c) EXPECT_TRUE(std::isfinite(v[c]));
    }
}

// The mean of a level, in double.
glm::dvec4 levelMean(const Texture& texture, int level, int width, int height) {
    glm::dvec4 sum(0.0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) sum += glm::dvec4(texture.texel(level, x, y));
    return sum / static_cast<double>(width * height);
}

TEST(TextureMips, EveryLevelKeepsTheMeanForAnySize) {
    const std::pair<int, int> sizes[] = {{5, 3}, {7, 1}, {1, 9}, {3, 3}, {6, 5}, {17, 11}, {16, 16}, {2, 7}};
    for (auto [width, height] : sizes) {
        SCOPED_TRACE(std::to_string(width) + "x" + std::to_string(height));
        std::vector<glm::vec4> texels;
        for (int i = 0; i < width * height; ++i)
            texels.emplace_back(std::sin(i * 1.7f) + 1.0f, (i * 7919 % 101) / 100.0f, i % 3,
                                i % 2 ? 1.0f : 0.0f);
        Texture texture(width, height, texels, "mips");
        glm::dvec4 mean = levelMean(texture, 0, width, height);
        // Sizes halve, rounding down, never below 1, down to 1x1.
        int levels = 1, w = width, h = height;
        for (; w > 1 || h > 1; ++levels) {
            w = std::max(1, w / 2);
            h = std::max(1, h / 2);
            glm::dvec4 levelAverage = levelMean(texture, levels, w, h);
            for (int c = 0; c < 4; ++c) EXPECT_NEAR(levelAverage[c], mean[c], 1e-5) << "level " << levels;
        }
        EXPECT_EQ(texture.levels(), levels);
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(texture.average()[c], mean[c], 1e-6) << "channel " << c;
    }
}

TEST(TextureMips, OddSizesWeighTheirTexels) {
    // 3 -> 1 averages all three equally; 5 -> 2 gives each half 2.5 texels: (1 + 2 + 0.5 * 4) / 2.5 for the
    // left and (0.5 * 4 + 8 + 16) / 2.5 for the right.
    Texture three(3, 1, {glm::vec4(0.0f), glm::vec4(3.0f), glm::vec4(6.0f)}, "three");
    EXPECT_FLOAT_EQ(three.texel(1, 0, 0).x, 3.0f);
    Texture five(5, 1, {glm::vec4(1), glm::vec4(2), glm::vec4(4), glm::vec4(8), glm::vec4(16)}, "five");
    EXPECT_FLOAT_EQ(five.texel(1, 0, 0).x, 5.0f / 2.5f);
    EXPECT_FLOAT_EQ(five.texel(1, 1, 0).x, 26.0f / 2.5f);
    EXPECT_FLOAT_EQ(five.average().x, 31.0f / 5.0f);
}

// 8-bit texels are kept as 8 bits: level 0 gives the same floats as decoding them (sRGB for colour, alpha
// linear), the smaller levels are the float texture's levels to within half an 8-bit step of their encoding.
TEST(TextureEightBit, LevelZeroIsExactAndMipsWithinHalfAStep) {
    constexpr int kWidth = 6, kHeight = 5;
    std::vector<uint8_t> bytes(kWidth * kHeight * 4);
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<uint8_t>((i * 7919 + 13) % 256);
    for (TextureEncoding encoding : {TextureEncoding::Srgb, TextureEncoding::Linear}) {
        const bool srgb = encoding == TextureEncoding::Srgb;
        SCOPED_TRACE(srgb ? "srgb" : "linear");
        const Texture eight(kWidth, kHeight, bytes, encoding, "eight");
        EXPECT_TRUE(eight.eightBit());
        std::vector<glm::vec4> decoded;
        for (size_t p = 0; p < bytes.size(); p += 4) {
            auto colour = [&](uint8_t b) {
                return srgb ? static_cast<float>(decodeSrgb(b / 255.0)) : static_cast<float>(b) / 255.0f;
            };
            decoded.emplace_back(colour(bytes[p]), colour(bytes[p + 1]), colour(bytes[p + 2]),
                                 static_cast<float>(bytes[p + 3]) / 255.0f);
        }
        const Texture floats(kWidth, kHeight, decoded, "floats");
        EXPECT_FALSE(floats.eightBit());
        ASSERT_EQ(eight.levels(), floats.levels());
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                expectNear(eight.texel(0, x, y), decoded[y * kWidth + x], 1e-6f, "level 0");
        // The mips: 8-bit codes of the float levels (each level filtered from the 8-bit one above, so the
        // steps can add up over levels: within one and a half steps of the encoding).
        for (int level = 1; level < eight.levels(); ++level) {
            const int w = std::max(1, kWidth >> level), h = std::max(1, kHeight >> level);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const glm::vec4 a = eight.texel(level, x, y), b = floats.texel(level, x, y);
                    for (int c = 0; c < 4; ++c) {
                        auto encode = [&](float v) { return c < 3 && srgb ? encodeSrgb(v) : v; };
                        EXPECT_NEAR(encode(a[c]), encode(b[c]), 1.5 / 255.0)
                            << "level " << level << " (" << x << ", " << y << ") channel " << c;
                    }
                }
        }
        // Lookups read the same texels: a bilinear lookup at level 0 at a texel centre and between four
        // texels (8-bit linear texels are blended as codes and divided by 255 after the blend).
        const glm::vec2 centre((1.0f + 0.5f) / kWidth, (2.0f + 0.5f) / kHeight);
        expectNear(eight.sample(centre, 0.0f), floats.sample(centre, 0.0f), 1e-6f, "at a texel centre");
        const glm::vec2 between((1.0f + 0.8f) / kWidth, (2.0f + 0.3f) / kHeight);
        expectNear(eight.sample(between, 0.0f), floats.sample(between, 0.0f), 1e-6f, "bilinear lookup");
    }
}

TEST_F(TextureFileTest, EightBitFilesAreKeptAsEightBits) {
    fs::path file = dir_ / "colour.png";
    writeImage(file, 2, 1, 4, kRgba8);
    EXPECT_TRUE(Texture::load(file, TextureEncoding::Srgb, "")->eightBit());
    fs::path deep = dir_ / "deep.png";
    writeImage(deep, 1, 1, 3, std::vector<uint16_t>{0, 32768, 65535});
    EXPECT_FALSE(Texture::load(deep, TextureEncoding::Srgb, "")->eightBit());
}

// A palette PNG with transparency (tRNS) is an 8-bit RGBA texture: the entries' colours and alphas.
TEST_F(TextureFileTest, PalettePngWithTransparencyKeepsItsAlpha) {
    const uint8_t palette[] = {255, 0, 0, 0, 0, 255};
    const uint8_t alphas[] = {51};
    const uint8_t indices[] = {0, 1};
    test::writePngPalette(dir_ / "palette.png", indices, 2, 1, palette, alphas);
    const auto texture = Texture::load(dir_ / "palette.png", TextureEncoding::Linear, "");
    EXPECT_TRUE(texture->eightBit());
    expectEqual(texture->texel(0, 0, 0), glm::vec4(1.0f, 0.0f, 0.0f, 51 / 255.0f));
    expectEqual(texture->texel(0, 1, 0), glm::vec4(0.0f, 0.0f, 1.0f, 1.0f));
}

TEST(TextureErrors, EightBitConstructorRejectsBadSizes) {
    expectContains(
        inputErrorOf([] { Texture(2, 2, std::vector<uint8_t>(15), TextureEncoding::Srgb, "a.png"); }),
        {"a.png", "16 bytes", "got 15"});
    expectContains(
        inputErrorOf([] { Texture(0, 2, std::vector<uint8_t>{}, TextureEncoding::Linear, "b.png"); }),
        {"b.png", "0x2"});
}

TEST(TextureErrors, ConstructorRejectsBadSizesAndTexels) {
    auto make = [](int width, int height, std::vector<glm::vec4> texels) {
        return [=] { Texture(width, height, texels, "textures/wood.png"); };
    };
    expectContains(inputErrorOf(make(0, 4, {})), {"textures/wood.png", "0x4"});
    expectContains(inputErrorOf(make(-2, 1, {})), {"textures/wood.png", "-2x1"});
    expectContains(inputErrorOf(make(20000, 1, std::vector<glm::vec4>(20000))),
                   {"textures/wood.png", "16384"});
    expectContains(inputErrorOf(make(2, 2, std::vector<glm::vec4>(3))),
                   {"textures/wood.png", "4 texels, got 3"});
    std::vector<glm::vec4> texels(4, glm::vec4(0.5f));
    texels[3].y = kNaN;
    expectContains(inputErrorOf(make(2, 2, texels)), {"textures/wood.png", "(1, 1)", "not finite"});
    texels[3] = glm::vec4(-kInf);
    expectContains(inputErrorOf(make(2, 2, texels)), {"textures/wood.png", "not finite"});
}

TEST_F(TextureFileTest, BadFilesNameTheFile) {
    fs::path missing = dir_ / "missing.png", empty = dir_ / "empty.png", garbage = dir_ / "garbage.png";
    writeBytes(empty, {});
    std::vector<std::byte> noise;
    for (int i = 0; i < 300; ++i) noise.push_back(static_cast<std::byte>(i * 97 % 251));
    writeBytes(garbage, noise);
    expectContains(inputErrorOf([&] { Texture::load(missing, TextureEncoding::Srgb, ""); }),
                   {missing.string(), "no such file"});
    expectContains(inputErrorOf([&] { Texture::load(empty, TextureEncoding::Srgb, ""); }),
                   {empty.string(), "empty"});
    expectContains(inputErrorOf([&] { Texture::load(garbage, TextureEncoding::Srgb, ""); }),
                   garbage.string());
    expectContains(inputErrorOf([&] { Texture::load(dir_, TextureEncoding::Srgb, ""); }), dir_.string());
    // `where` comes first; the file is still named.
    try {
        Texture::load(missing, TextureEncoding::Srgb, "scene.gltf: images[2]");
        ADD_FAILURE() << "no InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(e.where(), "scene.gltf: images[2]");
        expectContains(e.message(), missing.string());
    }
}

TEST_F(TextureFileTest, TruncatedImagesAreErrors) {
    std::vector<uint8_t> pixels(64 * 64 * 3);
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>(i * 31 % 256);
    fs::path png = dir_ / "whole.png", cut = dir_ / "cut.png";
    writeImage(png, 64, 64, 3, pixels);
    std::vector<std::byte> bytes = readBytes(png);
    bytes.resize(bytes.size() / 2);
    writeBytes(cut, bytes);
    expectContains(inputErrorOf([&] { Texture::load(cut, TextureEncoding::Srgb, ""); }), cut.string());
    expectContains(inputErrorOf([&] { Texture::decode(bytes, "image/png", TextureEncoding::Srgb, ""); }),
                   "embedded texture");
}

TEST(TextureErrors, BadEmbeddedImagesNameTheTexture) {
    std::vector<std::byte> noise;
    for (int i = 0; i < 300; ++i) noise.push_back(static_cast<std::byte>(i * 97 % 251));
    expectContains(inputErrorOf([&] { Texture::decode({}, "png", TextureEncoding::Srgb, ""); }),
                   {"embedded texture", "no image data"});
    expectContains(inputErrorOf([&] { Texture::decode(noise, "", TextureEncoding::Srgb, ""); }),
                   "embedded texture");
    expectContains(inputErrorOf([&] { Texture::decode(noise, "image/ktx2", TextureEncoding::Srgb, ""); }),
                   {"embedded texture", "image/ktx2"});
    expectContains(
        inputErrorOf([&] { Texture::decode(noise, "image/png", TextureEncoding::Srgb, "a.glb: images[1]"); }),
        {"a.glb: images[1]", "embedded texture"});
    // A PNG signature followed by noise.
    std::vector<std::byte> fakePng = {std::byte{0x89}, std::byte{'P'},  std::byte{'N'},  std::byte{'G'},
                                      std::byte{'\r'}, std::byte{'\n'}, std::byte{0x1a}, std::byte{'\n'}};
    fakePng.insert(fakePng.end(), noise.begin(), noise.end());
    expectContains(inputErrorOf([&] { Texture::decode(fakePng, "", TextureEncoding::Srgb, ""); }),
                   "embedded texture");
}

// The CRC-32 of PNG chunks (ISO 3309, as the PNG specification's annex D), bit by bit.
uint32_t crc32(const std::vector<uint8_t>& bytes, size_t begin, size_t end) {
    uint32_t crc = 0xffffffffu;
    for (size_t i = begin; i < end; ++i) {
        crc ^= bytes[i];
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return crc ^ 0xffffffffu;
}

void appendBigEndian(std::vector<uint8_t>& bytes, uint32_t value) {
    for (int shift = 24; shift >= 0; shift -= 8) bytes.push_back(static_cast<uint8_t>(value >> shift));
}

TEST(TextureErrors, AbsurdSizesAreRefusedBeforeReading) {
    // A valid PNG signature and header chunk (IHDR) claiming 100000 x 100000 RGBA texels, and nothing more.
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    appendBigEndian(png, 13);
    size_t chunk = png.size();
    for (char c : std::string("IHDR")) png.push_back(static_cast<uint8_t>(c));
    appendBigEndian(png, 100000);
    appendBigEndian(png, 100000);
    for (uint8_t b : {8, 6, 0, 0, 0}) png.push_back(b);  // 8 bits, RGBA, deflate, no filter, no interlace
    appendBigEndian(png, crc32(png, chunk, png.size()));
    // An empty data chunk: libpng reads the header up to here.
    appendBigEndian(png, 0);
    chunk = png.size();
    for (char c : std::string("IDAT")) png.push_back(static_cast<uint8_t>(c));
    appendBigEndian(png, crc32(png, chunk, png.size()));
    std::vector<std::byte> bytes(png.size());
    for (size_t i = 0; i < png.size(); ++i) bytes[i] = static_cast<std::byte>(png[i]);
    expectContains(inputErrorOf([&] { Texture::decode(bytes, "", TextureEncoding::Srgb, ""); }),
                   {"embedded texture", "100000x100000", "16384"});
}

}  // namespace

// A material's maps of one size are read through one Lookup (Texture::locate, then read for each): reading
// another texture of the same size through it gives exactly that texture's own lookup, for every filter,
// wrap mode and footprint, 8-bit and float.
TEST(Texture, ALookupOfOneTextureReadsAnotherOfTheSameSize) {
    constexpr int kWidth = 12, kHeight = 6;
    std::vector<uint8_t> bytes(kWidth * kHeight * 4);
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<uint8_t>((i * 131 + 7) % 256);
    std::vector<glm::vec4> values(kWidth * kHeight);
    for (size_t i = 0; i < values.size(); ++i) values[i] = glm::vec4(0.01f * i, 1.0f, 0.5f, 0.25f);
    const Texture located(kWidth, kHeight, bytes, TextureEncoding::Srgb, "located");
    const Texture others[] = {Texture(kWidth, kHeight, bytes, TextureEncoding::Linear, "linear"),
                              Texture(kWidth, kHeight, values, "floats")};
    for (TextureFilter filter : {TextureFilter::Linear, TextureFilter::Nearest})
        for (TextureWrap wrap : {TextureWrap::Repeat, TextureWrap::ClampToEdge, TextureWrap::MirroredRepeat})
            for (float footprint : {0.0f, 0.5f / kWidth, 2.5f / kWidth, 100.0f})
                for (glm::vec2 uv :
                     {glm::vec2(0.37f, 0.81f), glm::vec2(-0.02f, 1.3f), glm::vec2(0.999f, 0.0f)}) {
                    TextureSampler sampler;
                    sampler.minFilter = sampler.magFilter = filter;
                    sampler.wrapS = sampler.wrapT = wrap;
                    const Texture::Lookup lookup = located.locate(uv, footprint, sampler);
                    for (const Texture& other : others) {
                        const glm::vec4 shared = other.read(lookup),
                                        own = other.sample(uv, footprint, sampler);
                        for (int c = 0; c < 4; ++c)
                            EXPECT_EQ(shared[c], own[c]) << other.name() << " channel " << c;
                    }
                }
}

// locate() into a Lookup that an earlier lookup filled (as a material's lookups reuse one): every lookup
// reads what a fresh one does, whatever the one before was (trilinear, nearest, one level, a non-finite uv).
TEST(Texture, ALookupFilledAgainReadsAsAFreshOne) {
    constexpr int kWidth = 16, kHeight = 8;
    std::vector<uint8_t> bytes(kWidth * kHeight * 4);
    for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<uint8_t>((i * 97 + 3) % 256);
    const Texture texture(kWidth, kHeight, bytes, TextureEncoding::Srgb, "reused");
    struct Case {
        glm::vec2 uv;
        float footprint;
        TextureFilter filter;
    };
    std::vector<Case> cases;
    for (TextureFilter filter : {TextureFilter::Linear, TextureFilter::Nearest})
        for (float footprint : {0.0f, 1.5f / kWidth, 3.0f / kWidth, 100.0f})
            for (glm::vec2 uv : {glm::vec2(0.31f, 0.62f), glm::vec2(NAN, 0.5f), glm::vec2(0.9f, 0.05f)})
                cases.push_back({uv, footprint, filter});
    Texture::Lookup reused;
    int trilinear = 0;
    for (int pass = 0; pass < 2; ++pass)  // forwards, then backwards: each case after others
        for (size_t k = 0; k < cases.size(); ++k) {
            const Case& c = cases[pass == 0 ? k : cases.size() - 1 - k];
            TextureSampler sampler;
            sampler.minFilter = sampler.magFilter = c.filter;
            texture.locate(c.uv, c.footprint, sampler, reused);
            trilinear += reused.levels == 2 ? 1 : 0;
            const glm::vec4 read = texture.read(reused), fresh = texture.sample(c.uv, c.footprint, sampler);
            for (int channel = 0; channel < 4; ++channel)
                EXPECT_EQ(read[channel], fresh[channel]) << "case " << k << " pass " << pass;
        }
    EXPECT_GT(trilinear, 0);  // the cases include two-level lookups, whose fields the others must reset
}

}  // namespace deltagi
