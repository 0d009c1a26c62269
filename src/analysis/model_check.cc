#include "kincal/analysis/model_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "kincal/effect.h"

namespace kincal {

const ModelCheck::OnlineTerm ModelCheck::kOnlineTerms[ModelCheck::kNumOnlineTerms] = {
    {{ResidualComponent::kAlong, Regressor::kAccel},
     "along-track innovation vs recent speed-command change"},
    {{ResidualComponent::kHeading, Regressor::kYawAccel},
     "heading innovation vs recent turn-command change"},
    {{ResidualComponent::kHeading, Regressor::kMoving}, "heading innovation biased while moving"},
    {{ResidualComponent::kCross, Regressor::kTurnRate}, "cross-track innovation vs turn rate"},
    {{ResidualComponent::kAlong, Regressor::kTurnRate}, "along-track innovation vs turn rate"},
    {{ResidualComponent::kAlong, Regressor::kAbsTurnRate}, "along-track innovation vs |turn rate|"},
    {{ResidualComponent::kAlong, Regressor::kAbsSpeed},
     "along-track innovation vs |speed| beyond a gain (sign-dependent speed gain)"},
    {{ResidualComponent::kHeading, Regressor::kAbsTurnRate},
     "heading innovation vs |turn rate| beyond a gain (sign-dependent turn gain)"},
    {{ResidualComponent::kCross, Regressor::kLatAccel},
     "cross-track innovation vs speed x turn rate beyond the turn rate (sideways slip)"},
    {{ResidualComponent::kHeading, Regressor::kTurnRateSq},
     "heading innovation vs turn rate x |turn rate| beyond a gain (turn-rate dependent track)"},
};

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
  // Every registered effect that applies to the model, for each term of its signature this
  // check measures (the signatures are the effects' own: kincal/signature.h).
  std::vector<std::pair<std::string, std::vector<SignatureTerm>>> signatures;
  for (const auto& name : EffectRegistry::Instance().Names()) {
    const auto effect = EffectRegistry::Instance().Create(name);
    if (effect->AppliesTo(sys_.model())) signatures.emplace_back(name, effect->signature());
  }
  for (int k = 0; k < kNumOnlineTerms; ++k) {
    for (const auto& [name, signature] : signatures) {
      for (const auto& term : signature) {
        if (term.component == kOnlineTerms[k].term.component &&
            term.regressor == kOnlineTerms[k].term.regressor) {
          suspects_.push_back({name, k});
        }
      }
    }
  }
}

void ModelCheck::Add(TimeNs t_ns, const UpdateResult& update, const StateVec& state,
                     const ControlSignal& u) {
  if (!(update.ok || update.gated) || update.innovation.size() < kPoseDim ||
      update.innovation_cov.rows() < kPoseDim || !std::isfinite(update.nis)) {
    return;
  }
  const double th = state[2];
  const double c = std::cos(th), s = std::sin(th);
  // Body-frame innovation, whitened by its predicted sigma, clipped.
  const Eigen::Matrix2d rot = (Eigen::Matrix2d() << c, s, -s, c).finished();
  const Eigen::Matrix2d s_body =
      rot * update.innovation_cov.topLeftCorner<2, 2>() * rot.transpose();
  const Eigen::Vector2d body = rot * update.innovation.head<2>();
  auto whiten = [](double v, double var) {
    return var > 0 ? std::clamp(v / std::sqrt(var), -kClipSigmas, kClipSigmas) : 0.0;
  };
  const double t = u.ToSeconds(t_ns);
  // Commanded body twist now and a lookback earlier (model at the current parameters).
  const double* p = state.data() + sys_.param_offset();
  const Twist<double> now = sys_.model().BodyTwist(p, u.At(t).data());
  const Twist<double> before = sys_.model().BodyTwist(p, u.At(t - options_.lookback_s).data());
  const double values[kNumSeries] = {whiten(body.x(), s_body(0, 0)),
                                     whiten(body.y(), s_body(1, 1)),
                                     whiten(update.innovation[2], update.innovation_cov(2, 2)),
                                     now.vx - before.vx,
                                     now.omega - before.omega,
                                     now.omega,
                                     std::abs(now.omega),
                                     (std::abs(now.vx) + std::abs(now.omega)) > 1e-9 ? 1.0 : 0.0,
                                     std::min(update.nis, kClipSigmas * kClipSigmas),
                                     now.vx,
                                     std::abs(now.vx),
                                     now.vx * now.omega,
                                     now.omega * std::abs(now.omega)};
  for (int k = 0; k < kNumSeries; ++k)
    data_[static_cast<size_t>(k)][static_cast<size_t>(next_)] = values[k];
  next_ = (next_ + 1) % kWindow;
  if (count_ < kWindow) ++count_;
}

// Every series' sum in one pass over the window: each sum still adds in window order (the
// same bits as a pass per series), the series' independent sums overlapping in the CPU.
std::array<double, ModelCheck::kNumSeries> ModelCheck::Means() const {
  std::array<double, kNumSeries> means{};
  for (int i = 0; i < count_; ++i) {
    for (size_t k = 0; k < means.size(); ++k) means[k] += data_[k][static_cast<size_t>(i)];
  }
  for (double& m : means) m /= count_;
  return means;
}

// Correlation of series y and x over the window, as a z (r sqrt(n)).
double ModelCheck::CorrZ(const std::array<double, kNumSeries>& means, Series y, Series x) const {
  const double my = means[y], mx = means[x];
  double sxy = 0, sxx = 0, syy = 0;
  for (int i = 0; i < count_; ++i) {
    const double a = data_[x][static_cast<size_t>(i)] - mx,
                 b = data_[y][static_cast<size_t>(i)] - my;
    sxy += a * b;
    sxx += a * a;
    syy += b * b;
  }
  return (sxx > 0 && syy > 0) ? sxy / std::sqrt(sxx * syy) * std::sqrt(static_cast<double>(count_))
                              : 0.0;
}

// Partial correlation of y and x with `control`'s linear part removed from both, as a z.
double ModelCheck::PartialZ(const std::array<double, kNumSeries>& means, Series y, Series x,
                            Series control) const {
  const double n_sqrt = std::sqrt(static_cast<double>(count_));
  const double rxy = CorrZ(means, y, x) / n_sqrt, rxc = CorrZ(means, x, control) / n_sqrt,
               ryc = CorrZ(means, y, control) / n_sqrt;
  const double d = (1.0 - rxc * rxc) * (1.0 - ryc * ryc);
  return d > 1e-9 ? (rxy - rxc * ryc) / std::sqrt(d) * n_sqrt : 0.0;
}

// The heading innovation's mean while moving, as a z (0 with 10 or fewer such samples).
double ModelCheck::HeadingBiasZ() const {
  double hm = 0, hs = 0;
  int moving = 0;
  for (int i = 0; i < count_; ++i) {
    if (data_[kMoving][static_cast<size_t>(i)] > 0.5) {
      hm += data_[kHeading][static_cast<size_t>(i)];
      ++moving;
    }
  }
  if (moving <= 10) return 0.0;
  hm /= moving;
  for (int i = 0; i < count_; ++i) {
    if (data_[kMoving][static_cast<size_t>(i)] > 0.5)
      hs += std::pow(data_[kHeading][static_cast<size_t>(i)] - hm, 2);
  }
  hs = std::sqrt(hs / moving);
  return hs > 0 ? hm / (hs / std::sqrt(static_cast<double>(moving))) : 0.0;
}

// The z of every term this check measures, in kOnlineTerms' order.
std::array<double, ModelCheck::kNumOnlineTerms> ModelCheck::TermZ(
    const std::array<double, kNumSeries>& m) const {
  return {CorrZ(m, kAlong, kDv),
          CorrZ(m, kHeading, kDw),
          HeadingBiasZ(),
          CorrZ(m, kCross, kW),
          CorrZ(m, kAlong, kW),
          CorrZ(m, kAlong, kAbsW),
          PartialZ(m, kAlong, kAbsV, kV),
          PartialZ(m, kHeading, kAbsW, kW),
          PartialZ(m, kCross, kLatAcc, kW),
          PartialZ(m, kHeading, kWSq, kW)};
}

ModelCheckVerdict ModelCheck::Verdict() const {
  ModelCheckVerdict v;
  v.window = count_;
  v.window_capacity = kWindow;
  if (count_ == 0) {
    v.evidence = "no innovations yet";
    return v;
  }
  const std::array<double, kNumSeries> means = Means();
  v.nis_mean = means[kNis];
  if (count_ < options_.min_samples) {
    v.evidence =
        "collecting: " + std::to_string(count_) + " of " + std::to_string(kWindow) + " innovations";
    return v;
  }
  const std::array<double, kNumOnlineTerms> term_z = TermZ(means);
  const Suspect* best = nullptr;
  double best_z = 0.0;
  for (const auto& c : suspects_) {
    const double z = term_z[static_cast<size_t>(c.term)];
    if (std::abs(z) >= options_.z_threshold &&
        (best == nullptr || std::abs(z) > std::abs(best_z))) {
      best = &c;
      best_z = z;
    }
  }
  const bool nis_ok = v.nis_mean < 3.0 * v.nis_expected;
  v.consistent = best == nullptr && nis_ok && count_ == kWindow;
  Describe(best, best_z, nis_ok, &v);
  return v;
}

// The verdict's suspect, confidence, candidates and evidence.
void ModelCheck::Describe(const Suspect* best, double best_z, bool nis_ok,
                          ModelCheckVerdict* v) const {
  std::ostringstream ev;
  ev.precision(3);
  if (best != nullptr) {
    v->suspected_effect = best->effect;
    v->confidence = 1.0 - std::exp(-(std::abs(best_z) - options_.z_threshold));
    ev << kOnlineTerms[best->term].what << " (z = " << best_z << ")";
    for (const auto& c : suspects_) {
      if (c.term == best->term) v->candidates.push_back(c.effect);
    }
    if (v->candidates.size() > 1) {
      ev << ": the signature of";
      for (const auto& name : v->candidates) ev << " " << name;
      ev << " (not told apart by this term)";
    }
  } else if (!nis_ok) {
    v->suspected_effect = "unknown";
    v->confidence = 0.5;
    ev << "innovations too large (mean NIS " << v->nis_mean << ", expected " << v->nis_expected
       << ") without a known signature";
  }
  if (best == nullptr && nis_ok && count_ < kWindow) {
    ev << "no signature so far; collecting: " << count_ << " of " << kWindow << " innovations";
  } else {
    if (best == nullptr && nis_ok) ev << "no signature, innovations as expected";
    ev << "; window " << count_ << " innovations";
  }
  v->evidence = ev.str();
}

}  // namespace kincal
