// ModelCheck: the residual diagnosis, online. Fed with every filter innovation, it keeps
// a sliding window and tests whether the innovations are what a correct model predicts:
// unbiased, of the expected size (NIS), and uncorrelated with what the robot was told to
// do. A correlation names the effect whose signature (Effect::signature(), in the
// vocabulary of kincal/signature.h) has that term; the terms measured online are
//   along-track innovation ~ recent change of commanded speed      (along, accel)
//   heading innovation     ~ recent change of commanded turn rate  (heading, yaw_accel)
//   heading innovation biased while moving                         (heading, moving)
//   cross- and along-track innovation ~ turn rate                  (cross|along, turn_rate)
//   along-track innovation ~ |turn rate|                           (along, abs_turn_rate)
// so that, with the registered effects, they name time_offset (actuator_lag shares its
// signature), yaw_rate_bias, lever_arm and turn_slowdown. The daemon publishes the verdict as
// kincal.model_check_t. Fixed-size ring buffer: no allocation per update.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/estimation/filter.h"
#include "kincal/signature.h"
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
  // True only over a full window of innovations that are white, unbiased and of the
  // expected size; false while the window fills (evidence says so) or when a signature or
  // the NIS says the model misses something.
  bool consistent = false;
  double nis_mean = 0.0;
  double nis_expected = 3.0;
  int window = 0;
  int window_capacity = 0;
  std::string suspected_effect;         // the first candidate; empty when none
  std::vector<std::string> candidates;  // every effect whose signature has the term found
  double confidence = 0.0;              // 0..1
  std::string evidence;
};

class ModelCheck {
 public:
  static constexpr int kWindow = 512;
  ModelCheck(const System& sys, ModelCheckOptions options = {});
  // One pose at time t (recording time base), used or gated: the innovation and its
  // covariance, the current state estimate (for heading and parameters) and the control
  // history. The innovation is whitened by its predicted sigma and clipped at
  // kClipSigmas, so a single wild pose cannot dominate the correlations.
  void Add(TimeNs t_ns, const UpdateResult& update, const StateVec& state, const ControlSignal& u);
  static constexpr double kClipSigmas = 8.0;
  ModelCheckVerdict Verdict() const;
  void Reset() {
    count_ = 0;
    next_ = 0;
  }

 private:
  enum Series {
    kAlong,
    kCross,
    kHeading,
    kDv,
    kDw,
    kW,
    kAbsW,
    kMoving,
    kNis,
    kV,
    kAbsV,
    kLatAcc,
    kWSq,
    kNumSeries
  };
  // The signature terms measured online (the command change over the lookback stands for
  // accel and yaw_accel; the current turn rate for turn_rate). Terms whose regressor is a
  // nonlinear function of the speed or turn rate are measured by partial correlation, with
  // the linear part removed: the filter's own gains explain that part while they converge.
  struct OnlineTerm {
    SignatureTerm term;
    const char* what;
  };
  static constexpr int kNumOnlineTerms = 10;
  static const OnlineTerm kOnlineTerms[kNumOnlineTerms];
  // An effect whose signature has a measured term.
  struct Suspect {
    std::string effect;
    int term;  // index into kOnlineTerms
  };
  const System& sys_;
  ModelCheckOptions options_;
  std::array<std::array<double, kWindow>, kNumSeries> data_{};
  int count_ = 0;
  int next_ = 0;
  std::vector<Suspect> suspects_;  // in kOnlineTerms order, effects in registration order

  std::array<double, kNumSeries> Means() const;
  double CorrZ(const std::array<double, kNumSeries>& means, Series y, Series x) const;
  double PartialZ(const std::array<double, kNumSeries>& means, Series y, Series x,
                  Series control) const;
  double HeadingBiasZ() const;
  std::array<double, kNumOnlineTerms> TermZ(const std::array<double, kNumSeries>& means) const;
  void Describe(const Suspect* best, double best_z, bool nis_ok, ModelCheckVerdict* v) const;
};

}  // namespace kincal
