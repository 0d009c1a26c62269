// ModelCheck: the residual diagnosis, online. Fed with every filter innovation, it keeps
// a sliding window and tests whether the innovations are what a correct model predicts:
// unbiased, of the expected size (NIS), and uncorrelated with what the robot was told to
// do. A correlation names the effect whose signature it is:
//   along-track innovation ~ recent change of commanded speed      -> time_offset (or lag)
//   heading innovation     ~ recent change of commanded turn rate  -> time_offset (or lag)
//   heading innovation biased while moving                         -> yaw_rate_bias
//   position innovation    ~ turn rate                             -> lever_arm
//   along-track innovation ~ |turn rate|                           -> turn_slowdown
// The daemon publishes the verdict as kincal.model_check_t. Fixed-size ring buffer: no
// allocation per update.
#pragma once

#include <array>
#include <string>

#include "kincal/control_signal.h"
#include "kincal/estimation/filter.h"
#include "kincal/system.h"
#include "kincal/time.h"

namespace kincal {

struct ModelCheckOptions {
  double lookback_s = 0.3;   // command change measured over this interval before a pose
  double z_threshold = 5.0;  // |z| above which a signature counts
  int min_samples = 100;     // no verdict before this many innovations
  bool IsValid(std::string* error) const;
};

struct ModelCheckVerdict {
  bool consistent = true;
  double nis_mean = 0.0;
  double nis_expected = 3.0;
  int window = 0;
  std::string suspected_effect;  // empty when none
  double confidence = 0.0;       // 0..1
  std::string evidence;
};

class ModelCheck {
 public:
  static constexpr int kWindow = 512;
  ModelCheck(const System& sys, ModelCheckOptions options = {});
  // One filter update at time t (recording time base): the innovation and its covariance,
  // the current state estimate (for heading and parameters) and the control history.
  void Add(TimeNs t_ns, const UpdateResult& update, const StateVec& state, const ControlSignal& u);
  ModelCheckVerdict Verdict() const;
  void Reset() {
    count_ = 0;
    next_ = 0;
  }

 private:
  enum Series { kAlong, kCross, kHeading, kDv, kDw, kW, kAbsW, kMoving, kNis, kNumSeries };
  const System& sys_;
  ModelCheckOptions options_;
  std::array<std::array<double, kWindow>, kNumSeries> data_{};
  int count_ = 0;
  int next_ = 0;
};

}  // namespace kincal
