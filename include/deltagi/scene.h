// The scene: camera, background photo, real reconstruction, virtual objects, lights and options.
// Everything is in world space (right-handed; any unit, used consistently), already transformed.
#pragma once

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/vec2.hpp>

#include "deltagi/environment.h"
#include "deltagi/export.h"
#include "deltagi/image.h"
#include "deltagi/math.h"
#include "deltagi/options.h"
#include "deltagi/texture.h"

DELTAGI_API_BEGIN
namespace deltagi {

// Two reflection models; both are two-sided, and a material may also emit: a diffuse (Lambertian) area light
// of uniform radiance over the mesh (times the emissive texture), from both faces.
//
// Phong (the scene format's "albedo"/"specular"/"roughness"): Lambertian diffuse + a normalized Phong glossy
// lobe around the mirror direction:
//   f(wi, wo) = albedo/pi + specular * (n+2)/(2 pi) * max(0, dot(reflect(-wo), wi))^n,  n = phongExponent().
// albedo + specular must not exceed 1 per channel (energy conservation).
//
// MetallicRoughness (glTF 2.0, and the scene format's "base_color"/"metallic"): the glTF BRDF, a Lambertian
// diffuse of colour base * (1 - metallic) under a GGX (Trowbridge-Reitz) specular lobe with height-correlated
// Smith visibility and Schlick Fresnel, F0 = mix(0.04, base, metallic); `albedo` holds the base colour
// factor and `roughness` glTF's perceptual roughness (GGX alpha = roughness^2).
enum class MaterialModel { Phong, MetallicRoughness };
// glTF's alphaMode: Opaque ignores alpha; Mask drops the surface where alpha < alphaCutoff (rays pass
// through it); Blend is read as Mask at 0.5 (a renderer of opaque surfaces cannot blend).
enum class AlphaMode { Opaque, Mask };

struct Material {
    glm::vec3 albedo{0.8f};  // "albedo": diffuse reflectance in [0,1]; MetallicRoughness: base colour factor
    glm::vec3 specular{0.0f};  // "specular": glossy reflectance in [0,1] (Phong only)
    float roughness = 1.0f;    // "roughness" in (0,1], or "glossiness" = 1 - roughness
    // "emission" times "emission_scale": emitted radiance (W / (sr m^2), per world unit squared), linear RGB
    glm::vec3 emission{0.0f};

    MaterialModel model = MaterialModel::Phong;
    float metallic = 0.0f;  // "metallic" in [0, 1] (MetallicRoughness)
    float opacity = 1.0f;   // the base colour factor's alpha
    AlphaMode alphaMode = AlphaMode::Opaque;
    float alphaCutoff = 0.5f;
    // Textures (each may be null). Base colour (sRGB, RGBA) multiplies `albedo` and `opacity`; for Phong
    // materials it is the diffuse map (OBJ map_Kd), `specularTexture` the specular map (map_Ks). Metallic-
    // roughness: B = metallic, G = roughness, multiplying the factors. Normal: tangent-space, scaled in xy by
    // `normalScale`. Emissive (sRGB) multiplies `emission`. Occlusion: R, blended in by
    // `occlusionStrength`; it dims the indirect light only.
    TextureSlot baseColorTexture;
    TextureSlot specularTexture;
    // OBJ/MTL's scalar maps (the red channel): map_Pr multiplies `roughness` (either model), map_Ns the
    // Phong exponent Ns (Phong only; as the MTL specification defines it).
    TextureSlot roughnessTexture;
    TextureSlot shininessTexture;
    TextureSlot metallicRoughnessTexture;
    TextureSlot normalTexture;
    float normalScale = 1.0f;
    TextureSlot emissiveTexture;
    TextureSlot occlusionTexture;
    float occlusionStrength = 1.0f;

    bool emits() const { return emission != glm::vec3(0.0f); }
    bool textured() const {
        return baseColorTexture || specularTexture || roughnessTexture || shininessTexture ||
               metallicRoughnessTexture || normalTexture || emissiveTexture || occlusionTexture;
    }
    // What the light volumes reflect: the diffuse and the glossy reflectance together. A voxel holds one
    // radiance for every direction, so a glossy surface's light goes in spread evenly over the hemisphere
    // rather than left out (the glossy Cornell box's floor sends a third of the light it reflects through its
    // glossy lobe): the reflected flux stays right, its direction is lost. Quality suite, glossy Cornell box:
    // delta_rel_error 0.250 -> 0.232, object_rel_rmse 0.106 -> 0.127 (the ball's glossy reflection sees the
    // floor as bright from every side); the other scenes have no glossy surfaces.
    glm::vec3 volumeReflectance() const { return albedo + specular; }

    // Phong exponent of the glossy lobe (the Blinn-Phong/Beckmann correspondence n = 2/r^2 - 2).
    float phongExponent() const {
        float r = std::max(roughness, 1e-3f);
        return std::max(2.0f / (r * r) - 2.0f, 0.0f);
    }
};

struct TriangleMesh {
    std::string name;                   // for messages: file name or shape name, and sub-mesh
    std::vector<glm::vec3> positions;   // world space
    std::vector<glm::vec3> normals;     // world space, unit length, one per position
    std::vector<glm::uvec3> triangles;  // indices into positions
    // Optional per-vertex attributes, each empty or one per position: texture coordinate sets 0 and 1
    // (glTF TEXCOORD_0/1, OBJ vt), tangents (xyz unit, in world space like the normals; w = +-1, the
    // bitangent's handedness: bitangent = w * cross(normal, tangent)), and linear RGB vertex colours that
    // multiply the material's albedo or base colour (glTF COLOR_0, PLY red/green/blue, estimated albedo).
    std::vector<glm::vec2> uvs;
    std::vector<glm::vec2> uvs1;
    std::vector<glm::vec4> tangents;
    std::vector<glm::vec3> colors;
    Material material;
    // The virtual objects' meshes as read, in object space, and the transform that placed them (the scene
    // file's "transform"): setTransform() (deltagi/transforms.h) places them again as the objects move.
    // Shared and never changed (copies of a scene share it); null for the real scene's meshes.
    std::shared_ptr<const TriangleMesh> objectSpace;
    glm::mat4 worldFromObject{1.0f};

    Bounds3f bounds() const;
    size_t triangleCount() const { return triangles.size(); }
};

// A pinhole camera. Pixel (i, j) has its centre at (i + 0.5, j + 0.5), origin top-left, +y down. Camera space
// follows OpenGL: +x right, +y up, looking down -z.
// Lens distortion as calibration tools (OpenCV, COLMAP, nerfstudio) give it, on normalized image coordinates
// (x right, y down, z = 1 in front): "opencv" (Brown-Conrady: radial k1 k2 k3, tangential p1 p2) and
// "fisheye" (OpenCV's equidistant fisheye model: k1..k4 on the angle from the axis).
struct LensDistortion {
    enum class Model { None, OpenCV, Fisheye };
    Model model = Model::None;
    float k1 = 0, k2 = 0, k3 = 0, k4 = 0, p1 = 0, p2 = 0;
    bool none() const { return model == Model::None; }
    // Where an undistorted point lands in the image (the model's forward direction).
    glm::vec2 distort(glm::vec2 undistorted) const;
    // The undistorted point that distort() takes to `distorted` (Newton's method; to about 1e-6).
    glm::vec2 undistort(glm::vec2 distorted) const;
    bool operator==(const LensDistortion&) const = default;
};

struct Camera {
    int width = 640;
    int height = 480;
    float fx = 0, fy = 0, cx = 0, cy = 0;  // pixels
    glm::mat4 worldFromCamera{1.0f};
    LensDistortion distortion;  // of the photo: rays go through it, so the layers line up with the photo

    glm::vec3 position() const { return glm::vec3(worldFromCamera[3]); }
    // Square pixels, the principal point at the centre and a vertical field of view of `fovYDeg` degrees in
    // (0, 180) (the scene file's "fov_y_deg"), for the current width and height.
    void setFieldOfView(double fovYDeg) {
        fy = static_cast<float>(0.5 * height / std::tan(0.5 * glm::radians(fovYDeg)));
        fx = fy;
        cx = 0.5f * static_cast<float>(width);
        cy = 0.5f * static_cast<float>(height);
    }
    // Unnormalized world-space direction through image point (px, py) in pixels.
    glm::vec3 rayDirection(float px, float py) const {
        glm::vec2 n((px - cx) / fx, (py - cy) / fy);
        if (!distortion.none()) n = distortion.undistort(n);
        return glm::mat3(worldFromCamera) * glm::vec3(n.x, -n.y, -1.0f);
    }
    // The image point (pixels) of camera-space point q in front of the camera (q.z < 0), through the
    // distortion: rayDirection's inverse.
    glm::vec2 imagePoint(glm::vec3 q) const {
        glm::vec2 n(q.x / -q.z, q.y / q.z);
        if (!distortion.none()) n = distortion.distort(n);
        return {cx + fx * n.x, cy + fy * n.y};
    }
    bool operator==(const Camera&) const = default;
};

struct Light {
    enum class Type { Point, Spot, Directional };
    Type type = Type::Point;
    glm::vec3 color{1.0f};     // "color": linear RGB, multiplied by intensity
    float intensity = 1.0f;    // "intensity": radiant intensity (W/sr) of point and spot lights; irradiance
                               // (W/m^2, per world unit squared) of directional lights
    glm::vec3 position{0.0f};  // "position": point and spot lights
    glm::vec3 direction{0, -1, 0};  // "direction": unit, the direction light travels (spot and directional)
    float innerAngleDeg = 30.0f;    // "inner_angle_deg": spot full intensity inside this half-angle
    float outerAngleDeg = 45.0f;    // "outer_angle_deg": spot zero intensity outside this half-angle
    float radius = 0.0f;  // "radius": size of the emitter in world units (softens shadow cones); 0 = use
                          // options.shadow.aperture_deg
    // Directional lights extracted from the environment map: the half-angle (radians) of the part of the sky
    // the light stands for, which widens its shadow cone; the path tracer skips these lights (it samples the
    // map itself). Not read from scene files.
    bool fromEnvironment = false;
    float angularRadius = 0.0f;
    // An emitting surface's stand-in for the reflective shadow maps (renderer.cpp): its intensity falls off
    // as the cosine of the angle to `direction` and is zero behind it, as a Lambertian emitter's. Not read
    // from scene files.
    bool lambertian = false;

    glm::vec3 power() const { return color * intensity; }
};

// One frame of a tracked camera sequence ("sequence": a transforms.json): its camera and its photo.
struct SequenceFrame {
    int index = 0;  // its place in the transforms file's "frames" (output files are numbered by it)
    Camera camera;
    // Empty for a frame without one (a camera path over the rendered real scene).
    std::filesystem::path photo;
};

// A virtual object that moves over a sequence (its "keyframes" in the scene file; deltagi/keyframes.h): each
// channel is a list of (frame, value) in increasing frame order, interpolated linearly between its keys,
// rotations by slerp (the shorter way round), and held before its first key and after its last; a channel
// without keys is the identity. Frames are the transforms file's frame indices ("time" keys are converted
// with the sequence's frame rate), fractions allowed.
struct ObjectAnimation {
    size_t firstMesh = 0, meshCount = 0;  // its meshes in Scene::virtuals (a mesh file may hold several)
    std::vector<std::pair<double, glm::vec3>> translate;
    std::vector<std::pair<double, glm::quat>> rotation;
    std::vector<std::pair<double, glm::vec3>> scale;
    std::string where;  // "scene.json: virtual[1].keyframes", for messages
};

// A fiducial marker printed and laid on the real scene (the scene file's "markers"): it registers a camera
// that sees it (`deltagi track`, src/live/marker_registration.h). AprilTag family tag36h11.
struct Marker {
    int id = 0;         // "id": the tag's number in its family (0-586)
    float size = 0.0f;  // "size": side of the printed black square, in world units
    // "transform" (an object or 4 rows, as for meshes, but rigid): the marker's frame, whose origin is the
    // black square's centre, x to the right and y up as the tag is printed, z out of its printed face.
    glm::mat4 worldFromMarker{1.0f};
    bool operator==(const Marker&) const = default;
};

struct Scene {
    std::filesystem::path file;  // the scene file, for messages; relative paths were resolved against it
    Camera camera;               // with a sequence: its first frame's
    // "sequence": the frames to render, in order (empty: a single image from `camera`); `background` is the
    // first frame's photo, and each frame's is read when it is rendered.
    std::vector<SequenceFrame> sequence;
    std::filesystem::path sequenceFile;  // the transforms file
    // The sequence's frame rate (frames per second): "sequence.fps", else the transforms file's "fps", else
    // 30. Converts keyframe times to frames, and is the video's default rate.
    double frameRate = 30.0;
    std::vector<ObjectAnimation> animations;  // the virtual objects that move (only with a sequence)
    std::optional<Image> background;  // the real camera image, linear RGB, camera-sized; absent: rendered
    std::filesystem::path backgroundFile;
    // The mesh files read ("file" keys), in the scene's order.
    std::vector<std::filesystem::path> meshFiles;
    std::vector<TriangleMesh> real;      // "scene": the reconstruction of the real scene
    std::vector<TriangleMesh> virtuals;  // "virtual": the virtual objects
    // For each of `virtuals`, its entry in the scene file's "virtual" list (a file entry may hold several
    // meshes, which share its "transform"); filled by loadScene, may be empty for scenes built in code.
    std::vector<int> virtualEntries;
    std::vector<int> realEntries;  // the same for `real` and the scene file's "scene" list
    std::vector<Light> lights;     // the scene file's lights, then those extracted from the environment
    std::optional<Environment> environment;  // "environment": the light probe
    std::vector<Marker> markers;             // "markers": what registers a camera by its image
    Options options;
    // What the loader accepted but the user should know (an LDR environment map, repaired pixels).
    std::vector<std::string> warnings;
};

}  // namespace deltagi
DELTAGI_API_END
