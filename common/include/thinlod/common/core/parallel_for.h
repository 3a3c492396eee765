// parallelFor: runs independent work items on a few threads.
//
// Contract:
// - fn(i) is called exactly once for every i in [0, count), on up to
//   `threads` threads (the calling thread is one of them; 0 means one per
//   hardware thread, never more threads than items). Items are handed out
//   one at a time in increasing i, so put the longest first for balance.
// - fn must be safe to call concurrently for distinct i; results go to
//   per-item slots, so the outcome does not depend on the thread count.
// - An exception thrown by fn stops the handing out of further items; the
//   first one is rethrown on the calling thread after every thread joined.
//   When no more threads can be started, fewer do the work.
// Written by hand rather than with TBB: one loop over a dozen coarse items
// (seconds each) needs no scheduler, and the daemons need no new package.
#pragma once

#include <cstddef>
#include <functional>

namespace thinlod {

// The thread count `threads` stands for (0: std::thread::hardware_concurrency,
// at least 1).
int resolveThreadCount(int threads);

void parallelFor(std::size_t count, int threads, const std::function<void(std::size_t)>& fn);

}  // namespace thinlod
