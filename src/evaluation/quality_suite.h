// Internals of the quality suite (deltagi/quality_suite.h), exposed for tests.
#pragma once

#include "deltagi/quality_suite.h"

namespace deltagi {

// A reference's composite moved onto another background: each pixel keeps its change and, by its coverage,
// the object's radiance, so that references whose backgrounds are their own path-traced `without` (noisy,
// or direct light only) compare by their change alone. With a photo both backgrounds are the photo.
Image onBackground(const ReferenceOutput& reference, const Image& background);

struct DeltaSplit {
    double shadowPart = 0.0, indirectPart = 0.0;  // SceneQuality::shadowPart, indirectPart
    double referenceShadowShare = 0.0, referenceIndirectShare = 0.0;  // SceneQuality's, of Δref
};

// Over the real pixels of `e.classes`: DGI's shadow only (e.shadowOnlyComposite) against the
// direct-light-only reference's change (over its own background), and what DGI and the reference add to them
// (the indirect change), each relative to ||Δref|| (docs/ground-truth.md#the-quality-suite).
DeltaSplit splitDeltaError(const Evaluation& e, const ReferenceOutput& direct);

}  // namespace deltagi
