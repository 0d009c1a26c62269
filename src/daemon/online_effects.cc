#include "daemon/online_effects.h"

#include <spdlog/spdlog.h>

#include <algorithm>

namespace kincal::daemon {
namespace {

constexpr double kHistoryMarginS = 10.0;

}  // namespace

OnlineEffects::OnlineEffects(OnlineEffectsOptions options)
    : opt_(options), cooldown_s_(options.cooldown_s) {}

void OnlineEffects::AddControl(TimeNs t_ns, std::span<const double> values, int num_controls) {
  if (!opt_.enabled) return;
  if (history_.num_channels() == 0) history_ = ControlSignal(num_controls, t_ns);
  // Kept a little longer than a window: controls arrive ahead of the poses by a varying
  // amount, and the window is cut at the pose time, exactly.
  if (history_.Append(t_ns, values)) {
    history_.DiscardBefore(history_.ToSeconds(t_ns) - opt_.window_s - kHistoryMarginS);
  }
}

Recording OnlineEffects::Window(TimeNs t_ns, const PoseRing& recent) const {
  Recording rec;
  rec.source = "kincald's last " + std::to_string(static_cast<int>(opt_.window_s)) + " s";
  const TimeNs from = t_ns - SecondsToNs(opt_.window_s);
  // The controls in force from the window's start to its end (t_ns), not those that came in
  // ahead of the poses: a replay must see the same window whatever the threads' timing.
  rec.controls = ControlSignal(history_.num_channels(), history_.origin_ns());
  const int first = std::max(0, history_.IndexAt(history_.ToSeconds(from)));
  const int last = history_.IndexAt(history_.ToSeconds(t_ns));
  for (int i = first; i <= last; ++i) {
    const auto& v = history_.ValuesAt(i);
    rec.controls.Append(
        history_.ToNs(history_.TimeAt(i)),
        std::span<const double>(v.data(), static_cast<size_t>(history_.num_channels())));
  }
  for (size_t k = 0; k < recent.size(); ++k) {
    const PoseSample& p = recent.at(k);
    const TimeNs t = UtimeToPipelineNs(p.utime);
    if (t < from || (!rec.poses.empty() && t <= rec.poses.back().t_ns)) continue;
    rec.poses.push_back({t, p.xytheta});
  }
  rec.stats.control_rows = static_cast<int>(rec.controls.size());
  rec.stats.pose_rows = static_cast<int>(rec.poses.size());
  return rec;
}

void OnlineEffects::OnCheck(TimeNs t_ns, const ModelCheckVerdict& verdict, const PoseRing& recent,
                            const System& sys, const VecN<kMaxState>& params,
                            const std::vector<std::string>& effects) {
  if (!opt_.enabled || searching() || added_ >= opt_.max_effects) return;
  if (verdict.suspected_effect.empty()) return;  // consistent, or still collecting
  if (next_allowed_ns_ != kNone && t_ns < next_allowed_ns_) return;
  if (history_.empty() || recent.empty()) return;
  const TimeNs first =
      std::max(history_.ToNs(history_.TimeAt(0)), UtimeToPipelineNs(recent.front().utime));
  if (t_ns - first < SecondsToNs(opt_.min_window_s)) return;
  AnalyzeOptions o;
  o.model = std::string(sys.model().name());
  o.base_effects = effects;
  o.effects_mode = "auto";
  o.max_effects = 1;
  o.num_threads = 1;
  for (int i = 0; i < sys.num_params(); ++i) {
    o.init[sys.params()[static_cast<size_t>(i)].name] = params[i];
  }
  if (search_.Start(Window(t_ns, recent), std::move(o))) {
    started_ns_ = t_ns;
    ++searches_;
    spdlog::info(
        "model check suspects {}: searching the last {:.0f} s for an effect the model lacks",
        verdict.suspected_effect, opt_.window_s);
  }
}

std::optional<EffectSearchResult> OnlineEffects::OnPose(TimeNs t_ns) {
  if (!searching()) return std::nullopt;
  std::optional<EffectSearchResult> r;
  if (opt_.lossless) {
    if (t_ns < started_ns_ + SecondsToNs(opt_.apply_after_s)) return std::nullopt;
    r = search_.Wait();
  } else {
    r = search_.Poll();
    if (!r) return std::nullopt;
  }
  started_ns_ = kNone;
  if (!r->ok || r->added.empty()) {
    spdlog::info("effect search: {}; next search in {:.0f} s",
                 r->ok ? "no effect explains the residuals better (" + r->evidence + ")" : r->error,
                 cooldown_s_);
    next_allowed_ns_ = t_ns + SecondsToNs(cooldown_s_);
    cooldown_s_ = std::min(2.0 * cooldown_s_, opt_.max_cooldown_s);
    return std::nullopt;
  }
  added_ += static_cast<int>(r->added.size());
  next_allowed_ns_ = t_ns + SecondsToNs(opt_.cooldown_s);
  cooldown_s_ = opt_.cooldown_s;
  return r;
}

void OnlineEffects::Reset() {
  if (searching()) search_.Wait();  // its window was on the old time base
  started_ns_ = kNone;
  next_allowed_ns_ = kNone;
  history_ = ControlSignal();
}

}  // namespace kincal::daemon
