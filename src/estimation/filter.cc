#include "kincal/estimation/filter.h"

#include <stdexcept>

#include "filter_util.h"

namespace kincal {

void ProcessFunction::Jacobians(const StateVec& x, StateMat* F, StateNoiseMat* G) const {
  const int n = state_dim();
  const int nv = noise_dim();
  const uint32_t mask = internal::StateAngleMask(*this);
  F->resize(n, n);
  G->resize(n, nv);
  NoiseVec v = NoiseVec::Zero(nv);
  StateVec fp(n), fm(n);
  for (int j = 0; j < n; ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
    StateVec xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    Eval(xp.data(), v.data(), fp.data());
    Eval(xm.data(), v.data(), fm.data());
    F->col(j) = internal::WrappedDiff(fp, fm, mask) / (2.0 * h);
  }
  for (int j = 0; j < nv; ++j) {
    const double h = 1e-6;
    NoiseVec vp = v, vm = v;
    vp[j] += h;
    vm[j] -= h;
    Eval(x.data(), vp.data(), fp.data());
    Eval(x.data(), vm.data(), fm.data());
    G->col(j) = internal::WrappedDiff(fp, fm, mask) / (2.0 * h);
  }
}

void MeasurementFunction::Jacobian(const StateVec& x, MeasStateMat* H) const {
  const int n = state_dim();
  const int m = meas_dim();
  const uint32_t mask = internal::MeasAngleMask(*this);
  H->resize(m, n);
  MeasVec zp(m), zm(m);
  for (int j = 0; j < n; ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
    StateVec xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    Eval(xp.data(), zp.data());
    Eval(xm.data(), zm.data());
    H->col(j) = internal::WrappedDiff(zp, zm, mask) / (2.0 * h);
  }
}

StatusOr<std::unique_ptr<Filter>> MakeFilter(std::string_view name) {
  auto f = FilterRegistry::Instance().Create(name);
  if (!f) {
    return Status::Error("unknown filter '" + std::string(name) +
                         "' (known: " + FilterRegistry::Instance().KnownList() + ")");
  }
  return f;
}

}  // namespace kincal
