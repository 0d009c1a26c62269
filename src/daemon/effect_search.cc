#include "daemon/effect_search.h"

#include <sstream>

namespace kincal::daemon {

EffectSearch::EffectSearch() : thread_([this] { Loop(); }) {}

EffectSearch::~EffectSearch() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool EffectSearch::Start(Recording window, AnalyzeOptions options) {
  {
    std::lock_guard lock(mu_);
    if (busy_ || pending_) return false;
    window_ = std::move(window);
    options_ = std::move(options);
    result_.reset();
    pending_ = true;
  }
  cv_.notify_all();
  return true;
}

bool EffectSearch::running() const {
  std::lock_guard lock(mu_);
  return busy_ || pending_;
}

std::optional<EffectSearchResult> EffectSearch::Poll() {
  std::lock_guard lock(mu_);
  std::optional<EffectSearchResult> r = std::move(result_);
  result_.reset();
  return r;
}

EffectSearchResult EffectSearch::Wait() {
  std::unique_lock lock(mu_);
  cv_.wait(lock, [this] { return result_.has_value() || (!busy_ && !pending_); });
  EffectSearchResult r = result_ ? std::move(*result_) : EffectSearchResult{};
  result_.reset();
  return r;
}

void EffectSearch::Loop() {
  std::unique_lock lock(mu_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || pending_; });
    if (stop_) return;
    pending_ = false;
    busy_ = true;
    const Recording window = std::move(window_);
    const AnalyzeOptions options = options_;
    lock.unlock();
    EffectSearchResult r = Run(window, options);
    lock.lock();
    busy_ = false;
    result_ = std::move(r);
    cv_.notify_all();
  }
}

EffectSearchResult EffectSearch::Run(const Recording& window, const AnalyzeOptions& options) {
  EffectSearchResult r;
  try {
    const AnalyzeResult a = Analyze(window, options);
    r.ok = true;
    for (size_t i = options.base_effects.size(); i < a.after.effects.size(); ++i) {
      r.added.push_back(a.after.effects[i]);
    }
    r.params = a.after.params;
    r.heldout_before_m = a.before.heldout.pos_rms_m;
    r.heldout_after_m = a.after.heldout.pos_rms_m;
    std::ostringstream ev;
    ev.precision(3);
    for (const auto& t : a.trials) {
      ev << t.name << (t.accepted ? " accepted" : " rejected") << " (held-out gain "
         << t.heldout_gain << ", dBIC " << t.delta_bic << "); ";
    }
    r.evidence = ev.str();
  } catch (const AnalysisError& e) {  // too little or unsuitable data in the window
    r.error = e.what();
  }
  return r;
}

}  // namespace kincal::daemon
