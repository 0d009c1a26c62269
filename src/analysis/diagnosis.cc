#include "kincal/analysis/diagnosis.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace kincal {
namespace {

// Fewer fit windows than this give no diagnosis.
constexpr size_t kMinWindows = 10;

double Component(const ResidualPoint& p, int c) {
  return c == 0 ? p.along : (c == 1 ? p.cross : p.heading);
}

// Bias of y: mean over its root-mean-square.
double BiasRatio(const std::vector<double>& y, double mean) {
  double s2 = 0;
  for (double v : y) s2 += v * v;
  return s2 > 0 ? mean / std::sqrt(s2 / static_cast<double>(y.size())) : 0.0;
}

double Correlation(const std::vector<double>& x, const std::vector<double>& y, double my,
                   double syy) {
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
  double sxx = 0, sxy = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  return (sxx > 0 && syy > 0) ? sxy / std::sqrt(sxx * syy) : 0.0;
}

}  // namespace

std::vector<DiagnosisTerm> Diagnose(const std::vector<ResidualPoint>& points,
                                    const std::vector<RegressorValues>& regressors,
                                    double horizon_s) {
  std::vector<DiagnosisTerm> out;
  if (regressors.empty()) return out;
  // Effective number of independent windows: windows start at every (strided) pose but
  // overlap over one horizon.
  std::vector<size_t> fit_idx;
  for (size_t k = 0; k < points.size(); ++k) {
    if (!points[k].heldout) fit_idx.push_back(k);
  }
  if (fit_idx.size() < kMinWindows) return out;
  const double span = points[fit_idx.back()].t_s - points[fit_idx.front()].t_s;
  const double n_eff =
      std::max(2.0, std::min<double>(static_cast<double>(fit_idx.size()), span / horizon_s));
  std::vector<double> x;
  for (int c = 0; c < kNumResidualComponents; ++c) {
    std::vector<double> y;
    for (size_t k : fit_idx) y.push_back(Component(points[k], c));
    const double my = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(y.size());
    double syy = 0;
    for (double v : y) syy += (v - my) * (v - my);
    for (int r = 0; r < kNumRegressors; ++r) {
      const auto reg = static_cast<Regressor>(r);
      if (!regressors.front().Has(reg)) continue;
      const auto comp = static_cast<ResidualComponent>(c);
      DiagnosisTerm t{
          std::string(ComponentName(comp)), std::string(RegressorName(reg)), 0.0, 0.0, comp, reg};
      if (reg == Regressor::kConst) {
        t.r = BiasRatio(y, my);
      } else {
        x.clear();
        for (size_t k : fit_idx) x.push_back(regressors[k][reg]);
        t.r = Correlation(x, y, my, syy);
      }
      t.z = t.r * std::sqrt(n_eff);
      out.push_back(t);
    }
  }
  std::sort(out.begin(), out.end(),
            [](const auto& a, const auto& b) { return std::abs(a.z) > std::abs(b.z); });
  return out;
}

double SignatureZ(const std::vector<SignatureTerm>& signature,
                  const std::vector<DiagnosisTerm>& diagnosis) {
  double z = 0.0;
  for (const auto& term : signature) {
    for (const auto& t : diagnosis) {
      if (t.component_id == term.component && t.regressor_id == term.regressor) {
        z = std::max(z, std::abs(t.z));
      }
    }
  }
  return z;
}

}  // namespace kincal
