// A pipeline stage that calls the scene reader through its public header: what
// tests/layout/check_includes.cmake must refuse (its code is in scene/, above the pipeline).
#pragma once

#include "deltagi/scene_io.h"
