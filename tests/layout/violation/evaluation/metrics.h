// The evaluation may include the pipeline (tests/layout/violation/pipeline/stage.h breaks the rule, not
// this).
#pragma once
