// The scene reader running the albedo estimation itself: what tests/layout/check_includes.cmake must refuse
// (its code is in reference/; loading/ joins the two).
#include "deltagi/albedo_estimation.h"
