// Reading a virtual object's "keyframes" (src/scene/keyframes.cpp); the format is in README "Scene files".
#pragma once

#include "deltagi/scene.h"
#include "scene/json_reader.h"

namespace deltagi {

// "keyframes": [{"frame": F or "time": SECONDS, "translate": [x, y, z], "rotate_deg": [x, y, z],
// "scale": s or [x, y, z]}, ...]: at least one key, each with a frame or a time (one kind for all keys, in
// strictly increasing order) and at least one channel. `frameRate` converts times to frames. Throws
// InputError naming the file and the key (virtual[1].keyframes[2].frame) for keys out of order, missing or of
// the wrong type, non-finite numbers, a zero scale or a scale whose sign changes between two keys (it would
// pass through zero: a flat, non-invertible object).
ObjectAnimation readKeyframes(const JsonNode& node, double frameRate);

}  // namespace deltagi
