// kincald's robot.effects: auto. When the model check names a suspect (or sees innovations
// too large for any signature), the recent window of poses and controls goes to the effect
// search (effect_search.h: kincal analyze's selection, in a worker thread). An accepted
// effect comes back to the filter stage, which re-initialises the filter on the augmented
// model from the search's fit.
//
// When a result is applied: live, at the first pose after it is ready; in a lossless
// replay, at the first pose `apply_after_s` of data time after the search started (the
// filter thread waits for it there), so that a replay decides bit-identically every time.
// A search that adds nothing makes the next one wait twice as long (data time).
#pragma once

#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "daemon/effect_search.h"
#include "daemon/pose_ring.h"
#include "kincal/analysis/model_check.h"
#include "kincal/control_signal.h"
#include "kincal/system.h"
#include "kincal/time.h"

namespace kincal::daemon {

struct OnlineEffectsOptions {
  bool enabled = false;
  bool lossless = false;       // a replay with --fast: results applied at fixed data times
  double window_s = 60.0;      // the search's window of recent data (at most)
  double min_window_s = 30.0;  // no search before this much data in the window
  double cooldown_s = 30.0;    // data time between searches (doubles after each fruitless one)
  double max_cooldown_s = 480.0;
  double apply_after_s = 5.0;  // lossless: results applied this long after the start
  int max_effects = 4;         // effects added online at most
};

// One effect added, for model_check_t.
struct AddedEffect {
  std::string name;
  int64_t utime = 0;
  double heldout_before_m = 0, heldout_after_m = 0;
};

class OnlineEffects {
 public:
  explicit OnlineEffects(OnlineEffectsOptions options);

  // Every control sample the filter takes (the search's window needs more history than
  // the filter keeps).
  void AddControl(TimeNs t_ns, std::span<const double> values, int num_controls);
  // At each model-check publication: starts a search if the verdict names a suspect and
  // the window and the cooldown allow. `sys`, `params` and `effects` are the running model.
  void OnCheck(TimeNs t_ns, const ModelCheckVerdict& verdict, const PoseRing& recent,
               const System& sys, const VecN<kMaxState>& params,
               const std::vector<std::string>& effects);
  // At each pose: a result with effects to add, at its application point.
  std::optional<EffectSearchResult> OnPose(TimeNs t_ns);
  // A new time base: the history and any running search are void.
  void Reset();

  bool searching() const { return started_ns_ != kNone; }
  int searches() const { return searches_; }

 private:
  Recording Window(TimeNs t_ns, const PoseRing& recent) const;

  static constexpr TimeNs kNone = std::numeric_limits<TimeNs>::min();
  OnlineEffectsOptions opt_;
  EffectSearch search_;
  ControlSignal history_;
  TimeNs started_ns_ = kNone;  // the running search's start (data time)
  TimeNs next_allowed_ns_ = kNone;
  double cooldown_s_;
  int searches_ = 0, added_ = 0;
};

}  // namespace kincal::daemon
