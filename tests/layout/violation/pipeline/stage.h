// A pipeline stage that reaches into the evaluation: what tests/layout/check_includes.cmake must refuse.
#pragma once

#include "evaluation/metrics.h"
