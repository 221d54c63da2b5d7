// The procedural meshes are public API now (deltagi/shapes.h, issue 14); this forwarder keeps the includes in
// src/, tests/ and bench/ unchanged until src/ is reorganized (issue 14, part 3).
#pragma once

#include "deltagi/shapes.h"
