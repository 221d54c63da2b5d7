// Textures of materials: 2D images with their mip chain, and the sampler state glTF 2.0 gives them
// (wrap modes and filters). Texels of 8-bit files are kept as 8 bits and decoded at lookup (sRGB for colour:
// base colour, emissive; linear for data: metallic-roughness, normals, occlusion); those of other files as
// linear RGBA floats (16-bit colour sRGB-decoded when read).
// Texture coordinates follow glTF: (0, 0) is the image's top-left corner, u to the right, v down.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "deltagi/export.h"

DELTAGI_API_BEGIN
namespace deltagi {

enum class TextureWrap { Repeat, ClampToEdge, MirroredRepeat };
enum class TextureFilter { Nearest, Linear };
// How a file's integer texels become linear values: Srgb for colour (base colour, emissive, OBJ map_Kd),
// Linear for data (metallic-roughness, normal, occlusion maps). Float files are always linear.
enum class TextureEncoding { Linear, Srgb };

// glTF's sampler: wrapS/wrapT, magFilter, minFilter (a minFilter with MIPMAP uses the mip chain).
struct TextureSampler {
    TextureWrap wrapS = TextureWrap::Repeat;
    TextureWrap wrapT = TextureWrap::Repeat;
    TextureFilter magFilter = TextureFilter::Linear;
    TextureFilter minFilter = TextureFilter::Linear;
    bool mipmaps = true;  // minification selects (and blends) mip levels by the lookup's footprint
    bool operator==(const TextureSampler&) const = default;
};

// An immutable image with its mip chain (box-filtered halvings down to 1x1, any size: odd sizes round
// down, never below 1). Shared by the materials that use it.
class Texture {
  public:
    // `texels`: width * height linear RGBA values, row 0 at the top (v = 0). Throws InputError(name, ...)
    // for a zero or negative size, a texel count that does not match, or a non-finite texel.
    Texture(int width, int height, std::vector<glm::vec4> texels, std::string name);
    // 8-bit texels as an image file holds them: width * height * 4 bytes, RGBA, row 0 at the top; `encoding`
    // says how RGB become linear values (alpha is always linear). Kept as 8 bits, as graphics hardware keeps
    // an RGBA8 or SRGB8_ALPHA8 texture: a quarter of the memory of linear floats, and lookups that read a
    // quarter of the bytes. Level 0 gives exactly the values of a decoding to floats; the smaller levels are
    // box-filtered in linear values and stored as 8 bits again (rounded to the nearest code). Throws as the
    // constructor above for a bad size or a byte count that does not match.
    Texture(int width, int height, std::vector<uint8_t> rgba8, TextureEncoding encoding, std::string name);

    // Reads an image file: PNG (8 or 16 bit), JPEG, OpenEXR or Radiance HDR, by its extension. Grey files
    // repeat their channel to RGB, files without alpha get alpha 1. Throws InputError(where, ...) naming the
    // file when it is missing, unreadable, of zero size or of another format.
    static std::shared_ptr<const Texture> load(const std::filesystem::path& file, TextureEncoding encoding,
                                               const std::string& where);
    // The same for an image held in memory (a texture embedded in a GLB file): `formatHint` is the file
    // extension or MIME type the container gives ("png", "image/jpeg"), may be empty; the bytes' signature
    // wins over it.
    static std::shared_ptr<const Texture> decode(std::span<const std::byte> encoded,
                                                 std::string_view formatHint, TextureEncoding encoding,
                                                 const std::string& where);

    int width() const { return width_; }
    int height() const { return height_; }
    int levels() const { return static_cast<int>(levels_.size()); }
    const std::string& name() const { return name_; }

    // Filtered lookup at `uv`. `footprint`: the size of the area looked up, in uv units (1 = the whole
    // image's width); 0 or less: the finest level. Magnification (footprint at most one texel) uses
    // magFilter; minification selects the mip level of the footprint and, with a Linear minFilter, blends
    // bilinear lookups of the two nearest levels (trilinear). Wrap modes as the sampler says; a non-finite
    // uv gives the mean texel (average()).
    glm::vec4 sample(glm::vec2 uv, float footprint, const TextureSampler& sampler = {}) const;
    // sample() in two halves, for the lookups of several textures at one point (a material's maps): where
    // the texels lie and how they blend, the same for every texture of this size at that uv with that
    // footprint and sampler; then the blend of a texture's texels there. read() takes a Lookup of this
    // texture or of one of the same width and height (sameSize()); sample() is read(locate()).
    struct Lookup {
        bool average = false;  // a non-finite uv: the mean texel
        bool bilinear = true;  // else the nearest texel, index[slot][0]
        int levels = 1;        // 2: trilinear, the second level weighing levelBlend
        float levelBlend = 0.0f;
        std::array<int, 2> level{};
        std::array<std::array<size_t, 4>, 2> index{};  // per level: top left, top right, bottom left, right
        std::array<float, 2> fx{}, fy{};               // per level: the bilinear weights along x and y
    };
    Lookup locate(glm::vec2 uv, float footprint, const TextureSampler& sampler) const;
    // The same into `out` (every field that read() uses is set): no Lookup made and copied per lookup.
    void locate(glm::vec2 uv, float footprint, const TextureSampler& sampler, Lookup& out) const;
    glm::vec4 read(const Lookup& lookup) const;
    bool sameSize(const Texture& other) const { return width_ == other.width_ && height_ == other.height_; }
    // The mean of all texels (the 1x1 level).
    glm::vec4 average() const;
    // The texel (x, y) of mip level `level` (no filtering, no wrapping; x, y in range).
    glm::vec4 texel(int level, int x, int y) const;

    // Whether the texels are kept as 8 bits (the second constructor).
    bool eightBit() const { return eightBit_; }

  private:
    struct Level {
        int width = 0, height = 0;
        std::vector<glm::vec4> texels;  // linear values; empty when eightBit_
        std::vector<uint32_t> packed;   // eightBit_: R | G << 8 | B << 16 | A << 24
    };
    void buildMipChain();
    int width_ = 0, height_ = 0;
    bool eightBit_ = false;
    TextureEncoding encoding_ = TextureEncoding::Linear;
    // eightBit_: the decoding tables of the RGB codes (sRGB or linear) and of alpha, 256 values each.
    const float* rgbValues_ = nullptr;
    const float* alphaValues_ = nullptr;
    std::vector<Level> levels_;
    std::string name_;
};

// A material's use of a texture: which image, how it is sampled, and which of the mesh's texture
// coordinate sets (glTF's texCoord: 0 or 1) it reads.
struct TextureSlot {
    std::shared_ptr<const Texture> texture;  // null: the material has no such texture
    TextureSampler sampler;
    int texCoord = 0;
    explicit operator bool() const { return texture != nullptr; }
    glm::vec4 sample(glm::vec2 uv, float footprint) const { return texture->sample(uv, footprint, sampler); }
};

}  // namespace deltagi
DELTAGI_API_END
