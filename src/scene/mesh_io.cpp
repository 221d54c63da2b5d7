// Loading mesh files with Assimp: one importer set-up for every format.
#include "scene/mesh_io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>
#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/error.h"
#include "io/file_names.h"
#include "io/image_encode.h"
#include "scene/json_reader.h"

namespace deltagi {

namespace {

bool isGltf(const std::filesystem::path& file) {
    const std::string ext = lowerExtension(file);
    return ext == ".gltf" || ext == ".glb";
}

TriangleMesh readTriangles(const aiMesh& source) {
    TriangleMesh mesh;
    mesh.positions.reserve(source.mNumVertices);
    for (unsigned i = 0; i < source.mNumVertices; ++i) {
        const aiVector3D& p = source.mVertices[i];
        mesh.positions.emplace_back(p.x, p.y, p.z);
    }
    if (source.HasNormals()) {
        mesh.normals.reserve(source.mNumVertices);
        for (unsigned i = 0; i < source.mNumVertices; ++i) {
            const aiVector3D& n = source.mNormals[i];
            mesh.normals.emplace_back(n.x, n.y, n.z);
        }
    }
    mesh.triangles.reserve(source.mNumFaces);
    for (unsigned f = 0; f < source.mNumFaces; ++f) {
        const aiFace& face = source.mFaces[f];
        if (face.mNumIndices == 3)
            mesh.triangles.emplace_back(face.mIndices[0], face.mIndices[1], face.mIndices[2]);
    }
    return mesh;
}

// The per-vertex attributes beyond positions and normals.
// Texture coordinates: Assimp gives every format's in OpenGL's convention, v up from the image's bottom (its
// glTF reader flips glTF's v); deltagi keeps glTF's, v down from the top (deltagi/texture.h): v = 1 - v.
// Colours: glTF's COLOR_0 is linear (the glTF spec); every other format's (PLY red/green/blue, which
// Assimp divides by 255, and OBJ's "v x y z r g b") is taken as sRGB-encoded, as the camera colours of
// scans are, and decoded. Alpha is dropped.
// Tangents: Assimp's (glTF's TANGENT, else aiProcess_CalcTangentSpace's from texture coordinate set 0). Its
// bitangent points along increasing OpenGL v, up the image, as a normal map's +y (green) does; w is the
// handedness that gives it back as w * cross(n, t).
void readAttributes(const aiMesh& source, bool linearColours, TriangleMesh& mesh) {
    const unsigned count = source.mNumVertices;
    for (int set = 0; set < 2; ++set) {
        if (!source.HasTextureCoords(set)) continue;
        std::vector<glm::vec2>& uvs = set == 0 ? mesh.uvs : mesh.uvs1;
        uvs.reserve(count);
        for (unsigned i = 0; i < count; ++i) {
            const aiVector3D& uv = source.mTextureCoords[set][i];
            uvs.emplace_back(uv.x, 1.0f - uv.y);
        }
    }
    if (source.HasVertexColors(0)) {
        mesh.colors.reserve(count);
        for (unsigned i = 0; i < count; ++i) {
            const aiColor4D& c = source.mColors[0][i];
            glm::vec3 rgb(c.r, c.g, c.b);
            // Rounding in a file's floats may step just past [0, 1]; cleanMesh() refuses real excursions.
            if (!linearColours)
                for (int k = 0; k < 3; ++k) rgb[k] = srgbToLinearValue(std::clamp(rgb[k], 0.0f, 1.0f));
            mesh.colors.push_back(rgb);
        }
    }
    if (source.HasTangentsAndBitangents() && source.HasNormals() && !mesh.uvs.empty()) {
        mesh.tangents.reserve(count);
        for (unsigned i = 0; i < count; ++i) {
            const aiVector3D &t = source.mTangents[i], &b = source.mBitangents[i], &n = source.mNormals[i];
            const glm::vec3 tangent(t.x, t.y, t.z);
            const float handedness =
                glm::dot(glm::cross(glm::vec3(n.x, n.y, n.z), tangent), glm::vec3(b.x, b.y, b.z));
            // A NaN tangent (Assimp's mark for degenerate texture coordinates) is replaced by cleanMesh().
            mesh.tangents.emplace_back(tangent, handedness < 0.0f ? -1.0f : 1.0f);
        }
    }
}

bool hasPolygons(const aiScene& scene) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        const aiMesh* mesh = scene.mMeshes[m];
        if (mesh == nullptr || mesh->mFaces == nullptr) continue;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f)
            if (mesh->mFaces[f].mNumIndices >= 3) return true;
    }
    return false;
}

// ---- sizes claimed by a file's header ---------------------------------------------------------------------

// What loading one element costs in memory at most, Assimp's copy and ours together: a vertex's position and
// normal in Assimp, its copies through post-processing and in TriangleMesh; a face's indices likewise.
constexpr double kBytesPerVertex = 160.0;
constexpr double kBytesPerFace = 96.0;
// Formats without counts in a header: memory in proportion to the file (OBJ text or glTF binary data).
constexpr double kBytesPerFileByte = 16.0;
constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;

struct PlyProperty {
    uint64_t bytes = 0;        // a scalar's size, or a list's count's
    uint64_t itemBytes = 0;    // a list's items' size; 0: a scalar
    bool signedCount = false;  // a list's count is of a signed type (char, short, int)
};

struct ClaimedElement {
    std::string name;
    uint64_t count = 0;
    uint64_t minBytes = 0;  // the fewest bytes one element takes in the file
    std::vector<PlyProperty> properties;
};

constexpr int kMaxPlyHeaderLines = 10000;

// Where the stream is; past the end when it has reached it.
uint64_t streamPosition(std::istream& in) {
    const std::streamoff position = in.tellg();
    return position < 0 ? UINT64_MAX : static_cast<uint64_t>(position);
}

// The elements a PLY header declares, with the fewest bytes each can take (binary: the sizes of its scalar
// properties and list counts; ASCII: 2 characters per property, a digit and a separator); the header's length
// goes to `headerBytes`. The header must be printable text, begin with "ply" and "format FORMAT 1.0", and
// its "element NAME COUNT", "property TYPE NAME", "property list TYPE TYPE NAME" and "end_header" lines must
// be well formed, else InputError(where, ...): Assimp's PLY reader crashed or spun on malformed headers
// (found by scripts/fuzz.sh).
std::vector<ClaimedElement> plyElements(std::istream& in, uint64_t& headerBytes, const std::string& name,
                                        const std::string& where, std::string& plyFormat) {
    static const std::map<std::string, uint64_t> kTypeBytes = {
        {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
        {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
        {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
    std::vector<ClaimedElement> elements;
    bool binary = false;
    std::string line;
    auto corrupt = [&](int lineNumber, const std::string& expected) {
        std::string shown;
        for (char c : line.substr(0, 60)) shown += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
        return InputError(
            where, fmt::format("'{}' is corrupt: line {} of its PLY header is \"{}\", expected {}", name,
                               lineNumber, shown, expected));
    };
    plyFormat = "ascii";
    for (int number = 1; number <= kMaxPlyHeaderLines && std::getline(in, line); ++number) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (std::any_of(line.begin(), line.end(),
                        [](char c) { return !std::isprint(static_cast<unsigned char>(c)) && c != '\t'; }))
            throw corrupt(number, "printable text");
        std::istringstream words(line);
        std::string word, extra;
        words >> word;
        if (number == 1) {
            if (line != "ply") throw corrupt(number, "\"ply\"");
        } else if (number == 2) {
            std::string format, version;
            if (word != "format" || !(words >> format >> version) || (words >> extra) ||
                (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") ||
                (version != "1.0" && version != "1"))
                throw corrupt(number, "\"format ascii|binary_little_endian|binary_big_endian 1.0\"");
            binary = format != "ascii";
            plyFormat = format;
        } else if (word == "element") {
            ClaimedElement element;
            // A count beyond 64 bits would slip past the size check.
            if (!(words >> element.name >> element.count) || (words >> extra))
                throw corrupt(number, "\"element NAME COUNT\" with a whole number of 64 bits");
            elements.push_back(element);
        } else if (word == "property" && !elements.empty()) {
            std::string type, propertyName;
            words >> type;
            const bool list = type == "list";
            std::string itemType;
            if (list) words >> type >> itemType;  // the count's type, then the items' (the list may be empty)
            auto size = kTypeBytes.find(type);
            const bool integralCount = !type.starts_with("float") && type != "double";
            if (size == kTypeBytes.end() || (list && (!kTypeBytes.contains(itemType) || !integralCount)) ||
                !(words >> propertyName) || (words >> extra))
                throw corrupt(
                    number,
                    "\"property TYPE NAME\" or \"property list TYPE TYPE NAME\" with known types (a "
                    "list's count of an integer type)");
            const bool signedCount = type == "char" || type == "int8" || type == "short" || type == "int16" ||
                                     type == "int" || type == "int32";
            elements.back().minBytes += binary ? size->second : 2;
            elements.back().properties.push_back(
                {size->second, list ? kTypeBytes.at(itemType) : 0, list && signedCount});
        } else if (word == "end_header" && !(words >> extra)) {
            headerBytes = streamPosition(in);
            return elements;
        }
        // Other printable lines are skipped, as Assimp skips them (Blender 2.47 wrote a comment without the
        // "comment" keyword).
    }
    throw InputError(where, fmt::format("'{}' is corrupt: its PLY header has no line \"end_header\" within "
                                        "{} lines",
                                        name, kMaxPlyHeaderLines));
}

// The lists in a binary PLY's data, element by element: a list whose count claims more items than the bytes
// left could hold (a face of 4e9 indices) would have Assimp allocate for it; ASCII lists are bounded by their
// line. Scans at most the elements the file holds.
void checkPlyLists(std::istream& in, const std::vector<ClaimedElement>& elements, const std::string& format,
                   uint64_t dataBytes, const std::string& name, const std::string& where) {
    if (format == "ascii") return;
    const bool big = format == "binary_big_endian";
    uint64_t left = dataBytes;
    auto readCount = [&](uint64_t bytes) -> std::optional<uint64_t> {
        unsigned char b[8] = {};
        if (bytes > left || !in.read(reinterpret_cast<char*>(b), static_cast<std::streamsize>(bytes)))
            return std::nullopt;
        left -= bytes;
        uint64_t v = 0;
        for (uint64_t i = 0; i < bytes; ++i)
            v |= static_cast<uint64_t>(b[big ? bytes - 1 - i : i]) << (8 * i);
        return v;
    };
    for (const ClaimedElement& element : elements) {
        const bool hasList = std::any_of(element.properties.begin(), element.properties.end(),
                                         [](const PlyProperty& p) { return p.itemBytes > 0; });
        if (!hasList) {  // fixed size: skip the whole element at once
            uint64_t size = 0;
            for (const PlyProperty& p : element.properties) size += p.bytes;
            const double total = static_cast<double>(size) * static_cast<double>(element.count);
            if (total > static_cast<double>(left)) return;  // checkMeshFileClaims reports it
            in.seekg(static_cast<std::streamoff>(size * element.count), std::ios::cur);
            left -= size * element.count;
            continue;
        }
        for (uint64_t i = 0; i < element.count; ++i)
            for (const PlyProperty& p : element.properties) {
                const std::optional<uint64_t> value = readCount(p.bytes);
                if (!value) return;  // truncated: checkMeshFileClaims or Assimp reports it
                if (p.itemBytes == 0) continue;
                // A negative count of a signed type: Assimp takes it as 4 billion items.
                if (p.signedCount && (*value >> (8 * p.bytes - 1)) != 0)
                    throw InputError(where,
                                     fmt::format("'{}' is corrupt: {} {} of its data claims a list of a "
                                                 "negative number of items",
                                                 name, element.name, i));
                const double items = static_cast<double>(*value) * static_cast<double>(p.itemBytes);
                if (items > static_cast<double>(left))
                    throw InputError(where,
                                     fmt::format("'{}' is truncated or corrupt: {} {} of its data claims a "
                                                 "list of {} items, more than the {} bytes left hold",
                                                 name, element.name, i, *value, left));
                in.seekg(static_cast<std::streamoff>(*value * p.itemBytes), std::ios::cur);
                left -= *value * p.itemBytes;
            }
    }
}

// OFF: "OFF" (or COFF, NOFF, ...) then "vertices faces edges"; a vertex takes at least "0 0 0\n", a face
// at least "0\n".
std::vector<ClaimedElement> offElements(std::istream& in, uint64_t& headerBytes) {
    std::string line;
    std::getline(in, line);
    std::istringstream first(line);
    std::string magic;
    first >> magic;
    uint64_t vertices = 0, faces = 0;
    if (!(first >> vertices >> faces)) {  // the counts on a line of their own
        do {
            if (!std::getline(in, line)) return {};
        } while (line.empty() || line[0] == '#');
        std::istringstream counts(line);
        if (!(counts >> vertices >> faces)) return {};
    }
    headerBytes = streamPosition(in);
    return {{"vertex", vertices, 6, {}}, {"face", faces, 2, {}}};
}

// ---- Assimp's output --------------------------------------------------------------------------------------

// Assimp's warnings during one import: glTF faces with out-of-range indices are dropped with a warning only.
// Assimp's logger is global: one import at a time (scenes are loaded on one thread).
class WarningLog : public Assimp::LogStream {
  public:
    WarningLog() {
        Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
        Assimp::DefaultLogger::get()->attachStream(this, Assimp::Logger::Warn | Assimp::Logger::Err);
    }
    ~WarningLog() override {
        Assimp::DefaultLogger::get()->detachStream(this, Assimp::Logger::Warn | Assimp::Logger::Err);
        Assimp::DefaultLogger::kill();
    }
    WarningLog(const WarningLog&) = delete;
    WarningLog& operator=(const WarningLog&) = delete;
    void write(const char* message) override { messages.emplace_back(message); }
    std::vector<std::string> messages;
};

// What post-processing relies on, checked on the importer's raw output (Assimp's ValidateDataStructure has
// checked the indices already; this also covers what it does not: finite positions).
// Meshes are named as loadMeshFile() names them.
// Also sets each mesh's primitive types to those its faces have, which Assimp's triangulation relies on (an
// assertion aborts it otherwise).
void validateRawScene(aiScene& scene, const std::filesystem::path& file, const std::string& where,
                      const std::string& baseName) {
    const std::string name = file.filename().string();
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        aiMesh* mesh = scene.mMeshes[m];
        if (mesh == nullptr || (mesh->mNumVertices > 0 && mesh->mVertices == nullptr) ||
            (mesh->mNumFaces > 0 && mesh->mFaces == nullptr))
            throw InputError(where, fmt::format("'{}': mesh {} has no vertex or face data", name, m));
        const std::string meshName =
            scene.mNumMeshes == 1
                ? baseName
                : baseName + "/" + (mesh->mName.length > 0 ? mesh->mName.C_Str() : std::to_string(m));
        for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
            const aiVector3D& p = mesh->mVertices[i];
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
                throw InputError(where,
                                 fmt::format("vertex {} of mesh '{}' is not finite: ({}, {}, {}) ('{}')", i,
                                             meshName, p.x, p.y, p.z, name));
        }
        // Texture coordinates outside [0, 1] are legal (textures repeat); NaN or infinite ones are not.
        for (unsigned set = 0; set < 2; ++set) {
            if (!mesh->HasTextureCoords(set)) continue;
            for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
                const aiVector3D& uv = mesh->mTextureCoords[set][i];
                if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
                    throw InputError(where,
                                     fmt::format("texture coordinate (set {}) of vertex {} of mesh '{}' is "
                                                 "not finite: ({}, {}) ('{}')",
                                                 set, i, meshName, uv.x, 1.0f - uv.y, name));  // glTF's v
            }
        }
        unsigned primitiveTypes = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            primitiveTypes |= face.mNumIndices == 1   ? aiPrimitiveType_POINT
                              : face.mNumIndices == 2 ? aiPrimitiveType_LINE
                              : face.mNumIndices == 3 ? aiPrimitiveType_TRIANGLE
                                                      : aiPrimitiveType_POLYGON;
            // A face of no vertices passes Assimp's validation but aborts its triangulation (fuzz finding).
            if (face.mNumIndices == 0)
                throw InputError(
                    where, fmt::format("'{}': face {} of mesh '{}' has no vertices", name, f, meshName));
            if (face.mIndices == nullptr)
                throw InputError(where,
                                 fmt::format("'{}': face {} of mesh '{}' has no indices", name, f, meshName));
            for (unsigned k = 0; k < face.mNumIndices; ++k)
                if (face.mIndices[k] >= mesh->mNumVertices)
                    throw InputError(
                        where, fmt::format("'{}': face {} of mesh '{}' refers to vertex {}, but the mesh "
                                           "has {} vertices",
                                           name, f, meshName, face.mIndices[k], mesh->mNumVertices));
        }
        mesh->mPrimitiveTypes = primitiveTypes;
    }
}

// Assimp's message without its prefixes, e.g. "Validation failed: aiMesh::mFaces[0]::mIndices[1] is out of
// range".
std::string importError(const Assimp::Importer& importer) {
    std::string error = importer.GetErrorString();
    // Assimp catches its own allocation failures (a count in the data that the header checks cannot see, a
    // PLY face claiming 4e9 indices) and reports the exception's name.
    if (error.find("bad_alloc") != std::string::npos)
        return "it is corrupt or too large: reading it ran out of memory (a count in it beyond its data)";
    return error.empty() ? "unknown error" : error;
}

// The deepest nesting of JSON arrays and objects in `text` (strings skipped).
size_t jsonDepth(std::string_view text) {
    size_t depth = 0, deepest = 0;
    bool inString = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (inString) {
            if (c == '\\')
                ++i;
            else if (c == '"')
                inString = false;
        } else if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            deepest = std::max(deepest, ++depth);
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
    return deepest;
}

// The deepest nesting of XML elements in `text` (comments, declarations and CDATA skipped; roughly: enough to
// bound what a recursive reader would go through).
size_t xmlDepth(std::string_view text) {
    size_t depth = 0, deepest = 0;
    for (size_t i = text.find('<'); i != std::string_view::npos; i = text.find('<', i + 1)) {
        if (text.compare(i, 4, "<!--") == 0) {
            i = text.find("-->", i);
            if (i == std::string_view::npos) break;
        } else if (text.compare(i, 9, "<![CDATA[") == 0) {
            i = text.find("]]>", i);
            if (i == std::string_view::npos) break;
        } else if (i + 1 < text.size() && text[i + 1] == '/') {
            if (depth > 0) --depth;
        } else if (i + 1 < text.size() && text[i + 1] != '?' && text[i + 1] != '!') {
            const size_t close = text.find('>', i);
            if (close == std::string_view::npos) break;
            if (text[close - 1] != '/') deepest = std::max(deepest, ++depth);
        }
    }
    return deepest;
}

// The deepest chain of glTF nodes (children), cycles counted as deep; 0 without nodes.
size_t gltfNodeDepth(const nlohmann::json& document) {
    const auto nodes = document.find("nodes");
    if (nodes == document.end() || !nodes->is_array()) return 0;
    const size_t count = nodes->size();
    std::vector<size_t> depth(count, 0);  // 0: not yet known
    std::vector<int> state(count, 0);     // 0 new, 1 on the path, 2 done
    size_t deepest = 0;
    for (size_t root = 0; root < count; ++root) {
        if (state[root] != 0) continue;
        // Iterative depth-first: (node, next child) pairs.
        std::vector<std::pair<size_t, size_t>> path{{root, 0}};
        state[root] = 1;
        while (!path.empty()) {
            auto& [node, next] = path.back();
            const nlohmann::json& entry = (*nodes)[node];
            const nlohmann::json* children =
                entry.is_object() && entry.contains("children") ? &entry["children"] : nullptr;
            if (children && children->is_array() && next < children->size()) {
                const nlohmann::json& c = (*children)[next++];
                if (!c.is_number_unsigned() || c.get<uint64_t>() >= count) continue;
                const size_t child = c.get<size_t>();
                if (state[child] == 1) return std::numeric_limits<size_t>::max();  // a cycle
                if (state[child] == 0) {
                    state[child] = 1;
                    path.push_back({child, 0});
                }
                continue;
            }
            size_t d = 1;
            if (children && children->is_array())
                for (const nlohmann::json& c : *children)
                    if (c.is_number_unsigned() && c.get<uint64_t>() < count)
                        d = std::max(d, depth[c.get<size_t>()] + 1);
            depth[node] = d;
            state[node] = 2;
            deepest = std::max(deepest, d);
            path.pop_back();
        }
    }
    return deepest;
}

// Each glTF material's KHR_materials_emissive_strength (1 where it gives none, or a value that is not a
// finite number >= 0).
std::vector<float> gltfEmissiveStrengths(const nlohmann::json& document) {
    std::vector<float> strengths;
    const auto materials = document.find("materials");
    if (materials == document.end() || !materials->is_array()) return strengths;
    for (const nlohmann::json& material : *materials) {
        float strength = 1.0f;
        const nlohmann::json* value = nullptr;
        if (material.is_object() && material.contains("extensions") && material["extensions"].is_object() &&
            material["extensions"].contains("KHR_materials_emissive_strength")) {
            const nlohmann::json& extension = material["extensions"]["KHR_materials_emissive_strength"];
            if (extension.is_object() && extension.contains("emissiveStrength"))
                value = &extension["emissiveStrength"];
        }
        if (value && value->is_number()) {
            const double v = value->get<double>();
            if (std::isfinite(v) && v >= 0.0 && v <= 1e20) strength = static_cast<float>(v);
        }
        strengths.push_back(strength);
    }
    return strengths;
}

}  // namespace

std::optional<nlohmann::json> checkMeshFileStructure(const std::filesystem::path& file,
                                                     const std::string& where) {
    const std::string name = file.filename().string();
    const std::string extension = lowerExtension(file);
    const bool gltf = extension == ".gltf", glb = extension == ".glb",
               xml = extension == ".dae" || extension == ".xml";
    if (!gltf && !glb && !xml) return std::nullopt;
    std::ifstream in(file, std::ios::binary);
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    if (glb) {  // the JSON chunk: 12 bytes of header, its length and type, then the JSON
        if (text.size() < 20) return std::nullopt;  // Assimp reports it
        uint32_t length = 0;
        std::memcpy(&length, text.data() + 12, 4);
        text = text.substr(20, std::min<size_t>(length, text.size() - 20));
    }
    const size_t depth = xml ? xmlDepth(text) : jsonDepth(text);
    if (depth > kMaxFileNesting)
        throw InputError(where, fmt::format("'{}' nests {} levels deep, more than the {} this program reads",
                                            name, depth, kMaxFileNesting));
    if (xml) return std::nullopt;
    nlohmann::json document = nlohmann::json::parse(text, nullptr, false);
    if (document.is_discarded() || !document.is_object()) return std::nullopt;  // Assimp reports it
    const size_t nodes = gltfNodeDepth(document);
    if (nodes > kMaxFileNesting)
        throw InputError(where,
                         nodes == std::numeric_limits<size_t>::max()
                             ? fmt::format("'{}': its nodes are their own children (a cycle)", name)
                             : fmt::format("'{}': its nodes nest {} levels deep, more than the {} this "
                                           "program reads",
                                           name, nodes, kMaxFileNesting));
    // Files a glTF names (buffers, images): regular files only, or reading one (a FIFO) would wait forever.
    for (const char* kind : {"buffers", "images"}) {
        const auto list = document.find(kind);
        if (list == document.end() || !list->is_array()) continue;
        for (const nlohmann::json& entry : *list) {
            if (!entry.is_object() || !entry.contains("uri") || !entry["uri"].is_string()) continue;
            const std::string uri = entry["uri"].get<std::string>();
            if (uri.starts_with("data:")) continue;
            std::error_code error;
            const std::filesystem::file_status status =
                std::filesystem::status(file.parent_path() / uri, error);
            if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
                throw InputError(where,
                                 fmt::format("'{}': {} '{}' is not a regular file (a folder, a FIFO, a "
                                             "device)",
                                             name, std::string(kind) == "buffers" ? "buffer" : "image", uri));
        }
    }
    return document;
}

void checkMeshFileClaims(const std::filesystem::path& file, const std::string& where, uint64_t memoryBytes) {
    std::error_code error;
    const uint64_t fileBytes = std::filesystem::file_size(file, error);
    if (error) return;  // Assimp reports the unreadable file
    std::ifstream in(file, std::ios::binary);
    char magic[4] = {};
    in.read(magic, 4);
    in.seekg(0);
    std::vector<ClaimedElement> elements;
    uint64_t headerBytes = 0;
    const std::string extension = lowerExtension(file);
    // Assimp picks its PLY reader by the extension or by these 3 bytes.
    if (extension == ".ply" || std::string(magic, 3) == "ply") {
        std::string plyFormat;
        elements = plyElements(in, headerBytes, file.filename().string(), where, plyFormat);
        checkPlyLists(in, elements, plyFormat, fileBytes - std::min(fileBytes, headerBytes),
                      file.filename().string(), where);
    } else if (std::string(magic, 3) == "OFF" || std::string(magic + 1, 3) == "OFF" ||
               std::string(magic, 4) == "STOF")
        elements = offElements(in, headerBytes);

    double neededMemory = 0.0, neededBytes = 0.0;
    std::string claims;
    for (const ClaimedElement& element : elements) {
        neededBytes += static_cast<double>(element.count) * static_cast<double>(element.minBytes);
        neededMemory +=
            static_cast<double>(element.count) * (element.name == "vertex" ? kBytesPerVertex : kBytesPerFace);
        claims += fmt::format("{}{} {} element{}", claims.empty() ? "" : ", ", element.count, element.name,
                              element.count == 1 ? "" : "s");
    }
    const std::string name = file.filename().string();
    const uint64_t dataBytes = fileBytes - std::min(fileBytes, headerBytes);
    if (!elements.empty() && neededBytes > static_cast<double>(dataBytes))
        throw InputError(where,
                         fmt::format("'{}' is truncated or corrupt: its header claims {}, which take at "
                                     "least {:.0f} bytes, but the file holds {} bytes after the header",
                                     name, claims, neededBytes, dataBytes));
    if (elements.empty()) neededMemory = kBytesPerFileByte * static_cast<double>(fileBytes);
    if (neededMemory > static_cast<double>(memoryBytes))
        throw InputError(where,
                         fmt::format("loading '{}' needs about {:.1f} GiB, more than the {:.1f} GiB of "
                                     "physical memory",
                                     name, neededMemory / kGiB, static_cast<double>(memoryBytes) / kGiB));
}

std::vector<FileMesh> loadMeshFile(const std::filesystem::path& file, const std::string& where,
                                   const std::string& baseName, std::vector<std::string>* warnings) {
    const std::optional<nlohmann::json> gltf = checkMeshFileStructure(file, where);
    checkMeshFileClaims(file, where, physicalMemoryBytes());
    const std::vector<float> emissiveStrengths = gltf ? gltfEmissiveStrengths(*gltf) : std::vector<float>{};
    Assimp::Importer importer;
    importer.SetPropertyFloat(AI_CONFIG_PP_GSN_MAX_SMOOTHING_ANGLE, kCreaseAngleDeg);
    // Bake node transforms but keep one mesh per node: joining meshes of equal material would name, say, all
    // white walls of a Cornell box after the first of them.
    importer.SetPropertyBool(AI_CONFIG_PP_PTV_KEEP_HIERARCHY, true);
    const std::string name = file.filename().string();

    // First the import alone, validated (indices in range, counts consistent), and checked by us, so that
    // post-processing never sees a broken scene; then the post-processing steps.
    const aiScene* scene = nullptr;
    {
        WarningLog log;
        try {
            scene = importer.ReadFile(file.string(), aiProcess_ValidateDataStructure);
        } catch (const std::bad_alloc&) {
            // A count in the data that the header checks cannot see (a PLY face claiming 4e9 indices).
            throw InputError(where,
                             fmt::format("'{}' is corrupt or too large: reading it ran out of memory", name));
        }
        if (scene == nullptr) {
            // Validation fails a file of points alone ("Mesh contains no faces"): say what is wrong.
            const std::string error = importError(importer);
            Assimp::Importer plain;
            if (const aiScene* raw = plain.ReadFile(file.string(), 0); raw != nullptr && !hasPolygons(*raw))
                throw InputError(where, fmt::format("'{}' contains no triangles", name));
            throw InputError(where, fmt::format("cannot load '{}': {}", file.string(), error));
        }
        for (const std::string& message : log.messages)
            if (message.find("out-of-range indices") != std::string::npos)
                throw InputError(where,
                                 fmt::format("'{}': some triangles refer to vertices that do not exist "
                                             "(index out of range)",
                                             name));
    }
    // The importer owns the scene; the post-processing below reads the primitive types validateRawScene sets.
    validateRawScene(*const_cast<aiScene*>(scene), file, where, baseName);
    if (!hasPolygons(*scene)) throw InputError(where, fmt::format("'{}' contains no triangles", name));
    constexpr unsigned kFlags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                aiProcess_GenSmoothNormals | aiProcess_CalcTangentSpace |
                                aiProcess_PreTransformVertices | aiProcess_SortByPType;
    // SortByPType splits meshes by primitive type; point and line meshes are skipped below.
    scene = importer.ApplyPostProcessing(kFlags);
    if (scene == nullptr)
        throw InputError(where, fmt::format("cannot load '{}': {}", file.string(), importError(importer)));

    std::vector<FileMesh> meshes;
    std::map<std::string, int> timesSeen;
    MaterialReader materialReader{*scene, file, where, {}, {}, false};
    std::vector<std::optional<FileMaterial>> materials(scene->mNumMaterials);  // each read once
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
        const aiMesh& source = *scene->mMeshes[m];
        if ((source.mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
        FileMesh result{readTriangles(source), {}};
        if (result.mesh.triangles.empty()) continue;
        readAttributes(source, isGltf(file), result.mesh);
        if (source.mMaterialIndex < scene->mNumMaterials) {
            std::optional<FileMaterial>& material = materials[source.mMaterialIndex];
            if (!material) {
                const aiMaterial& read = *scene->mMaterials[source.mMaterialIndex];
                material = readFileMaterial(read, materialReader);
                // KHR_materials_emissive_strength, which Debian's Assimp (5.2) does not read; glTF materials
                // come in the file's order.
                float assimpStrength = 0.0f;
                if (material->emission && source.mMaterialIndex < emissiveStrengths.size() &&
                    read.Get(AI_MATKEY_EMISSIVE_INTENSITY, assimpStrength) != AI_SUCCESS)
                    *material->emission *= emissiveStrengths[source.mMaterialIndex];
            }
            result.material = *material;
        }
        std::string name =
            baseName + "/" + (source.mName.length > 0 ? source.mName.C_Str() : std::to_string(m));
        // A mesh placed by several nodes (glTF instancing) appears once per node: number the repeats.
        int seen = ++timesSeen[name];
        result.mesh.name = seen == 1 ? name : fmt::format("{} ({})", name, seen);
        meshes.push_back(std::move(result));
    }
    if (meshes.empty())
        throw InputError(where, fmt::format("'{}' contains no triangles", file.filename().string()));
    if (meshes.size() == 1) meshes[0].mesh.name = baseName;
    if (warnings)
        warnings->insert(warnings->end(), materialReader.warnings.begin(), materialReader.warnings.end());
    return meshes;
}

}  // namespace deltagi
