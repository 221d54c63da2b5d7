#include "arrays.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "deltagi/error.h"

namespace deltagi::python {

namespace {

std::string shapeText(const py::array& a) {
    std::string text = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) text += (i ? ", " : "") + std::to_string(a.shape(i));
    return text + (a.ndim() == 1 ? ",)" : ")");
}

// Any array-like of numbers as a C-contiguous float32 array (NumPy converts; a copy only when it must).
py::array_t<float, py::array::c_style | py::array::forcecast> floats(const py::handle& object,
                                                                     const std::string& where) {
    auto array = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(object);
    if (!array) throw InputError(where, "expected an array of numbers");
    return array;
}

std::vector<py::ssize_t> shapeOf(const Image& image) {
    if (image.channels() == 1) return {image.height(), image.width()};
    return {image.height(), image.width(), image.channels()};
}

}  // namespace

glm::mat4 toMat4(const py::handle& object, const std::string& where) {
    auto a = floats(object, where);
    if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
        throw InputError(where, "expected a 4x4 matrix, got shape " + shapeText(a));
    glm::mat4 m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m[c][r] = a.at(r, c);
    return m;
}

py::array_t<float> fromMat4(const glm::mat4& m) {
    py::array_t<float> a({4, 4});
    auto out = a.mutable_unchecked<2>();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out(r, c) = m[c][r];
    return a;
}

glm::vec3 toVec3(const py::handle& object, const std::string& where) {
    auto a = floats(object, where);
    if (a.ndim() != 1 || a.shape(0) != 3)
        throw InputError(where, "expected 3 numbers, got shape " + shapeText(a));
    glm::vec3 v(a.at(0), a.at(1), a.at(2));
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw InputError(where, "expected finite numbers");
    return v;
}

Image toImage(const py::handle& object, const std::string& where) {
    auto a = floats(object, where);
    if (a.ndim() != 3 || a.shape(2) != 3)
        throw InputError(where,
                         "expected an RGB image, an array of shape (height, width, 3), got " + shapeText(a));
    Image image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)), 3);
    std::copy_n(a.data(), image.data().size(), image.data().begin());
    return image;
}

py::array_t<float> toArray(Image&& image) {
    auto* owned = new Image(std::move(image));
    py::capsule free(owned, [](void* p) { delete static_cast<Image*>(p); });
    return py::array_t<float>(shapeOf(*owned), owned->data().data(), free);
}

py::array_t<float> viewOf(Image& image, const py::handle& owner) {
    return py::array_t<float>(shapeOf(image), image.data().data(), owner);
}

}  // namespace deltagi::python
