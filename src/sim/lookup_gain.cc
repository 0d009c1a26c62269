#include "sim/lookup_gain.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kincal {
namespace {

class LookupTableGain final : public EffectImpl<LookupTableGain> {
 public:
  LookupTableGain(int bands, double band_width) : bands_(bands), width_(band_width) {}

  std::string_view name() const override { return "lookup_gain"; }
  std::string_view description() const override {
    return "gain error of a channel per speed band of a look-up table (g_<channel>_<band>)";
  }
  EffectStage stage() const override { return EffectStage::kControlMap; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  bool Bind(const KinematicModel& model, const std::vector<std::string>& channels,
            std::string* error) override {
    if (!BindChannels(model, channels, &channels_, error)) return false;
    params_.clear();
    for (int c : channels_) {
      for (int b = 0; b < bands_; ++b) {
        params_.push_back(
            {"g_" + model.controls()[static_cast<size_t>(c)].name + "_" + std::to_string(b), "1",
             0.0, 0.01, "commands in this speed band"});
      }
    }
    return true;
  }
  template <class T>
  void MapControlsT(const T* p, T* u) const {
    for (size_t k = 0; k < channels_.size(); ++k) {
      T& v = u[channels_[k]];
      const int band = std::min(bands_ - 1, static_cast<int>(std::abs(ScalarOf(v)) / width_));
      v = v * (1.0 + p[k * static_cast<size_t>(bands_) + static_cast<size_t>(band)]);
    }
  }

 private:
  int bands_;
  double width_;
  std::vector<ParamInfo> params_;
  std::vector<int> channels_;
};

}  // namespace

std::shared_ptr<const Effect> MakeLookupTableGain(const KinematicModel& model, int bands,
                                                  double band_width) {
  if (bands < 1 || !(band_width > 0.0)) {
    throw std::invalid_argument("lookup_gain: bands >= 1 and band_width > 0 expected");
  }
  auto effect = std::make_shared<LookupTableGain>(bands, band_width);
  std::string error;
  if (!effect->Bind(model, {}, &error)) throw std::invalid_argument("lookup_gain: " + error);
  return effect;
}

}  // namespace kincal
