// The one parallel loop helper of the pipeline (pbrt-v4's ParallelFor): splits [begin, end) into fixed chunks
// and runs them on TBB's pool, the caller included. Chunks never depend on the thread count, so a loop whose
// body writes only to its own indices gives the same result with any number of threads.
#pragma once

#include <algorithm>
#include <cstdint>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace deltagi {

// Calls body(i) for every i in [begin, end); `grain` indices per task.
template <typename Body>
void parallelFor(int64_t begin, int64_t end, int64_t grain, Body&& body) {
    if (end <= begin) return;
    tbb::parallel_for(
        tbb::blocked_range<int64_t>(begin, end, std::max<int64_t>(grain, 1)),
        [&](const tbb::blocked_range<int64_t>& r) {
            for (int64_t i = r.begin(); i != r.end(); ++i) body(i);
        },
        tbb::simple_partitioner());
}

}  // namespace deltagi
