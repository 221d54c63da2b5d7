// Reading scene files (JSON). The format is documented in docs/scene-format.md.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "deltagi/export.h"
#include "deltagi/scene.h"

DELTAGI_API_BEGIN
namespace deltagi {

// Applies one "--set KEY=VALUE" override to a parsed scene document. KEY is a dotted path; numeric
// components index arrays ("virtual.0.material.albedo"); VALUE is parsed as JSON, and taken as a string when
// it is not valid JSON. Throws InputError naming the override when KEY walks through a non-object/array or
// an index is out of range.
void applyOverride(nlohmann::json& document, const std::string& keyEqualsValue);

// Reads, validates and loads a scene: the JSON, every mesh (Assimp), the background image. `overrides` are
// applied, in order, to the JSON before it is validated. Throws InputError (file + JSON path + what was
// expected) for any bad input: missing files, malformed JSON, wrong types, unknown keys, empty meshes, NaN
// or infinite vertices, a background of the wrong size, impossible options.
Scene loadScene(const std::filesystem::path& file, const std::vector<std::string>& overrides = {});

// Same, from an already parsed document; `file` is used for messages and to resolve relative paths.
Scene loadScene(const nlohmann::json& document, const std::filesystem::path& file);

// The scene file's JSON with `overrides` applied, as loadScene reads it before validating it (InputError
// when the file cannot be read or is not JSON): for a caller that changes the document before loading it.
nlohmann::json readSceneDocument(const std::filesystem::path& file,
                                 const std::vector<std::string>& overrides = {});

// The options as JSON, every key with its value (the defaults where the scene did not set one).
nlohmann::json optionsToJson(const Options& options);

// The options tables of docs/scene-format.md, made from the one description of each option
// (src/scene/option_table.cpp): one table per group, each between "<!-- options table: GROUP -->" and
// "<!-- end of options table -->".
std::string optionTablesMarkdown();
// `markdown` (the text of `file`) with the table between each pair of those markers made anew. Throws
// InputError naming the file and line for a group that does not exist, a table without its end marker, and
// a group without its table or with two.
std::string withOptionTables(const std::string& markdown, const std::string& file);

// ---- tracked camera sequences (src/scene/sequence_io.cpp)
// ------------------------------------------------------- As capture tools write them: the nerfstudio /
// instant-ngp `transforms.json` that COLMAP, Polycam, Record3D, Metashape and others are converted into.
// Intrinsics (fl_x fl_y cx cy w h, or camera_angle_x), the camera model (PINHOLE, OPENCV with k1 k2 (k3) p1
// p2, OPENCV_FISHEYE with k1..k4) globally or per frame; per frame `file_path` (the photo, relative to the
// file) and `transform_matrix` (camera to world, OpenGL axes: the camera looks down -z with +y up, as
// deltagi's cameras do). Keys deltagi does not use (aabb_scale, depth_file_path, ...) are ignored.

// A range of frames "A:B" (A included, B not; either may be left out: "A:", ":B", ":").
struct FrameRange {
    int first = 0;
    int last = -1;  // -1: to the end
};
// Throws InputError naming `where` when `text` is not such a range.
FrameRange parseFrameRange(const std::string& text, const std::string& where);

// The frames of `file` in `range`, in order: camera (with its distortion) and photo path (which must exist;
// a file_path without an extension may name a .png or .jpg). Throws InputError naming the file and the frame
// (frames[3].transform_matrix) for a missing or malformed key, a NaN or singular matrix or one that is no
// rotation (a scale, shear or mirror), an unknown camera model, a missing photo or one whose header gives
// another size than its camera's, or a range outside the frames.
std::vector<SequenceFrame> readTransforms(const std::filesystem::path& file, FrameRange range);

// The position of the camera of the first frame of `file` (whatever range is rendered): a sequence's
// options.volume.viewpoint unless the scene gives one.
glm::vec3 sequenceViewpoint(const std::filesystem::path& file);

// The frame rate a transforms file gives in a top-level "fps" (a number > 0; some capture tools write one),
// or nothing. Throws InputError naming the file and the key when it is not such a number.
inline constexpr double kMaxFrameRate = 1000.0;
std::optional<double> transformsFrameRate(const std::filesystem::path& file);

// The frame's photo, which must be of its camera's size: InputError naming the transforms file and the frame
// otherwise.
Image readFramePhoto(const SequenceFrame& frame, const std::filesystem::path& transformsFile);

// The scene as frame `frame` of its sequence: the frame's camera, its photo (read now: InputError as
// readFramePhoto; none for a frame without one, whose real scene is rendered) and the keyframed objects'
// poses (poseObjects).
void showFrame(Scene& scene, const SequenceFrame& frame);

// The scene's camera and photo as they are, to put back after a loop of showFrame(); restoring also poses
// the keyframed objects for the sequence's first frame, as the scene was loaded.
struct ShownFrame {
    Camera camera;
    std::optional<Image> background;
    std::filesystem::path backgroundFile;
};
ShownFrame shownFrame(const Scene& scene);
void restoreShownFrame(Scene& scene, const ShownFrame& shown);

// "frames A:B of FILE" for the scene's sequence (empty without one).
std::string sequenceRangeText(const Scene& scene);

// The frames of the scene's transforms file just before its sequence's first, which a run renders first,
// unwritten, so that temporal reuse (options.render.temporal_frames) averages as many frames in a range as
// in the whole file: temporal_frames - 1 of them, fewer at the file's start. InputError as readTransforms.
std::vector<SequenceFrame> framesBeforeSequence(const Scene& scene);

}  // namespace deltagi
DELTAGI_API_END
