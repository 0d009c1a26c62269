// The online effect search of kincald (robot.effects: auto): `kincal analyze`'s selection
// (the same code: Analyze with the running effects as its base) on a recent window of
// poses and controls, in a worker thread, so that neither capture nor the filter thread
// ever waits for it (except a lossless replay, which waits at a fixed point in data time
// so that its decisions are bit-identical run to run).
#pragma once

#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "kincal/analysis/analyze.h"
#include "kincal/io/recording.h"

namespace kincal::daemon {

struct EffectSearchResult {
  bool ok = false;
  std::string error;                  // why the search failed (too little data, no fit)
  std::vector<std::string> added;     // effects the selection accepted (empty: none)
  std::vector<ParamEstimate> params;  // of the augmented model (model's, then effects')
  double heldout_before_m = 0, heldout_after_m = 0;  // position RMS at the horizon
  std::string evidence;                              // one line per trial
};

class EffectSearch {
 public:
  EffectSearch();
  ~EffectSearch();
  EffectSearch(const EffectSearch&) = delete;
  EffectSearch& operator=(const EffectSearch&) = delete;

  // Starts a search (false if one is running).
  bool Start(Recording window, AnalyzeOptions options);
  bool running() const;
  // The result once the search is done (and forgets it); nothing while it runs.
  std::optional<EffectSearchResult> Poll();
  // Waits for the running search.
  EffectSearchResult Wait();

 private:
  void Loop();
  static EffectSearchResult Run(const Recording& window, const AnalyzeOptions& options);

  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false, pending_ = false, busy_ = false;
  Recording window_;
  AnalyzeOptions options_;
  std::optional<EffectSearchResult> result_;
  std::thread thread_;
};

}  // namespace kincal::daemon
