// Worker threads that must never slow the pipeline (the batch calibration, the preview, the
// guidance) run below its threads: nice + kBackgroundNice, about a tenth of a core's share
// against a busy pipeline thread. Not SCHED_IDLE: that runs only on a core nothing else wants, and
// on a loaded machine (a robot's computer, a CI run of two test programs) such a worker starved for
// minutes. Linux keeps the nice value per thread, and threads it starts inherit it.
#pragma once

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace kincal::daemon {

inline constexpr int kBackgroundNice = 10;

// Lowers the calling thread's priority by kBackgroundNice. Failing to changes nothing that
// matters (the worker only finishes sooner), so it is not an error.
inline void RunThisThreadInTheBackground() {
  (void)setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kBackgroundNice);
}

}  // namespace kincal::daemon
