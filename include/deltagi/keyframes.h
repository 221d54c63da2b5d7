// Virtual objects that move over a sequence: the keyframed transforms of the scene file's "keyframes"
// (deltagi::ObjectAnimation in deltagi/scene.h), evaluated at a frame and applied to the scene's meshes.
#pragma once

#include <glm/glm.hpp>

#include "deltagi/export.h"
#include "deltagi/scene.h"

DELTAGI_API_BEGIN
namespace deltagi {

// The object's pose at `frame` (a transforms file's frame index; fractions interpolate too):
// T * R * S from its channels, as the scene file's "transform" composes translate, rotate_deg and scale.
glm::mat4 worldFromObjectAt(const ObjectAnimation& animation, double frame);

// Places every animated virtual object at its pose at `frame` (setTransform, deltagi/transforms.h). Throws
// InputError naming the object's keyframes when a pose is not a valid transform.
void poseObjects(Scene& scene, double frame);

// Without an explicit options.volume region, the region follows the virtual objects' bounding box, so a
// moving object would move the voxel grid every frame (the real scene voxelized again, differently).
// This fixes options.volume.center and size to the region that volumeRegion() gives for the box the objects
// sweep over all their keyframes (each animated mesh's object-space box at every whole frame from the first
// key to the last, the other virtual meshes as they are): the same for every frame and every --frames chunk.
// Does nothing without animations or with an explicit region.
void fixVolumeRegionOverAnimation(Scene& scene);

}  // namespace deltagi
DELTAGI_API_END
