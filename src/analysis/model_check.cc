#include "kincal/analysis/model_check.h"

#include <cmath>
#include <sstream>

namespace kincal {

bool ModelCheckOptions::IsValid(std::string* error) const {
  if (!(lookback_s > 0.0) || !(z_threshold > 0.0) || min_samples < 10 ||
      min_samples > ModelCheck::kWindow) {
    *error = "lookback_s > 0, z_threshold > 0, 10 <= min_samples <= window expected";
    return false;
  }
  return true;
}

ModelCheck::ModelCheck(const System& sys, ModelCheckOptions options)
    : sys_(sys), options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("ModelCheck: " + error);
}

void ModelCheck::Add(TimeNs t_ns, const UpdateResult& update, const StateVec& state,
                     const ControlSignal& u) {
  if (!update.ok || update.innovation.size() < 3) return;
  const double th = state[2];
  const double c = std::cos(th), s = std::sin(th);
  const double ix = update.innovation[0], iy = update.innovation[1];
  const double t = u.ToSeconds(t_ns);
  // Commanded body twist now and a lookback earlier (model at the current parameters).
  const double* p = state.data() + sys_.param_offset();
  const Twist<double> now = sys_.model().BodyTwist(p, u.At(t).data());
  const Twist<double> before = sys_.model().BodyTwist(p, u.At(t - options_.lookback_s).data());
  const double values[kNumSeries] = {c * ix + s * iy,
                                     -s * ix + c * iy,
                                     update.innovation[2],
                                     now.vx - before.vx,
                                     now.omega - before.omega,
                                     now.omega,
                                     std::abs(now.omega),
                                     (std::abs(now.vx) + std::abs(now.omega)) > 1e-9 ? 1.0 : 0.0,
                                     update.nis};
  for (int k = 0; k < kNumSeries; ++k)
    data_[static_cast<size_t>(k)][static_cast<size_t>(next_)] = values[k];
  next_ = (next_ + 1) % kWindow;
  if (count_ < kWindow) ++count_;
}

ModelCheckVerdict ModelCheck::Verdict() const {
  ModelCheckVerdict v;
  v.window = count_;
  if (count_ == 0) return v;
  const int n = count_;
  auto mean = [&](Series k) {
    double m = 0;
    for (int i = 0; i < n; ++i) m += data_[k][static_cast<size_t>(i)];
    return m / n;
  };
  auto corr_z = [&](Series y, Series x) {
    const double my = mean(y), mx = mean(x);
    double sxy = 0, sxx = 0, syy = 0;
    for (int i = 0; i < n; ++i) {
      const double a = data_[x][static_cast<size_t>(i)] - mx,
                   b = data_[y][static_cast<size_t>(i)] - my;
      sxy += a * b;
      sxx += a * a;
      syy += b * b;
    }
    return (sxx > 0 && syy > 0) ? sxy / std::sqrt(sxx * syy) * std::sqrt(static_cast<double>(n))
                                : 0.0;
  };
  v.nis_mean = mean(kNis);
  if (count_ < options_.min_samples) return v;
  // Heading bias while moving.
  double hm = 0, hs = 0;
  int moving = 0;
  for (int i = 0; i < n; ++i) {
    if (data_[kMoving][static_cast<size_t>(i)] > 0.5) {
      hm += data_[kHeading][static_cast<size_t>(i)];
      ++moving;
    }
  }
  double bias_z = 0.0;
  if (moving > 10) {
    hm /= moving;
    for (int i = 0; i < n; ++i) {
      if (data_[kMoving][static_cast<size_t>(i)] > 0.5)
        hs += std::pow(data_[kHeading][static_cast<size_t>(i)] - hm, 2);
    }
    hs = std::sqrt(hs / moving);
    bias_z = hs > 0 ? hm / (hs / std::sqrt(static_cast<double>(moving))) : 0.0;
  }
  struct Candidate {
    const char* effect;
    const char* what;
    double z;
  };
  const Candidate candidates[] = {
      {"time_offset", "along-track innovation vs recent speed-command change", corr_z(kAlong, kDv)},
      {"time_offset", "heading innovation vs recent turn-command change", corr_z(kHeading, kDw)},
      {"yaw_rate_bias", "heading innovation biased while moving", bias_z},
      {"lever_arm", "cross-track innovation vs turn rate", corr_z(kCross, kW)},
      {"lever_arm", "along-track innovation vs turn rate", corr_z(kAlong, kW)},
      {"turn_slowdown", "along-track innovation vs |turn rate|", corr_z(kAlong, kAbsW)},
  };
  const Candidate* best = nullptr;
  for (const auto& c : candidates) {
    if (std::abs(c.z) >= options_.z_threshold &&
        (best == nullptr || std::abs(c.z) > std::abs(best->z)))
      best = &c;
  }
  const bool nis_ok = v.nis_mean < 3.0 * v.nis_expected;
  v.consistent = best == nullptr && nis_ok;
  std::ostringstream ev;
  ev.precision(3);
  if (best != nullptr) {
    v.suspected_effect = best->effect;
    v.confidence = 1.0 - std::exp(-(std::abs(best->z) - options_.z_threshold));
    ev << best->what << " (z = " << best->z << ")";
  } else if (!nis_ok) {
    v.suspected_effect = "unknown";
    v.confidence = 0.5;
    ev << "innovations too large (mean NIS " << v.nis_mean << ", expected " << v.nis_expected
       << ") without a known signature";
  }
  ev << "; window " << n << " updates";
  v.evidence = ev.str();
  return v;
}

}  // namespace kincal
