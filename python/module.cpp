// The Python module `deltagi`: load a scene, set the camera pose, the objects' transforms and the photo, and
// render frames into NumPy arrays. A thin layer over the public C++ API (include/deltagi/): every check is
// the library's, and its InputError becomes deltagi.InputError (a ValueError) with the same one-line message.
#include <mutex>
#include <string>
#include <vector>

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "arrays.h"
#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "deltagi/transforms.h"

namespace deltagi::python {

namespace {

// A scene and the lock that keeps it unchanged while a frame of it renders without the GIL: a setter called
// from another thread meanwhile waits for the frame.
struct PyScene {
    Scene scene;
    std::mutex busy;
};

// Runs `change` on the scene under its lock, the GIL released while waiting for a frame to finish.
template <typename Change>
void changeScene(PyScene& s, Change&& change) {
    std::unique_lock lock(s.busy, std::defer_lock);
    {
        py::gil_scoped_release released;
        lock.lock();
    }
    change(s.scene);
}

// The virtual meshes an object index or name stands for: the mesh at that index, or those named `name` and
// "name/..." (the sub-meshes of one file).
std::vector<size_t> objectMeshes(const Scene& scene, const py::handle& key) {
    const std::vector<TriangleMesh>& meshes = scene.virtuals;
    if (py::isinstance<py::int_>(key)) {
        const auto index = key.cast<long long>();
        if (index < 0 || static_cast<size_t>(index) >= meshes.size())
            throw InputError(
                "object " + std::to_string(index),
                "out of range: the scene has " + std::to_string(meshes.size()) + " virtual objects");
        return {static_cast<size_t>(index)};
    }
    if (!py::isinstance<py::str>(key)) throw InputError("object", "expected an index or a name");
    const auto name = key.cast<std::string>();
    std::vector<size_t> found;
    for (size_t i = 0; i < meshes.size(); ++i)
        if (meshes[i].name == name || meshes[i].name.starts_with(name + "/")) found.push_back(i);
    if (found.empty()) {
        std::string names;
        for (const TriangleMesh& m : meshes) names += (names.empty() ? "'" : ", '") + m.name + "'";
        throw InputError("object '" + name + "'", "no virtual object of that name (there are: " +
                                                      (names.empty() ? "none" : names) + ")");
    }
    return found;
}

py::dict outputToPython(RenderOutput&& out) {
    py::dict result;
    result["composite"] = toArray(std::move(out.composite));
    result["background"] = toArray(std::move(out.background));
    result["delta"] = toArray(std::move(out.delta));
    result["object_mask"] = toArray(std::move(out.objectMask));
    py::dict timings;  // in pipeline order (dicts keep insertion order); a stage run twice is summed
    for (const StageTiming& t : out.timings) {
        const py::str name(t.name);
        timings[name] = (timings.contains(name) ? timings[name].cast<double>() : 0.0) + t.ms;
    }
    result["timings_ms"] = timings;
    result["total_ms"] = out.totalMs;
    return result;
}

// One frame without the GIL, the scene locked against changes meanwhile.
template <typename RenderFn>
py::dict renderLocked(PyScene& s, RenderFn&& renderFn) {
    RenderOutput out;
    {
        py::gil_scoped_release released;
        std::lock_guard lock(s.busy);
        out = renderFn(s.scene);
    }
    return outputToPython(std::move(out));
}

struct PyFrameRenderer {
    FrameRenderer renderer;
    std::mutex busy;  // one frame at a time
};

// A frame of `r` (a still with `still`), one at a time; the GIL released while it waits and renders.
py::dict renderFrameLocked(PyFrameRenderer& r, PyScene& s, bool still) {
    std::unique_lock lock(r.busy, std::defer_lock);
    {
        py::gil_scoped_release released;
        lock.lock();
    }
    return renderLocked(s, [&](const Scene& scene) {
        return still ? r.renderer.renderStill(scene) : r.renderer.render(scene);
    });
}

}  // namespace
}  // namespace deltagi::python

PYBIND11_MODULE(deltagi, m) {
    // Frames allocate and free per-pixel arrays: keep the freed memory for the next (deltagi/renderer.h).
    deltagi::retainFreedMemory();
    using namespace deltagi;
    using namespace deltagi::python;
    m.doc() = "Delta Global Illumination: virtual objects rendered into real camera images (see README.md).";
    m.attr("__version__") = DELTAGI_VERSION;
    // Bad input of any kind, with the one line the command line prints after "deltagi: error: ".
    py::register_exception<InputError>(m, "InputError", PyExc_ValueError);

    py::class_<PyScene>(m, "Scene", "A scene: camera, photo, real meshes, virtual objects, lights, options.")
        .def_static(
            "load",
            [](const std::filesystem::path& path, const std::vector<std::string>& overrides) {
                auto s = std::make_unique<PyScene>();
                py::gil_scoped_release released;  // meshes and photos can take a while to read
                s->scene = loadScene(path, overrides);
                return s;
            },
            py::arg("path"), py::arg("overrides") = std::vector<std::string>{},
            "Reads a scene file; overrides are the CLI's --set KEY=VALUE strings.")
        .def_property_readonly("width", [](const PyScene& s) { return s.scene.camera.width; })
        .def_property_readonly("height", [](const PyScene& s) { return s.scene.camera.height; })
        .def_property_readonly("warnings", [](const PyScene& s) { return s.scene.warnings; })
        .def_property(
            "camera_pose", [](const PyScene& s) { return fromMat4(s.scene.camera.worldFromCamera); },
            [](PyScene& s, const py::handle& matrix) {
                const glm::mat4 pose = toMat4(matrix, "camera_pose");
                try {
                    checkCameraPose(pose);
                } catch (const InputError& e) {
                    throw InputError("camera_pose", e.message());
                }
                changeScene(s, [&](Scene& scene) { scene.camera.worldFromCamera = pose; });
            },
            "world_from_camera, 4x4 row-major (OpenGL camera frame: looking down -z, +y up).")
        .def(
            "set_camera",
            [](PyScene& s, const py::handle& position, const py::handle& lookAt, const py::handle& up) {
                const glm::mat4 pose =
                    lookAtPose(toVec3(position, "position"), toVec3(lookAt, "look_at"), toVec3(up, "up"));
                changeScene(s, [&](Scene& scene) { scene.camera.worldFromCamera = pose; });
            },
            py::arg("position"), py::arg("look_at"), py::arg("up") = std::vector<float>{0.0f, 1.0f, 0.0f},
            "Points the camera from `position` at `look_at`.")
        .def_property_readonly(
            "object_names",
            [](const PyScene& s) {
                std::vector<std::string> names;
                for (const TriangleMesh& mesh : s.scene.virtuals) names.push_back(mesh.name);
                return names;
            },
            "The virtual objects' meshes, in the scene's order (an index into this list names one).")
        .def(
            "object_transform",
            [](const PyScene& s, const py::handle& key) {
                return fromMat4(s.scene.virtuals[objectMeshes(s.scene, key).front()].worldFromObject);
            },
            py::arg("object"), "world_from_object of a virtual object (index or name), 4x4 row-major.")
        .def(
            "set_object_transform",
            [](PyScene& s, const py::handle& key, const py::handle& matrix) {
                const glm::mat4 worldFromObject = toMat4(matrix, "transform");
                const std::vector<size_t> meshes = objectMeshes(s.scene, key);
                changeScene(s, [&](Scene& scene) {
                    // All or nothing: a mesh that refuses the transform leaves the others where they were.
                    std::vector<TriangleMesh> placed;
                    for (size_t i : meshes) {
                        placed.push_back(scene.virtuals[i]);
                        setTransform(placed.back(), worldFromObject);
                    }
                    for (size_t k = 0; k < meshes.size(); ++k)
                        scene.virtuals[meshes[k]] = std::move(placed[k]);
                });
            },
            py::arg("object"), py::arg("world_from_object"),
            "Places a virtual object (index or name) by a 4x4 row-major transform that replaces the scene "
            "file's.")
        .def_property(
            "background",
            [](py::object self) -> py::object {
                PyScene& s = self.cast<PyScene&>();
                if (!s.scene.background) return py::none();
                return viewOf(*s.scene.background, self);
            },
            [](PyScene& s, const py::handle& array) {
                std::optional<Image> photo;
                if (!array.is_none()) photo = toImage(array, "background");
                changeScene(s, [&](Scene& scene) { scene.background = std::move(photo); });
            },
            "The photo, H x W x 3 float32 linear RGB (a view of the scene's; None: the real scene is "
            "rendered). Assigning copies the array once.");

    py::class_<PyFrameRenderer>(m, "FrameRenderer",
                                "Renders frames of one scene, keeping the real scene's work between them.")
        .def(py::init<>())
        .def(
            "render", [](PyFrameRenderer& r, PyScene& s) { return renderFrameLocked(r, s, false); },
            py::arg("scene"),
            "One frame: a dict of composite, background, delta (H x W x 3 float32), object_mask (H x W), "
            "timings_ms and total_ms. The GIL is released while it renders. The options' \"auto\" "
            "(refine_budget, object_gather_rays) spends a session frame's time, not a still's.")
        .def(
            "render_still", [](PyFrameRenderer& r, PyScene& s) { return renderFrameLocked(r, s, true); },
            py::arg("scene"),
            "render()'s image (a still: `deltagi render`'s) with the kept work's speed; the frames temporal "
            "reuse averages over are forgotten first. As render.")
        .def(
            "clear", [](PyFrameRenderer& r) { r.renderer.clear(); },
            "Forgets everything kept: a cold frame next.")
        .def(
            "clear_history", [](PyFrameRenderer& r) { r.renderer.clearHistory(); },
            "Forgets the frames temporal reuse averages over (options.render.temporal_frames): the next "
            "frame is one without reuse, for a frame that does not follow the ones before it.");

    m.def(
        "render",
        [](PyScene& s) { return renderLocked(s, [](const Scene& scene) { return render(scene); }); },
        py::arg("scene"),
        "One still from scratch (`deltagi render`'s image; FrameRenderer.render_still's result).");
    m.def(
        "read_image", [](const std::filesystem::path& path) { return toArray(readImage(path)); },
        py::arg("path"), "Reads PNG/JPEG (to linear), EXR, HDR as H x W x 3 float32.");
    m.def(
        "write_image",
        [](const std::filesystem::path& path, const py::handle& array) {
            writeImage(toImage(array, "image"), path);
        },
        py::arg("path"), py::arg("image"), "Writes .png (8-bit sRGB), .exr or .hdr (linear float).");
}
