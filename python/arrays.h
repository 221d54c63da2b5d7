// NumPy arrays <-> deltagi's images and matrices, for the Python module. Bad arrays raise InputError naming
// the argument, which the module turns into deltagi.InputError.
#pragma once

#include <string>

#include <pybind11/numpy.h>
#include <glm/glm.hpp>

#include "deltagi/image.h"

namespace deltagi::python {

namespace py = pybind11;

// A 4x4 matrix, row-major as written on paper (translation in the last column), to GLM's column-major one.
glm::mat4 toMat4(const py::handle& array, const std::string& where);
py::array_t<float> fromMat4(const glm::mat4& m);

// A 3-vector (any sequence of 3 finite numbers).
glm::vec3 toVec3(const py::handle& sequence, const std::string& where);

// An H x W x 3 array of floats (any dtype NumPy converts to float32) to an Image: one copy, the Image owns
// its pixels.
Image toImage(const py::handle& array, const std::string& where);

// The image as an H x W x C array (H x W when C = 1) that owns it: no copy; the array keeps the pixels alive.
py::array_t<float> toArray(Image&& image);

// A view of `image`, which `owner` keeps alive: no copy; writing to it changes the image.
py::array_t<float> viewOf(Image& image, const py::handle& owner);

}  // namespace deltagi::python
