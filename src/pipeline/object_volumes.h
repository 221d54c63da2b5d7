// The volumes that depend on the virtual objects (§3.2): their visibility volume, the full light volume and
// the delta volume, mip-mapped; kept from one frame to the next and, as the objects move, redone only where
// they change them, with the same bits as computing them from scratch:
//   1. voxelize: the objects are voxelized again into their box, their old box cleared (revoxelize);
//   3. inject: outside the objects' voxels and the voxels of the RSM texels they change (where each texel
//      landed without them and where it lands with them), the full light volume is the real scene's own and
//      the delta volume is (0, 0, 0, occupancy); the box around those voxels is injected again
//      (reinjectLight), together with last frame's box, which puts the scene's light back where the objects
//      have left;
//   4. mipmap: every level is recomputed above the changed boxes only (updateMipChain).
// When the real light changes (a new RealSceneVolumes::lightVersion, and the first frame), the full light
// volume starts from the scene's own light, the box of the objects and the texels they change injected as
// above, and its mip chain is made anew; the delta volume, (0, 0, 0, occupancy) outside that box and last
// frame's whatever the light, is injected and mip-mapped there only. A frame in which that box covers a large
// part of the volume injects everything as render() does.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include "core/ray_scene.h"
#include "deltagi/options.h"
#include "pipeline/gbuffer.h"
#include "pipeline/inject.h"
#include "pipeline/mipmap.h"
#include "pipeline/shadow_rays.h"
#include "pipeline/voxelize.h"

namespace deltagi {

// The real scene's share of the volumes (kept by the renderer). A changed real scene or region needs a new
// ObjectVolumes (the renderer keeps both in one place and drops both); a changed light, a new `lightVersion`.
struct RealSceneVolumes {
    const VoxelGeometry& geometry;
    std::span<const ReflectiveShadowMap> rsms;  // of the real scene alone, one per light
    const Grid3& light;                         // injected from rsms, plus `bounce`
    // The real scene's further bounces of light (bounceLight, at the surface voxels of `geometry`), added to
    // the full light volume as well; null: none.
    const SurfaceRadiance* bounce = nullptr;
    // Another value whenever `rsms`, `light` or `bounce` differ from the last frame's (the real light
    // changed).
    uint64_t lightVersion = 0;
    // The box around the non-zero voxels of `light` (injectedBounds), or null: found by reading it.
    const VoxelBox* lightBounds = nullptr;
    // The voxels injectLight wrote into `light` (which the bounces changed at `geometry`'s surface voxels
    // only), or null: any.
    const InjectedVoxels* lightVoxels = nullptr;
};

// What ObjectVolumes::roomChange is made from: the real scene's voxels with albedo, and the rays of the relit
// points towards the objects (the real scene alone, the objects over it, their bounds and bounding radius).
struct RoomChangeInputs {
    const VoxelGeometry& geometry;
    ShadowRayScenes rays;
};

class ObjectVolumes {
  public:
    // Stage 1: the objects' voxels, over `region` (a new region starts afresh). `unchanged`: the objects are
    // those of the last call, bit for bit (FrameRenderer::KeptWork::objects), and their voxels are kept.
    void voxelize(std::span<const TriangleMesh> objects, const VolumeRegion& region, bool withEmission = true,
                  bool withAlbedo = false, bool unchanged = false);
    // Stage 3: the full and delta light volumes (level 0). `updates` are the real scene's RSMs' updates for
    // the objects (traceRsmUpdate), one per light.
    void inject(const RealSceneVolumes& real, std::span<const RsmUpdate> updates);
    // Stage 4: the mip chains of the three volumes. With `sceneVisibility` and the objects voxelized with
    // albedo, the objects' own further bounce is added to the full and delta volumes (gatherObjectBounce):
    // they reflect the light of the room they receive, not only their direct light.
    // With `rays` (the objects' layer over the real scene) and options.diffuse.object_rays > 0 the bounce is
    // gathered by rays (gatherObjectBounceByRays). With `room` and options.diffuse.object_gather_rays > 0,
    // roomChange() too.
    void mipmap(const MipVolume* sceneVisibility = nullptr, const Options* options = nullptr,
                const RayScene* rays = nullptr, const RoomChangeInputs* room = nullptr);

    const MipVolume& objectVisibility() const { return objectVisibility_; }
    const MipVolume& fullLight() const { return fullLight_; }
    const MipVolume& deltaLight() const { return deltaLight_; }
    // The full light volume's voxels that the objects occupy (level 0; zero elsewhere), mip-mapped: the
    // objects' own light, which the differential relit cones tell apart from the scene's
    // (traceLightChangeCone).
    const MipVolume& objectLight() const { return objectLight_; }
    // What the objects change in the light of the real surfaces around them, bounced once more (radiance
    // times occupancy in rgb, 0 in w; empty: none): at each real surface voxel within an eighth of the
    // volume's side of the objects' box, its albedo times the change of its incoming light that the objects
    // make (traceObjectBounceRays, gathered over voxels of 4 level-0 voxels, on the side facing the objects):
    // their own light minus the real light they hide. The full light volume's further bounces are the real
    // scene's alone (bounce_light.h): without this the floor under an object still reflects the light the
    // object hides from it. Only the objects' own gather rays read it (traceDiffuseRays' `lightChange`): the
    // cones of the real surfaces' change take the objects' effect on them from the objects themselves, and
    // would count it twice.
    const MipVolume& roomChange() const { return roomChange_; }
    // The level-0 voxels of the light volumes that the last inject() wrote (all of them when it injected
    // from scratch): what a frame cost, for tests and measurements.
    const VoxelBox& injectedBox() const { return lightChanged_; }
    // How many of them it computed from their texels (all of them when it injected from scratch; with many
    // lights a box holds far more than the rows of voxels the objects change).
    size_t reinjectedVoxels() const { return reinjected_; }

  private:
    // mipmap() without the objects' bounce.
    void buildLightMips();
    // mipmap()'s parts: the objects' further bounce, and roomChange_.
    void addObjectBounce(const MipVolume& sceneVisibility, const Options& options, const RayScene* rays);
    void updateRoomChange(const MipVolume& sceneVisibility, const Options& options,
                          const RoomChangeInputs& room);
    // objectLight_ = the full light where the objects are, zero elsewhere, inside `box`, and its mip chain.
    void updateObjectLight(const VoxelBox& box);
    VolumeRegion region_;
    VoxelGeometry objects_;  // the objects' voxels (level 0 of objectVisibility_, copied there by mipmap())
    MipVolume objectVisibility_, fullLight_, deltaLight_, objectLight_, roomChange_;
    bool lightNew_ = true;  // the last inject() started from a new real light
    // The options roomChange_ was made with; none: it is not kept. A frame whose objects and light are the
    // last frame's (a camera that moves alone) keeps it: its inputs are the same, bit for bit.
    std::optional<Options> roomChangeOptions_;
    // The box over which objectVisibility_ and objectLight_ are stored (zero outside it): the objects' and a
    // margin, fitted anew when they leave it.
    VoxelBox window_;
    VoxelBox objectsChanged_;  // level-0 voxels that this frame's voxelization changed
    VoxelRows lightDiffers_;   // outside them the full light volume is the scene's (the last injection)
    size_t reinjected_ = 0;
    VoxelBox lightChanged_;  // level-0 voxels that this frame's injection rewrote (a new light: of the delta
                             // volume)
    std::optional<PackedGrid3> freshFull_, freshDelta_;  // made whole this frame, for mipmap()
    // Of the real light of version sceneLightVersion_, built on the first frame that needs them:
    std::optional<TexelBins> sceneTexels_;      // the real scene's RSM texels by voxel row
    std::optional<VoxelBox> sceneLightBounds_;  // the real scene's non-zero light voxels
    uint64_t sceneLightVersion_ = 0;
};

}  // namespace deltagi
