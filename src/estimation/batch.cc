#include "kincal/estimation/batch.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "kincal/angles.h"
#include "kincal/estimation/ceres_logging.h"

namespace kincal {
namespace {

// Residuals of one shooting segment: 3 per measurement, whitened.
// Parameter blocks: [0] reference pose at the segment start (x, y, theta),
//                   [1] all System parameters.
class SegmentCost final : public ceres::CostFunction {
 public:
  SegmentCost(const System& sys, const ControlSignal& u, double t0_s, double warmup_s,
              std::vector<const PoseMeasurement*> meas)
      : sys_(sys), u_(u), t0_(t0_s), warmup_(warmup_s), meas_(std::move(meas)) {
    set_num_residuals(3 * static_cast<int>(meas_.size()));
    mutable_parameter_block_sizes()->push_back(kPoseDim);
    mutable_parameter_block_sizes()->push_back(sys_.num_params());
    for (const auto* m : meas_) {
      Eigen::LLT<Eigen::Matrix3d> llt(m->R);  // positive definite: CheckMeasurements
      // Whitening W with W^T W = R^-1: W = L^-1.
      whiten_.push_back(llt.matrixL().solve(Eigen::Matrix3d::Identity()));
      times_.push_back(u_.ToSeconds(m->t_ns));
    }
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const bool want_jac =
        jacobians != nullptr && (jacobians[0] != nullptr || jacobians[1] != nullptr);
    if (!want_jac) return Run<double>(parameters, residuals, nullptr);
    if (3 + sys_.num_params() <= kBatchJetSize) return Run<BJet>(parameters, residuals, jacobians);
    return Run<Jet>(parameters, residuals, jacobians);
  }

 private:
  template <typename T>
  bool Run(double const* const* parameters, double* residuals, double** jacobians) const {
    const int np = sys_.num_params();
    T x[kMaxState];
    for (int i = 0; i < kPoseDim; ++i) x[i] = Seed<T>(parameters[0][i], i);
    for (int i = 0; i < np; ++i) x[3 + i] = Seed<T>(parameters[1][i], 3 + i);
    for (int i = sys_.state_offset(); i < sys_.state_dim(); ++i) x[i] = T(0.0);
    if (sys_.num_states() > 0 && warmup_ > 0.0) {
      // Warm the effect states up through the command history; the pose stays (the
      // segment's start pose is the free parameter block).
      sys_.InitEffectStates(x, u_, t0_ - warmup_);
      sys_.AdvanceEffectStates(x, t0_ - warmup_, t0_, u_);
    } else {
      sys_.InitEffectStates(x, u_, t0_);
    }
    double t = t0_;
    for (size_t k = 0; k < meas_.size(); ++k) {
      sys_.Propagate(x, x, t, times_[k], u_, static_cast<const T*>(nullptr));
      t = std::max(t, times_[k]);
      T z[3];
      sys_.Measure(x, z);
      const Eigen::Vector3d& zm = meas_[k]->z;
      T e[3] = {T(zm.x()) - z[0], T(zm.y()) - z[1], T(zm.z()) - z[2]};
      e[2] = WrapT(e[2]);
      for (int r = 0; r < kPoseDim; ++r) {
        const T res = whiten_[k](r, 0) * e[0] + whiten_[k](r, 1) * e[1] + whiten_[k](r, 2) * e[2];
        const int row = 3 * static_cast<int>(k) + r;
        residuals[row] = ScalarOf(res);
        if constexpr (!std::is_same_v<T, double>) {
          if (jacobians[0] != nullptr) {
            for (int j = 0; j < kPoseDim; ++j) jacobians[0][row * kPoseDim + j] = res.v[j];
          }
          if (jacobians[1] != nullptr) {
            for (int j = 0; j < np; ++j) jacobians[1][row * np + j] = res.v[3 + j];
          }
        }
      }
    }
    return true;
  }

  template <typename T>
  static T Seed(double value, int slot) {
    if constexpr (!std::is_same_v<T, double>) {
      return T(value, slot);
    } else {
      (void)slot;
      return value;
    }
  }
  static double WrapT(double a) { return WrapAngle(a); }
  static Jet WrapT(const Jet& a) { return WrapAngleJet(a); }
  static BJet WrapT(const BJet& a) { return WrapAngleJet(a); }

  const System& sys_;
  const ControlSignal& u_;
  double t0_;
  double warmup_;
  std::vector<const PoseMeasurement*> meas_;
  std::vector<Eigen::Matrix3d> whiten_;
  std::vector<double> times_;
};

// r = L^-1 (p - mean), with L L^T the prior covariance.
class PriorCost final : public ceres::CostFunction {
 public:
  explicit PriorCost(const ParamPrior& prior) : mean_(prior.mean) {
    const int n = static_cast<int>(mean_.size());
    set_num_residuals(n);
    mutable_parameter_block_sizes()->push_back(n);
    Eigen::LLT<Eigen::MatrixXd> llt(prior.covariance);  // positive definite: IsValid
    whiten_ = llt.matrixL().solve(Eigen::MatrixXd::Identity(n, n));
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int n = static_cast<int>(mean_.size());
    Eigen::Map<const Eigen::VectorXd> p(parameters[0], n);
    Eigen::Map<Eigen::VectorXd>(residuals, n) = whiten_ * (p - mean_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          jacobians[0], n, n) = whiten_;
    }
    return true;
  }

 private:
  Eigen::VectorXd mean_;
  Eigen::MatrixXd whiten_;
};

struct Problem {
  ceres::Problem problem;
  std::vector<SegmentCost*> costs;
  std::vector<std::array<double, kPoseDim>> starts;
  std::vector<TimeNs> start_ns;
  Eigen::VectorXd params;
};

// The measurements a fit can use: some, in segments of non-decreasing id, times not going
// backwards within a segment, each covariance positive definite.
Status CheckMeasurements(std::span<const PoseMeasurement> meas) {
  if (meas.empty()) return Status::Error("no pose measurements");
  for (size_t k = 0; k < meas.size(); ++k) {
    const auto& m = meas[k];
    if (k > 0 && m.segment < meas[k - 1].segment) {
      return Status::Error("segment ids must be non-decreasing (measurement " + std::to_string(k) +
                           ")");
    }
    if (k > 0 && m.segment == meas[k - 1].segment && m.t_ns < meas[k - 1].t_ns) {
      return Status::Error("measurement times go backwards within segment " +
                           std::to_string(m.segment));
    }
    if (!m.R.allFinite() || Eigen::LLT<Eigen::Matrix3d>(m.R).info() != Eigen::Success) {
      return Status::Error("measurement " + std::to_string(k) +
                           ": covariance is not positive definite");
    }
  }
  return {};
}

bool IsFixed(const BatchOptions& options, int i) {
  return std::find(options.fixed.begin(), options.fixed.end(), i) != options.fixed.end();
}

// Builds the problem from measurements that passed CheckMeasurements.
void Build(const System& sys, const ControlSignal& controls, std::span<const PoseMeasurement> meas,
           const BatchOptions& options, Problem* pb) {
  // Group by segment, in order of appearance.
  std::vector<std::vector<const PoseMeasurement*>> groups;
  int current = meas.front().segment - 1;
  for (const auto& m : meas) {
    if (groups.empty() || m.segment != current) {
      groups.emplace_back();
      current = m.segment;
    }
    groups.back().push_back(&m);
  }
  pb->starts.resize(groups.size());
  pb->start_ns.resize(groups.size());
  ceres::LossFunction* loss =
      options.huber_scale > 0.0 ? new ceres::HuberLoss(options.huber_scale) : nullptr;
  for (size_t g = 0; g < groups.size(); ++g) {
    pb->start_ns[g] = groups[g].front()->t_ns;
    const double t0 = controls.ToSeconds(pb->start_ns[g]);
    double warmup = options.warmup_s;
    const auto run =
        std::upper_bound(options.run_starts.begin(), options.run_starts.end(), pb->start_ns[g]);
    if (run != options.run_starts.begin()) {
      warmup = std::min(warmup, std::max(0.0, t0 - controls.ToSeconds(*std::prev(run))));
    }
    auto* cost = new SegmentCost(sys, controls, t0, warmup, groups[g]);
    pb->costs.push_back(cost);
    pb->problem.AddResidualBlock(cost, loss, pb->starts[g].data(), pb->params.data());
  }
  if (options.prior)
    pb->problem.AddResidualBlock(new PriorCost(*options.prior), nullptr, pb->params.data());
  if (!options.fixed.empty()) {
    pb->problem.SetManifold(pb->params.data(),
                            new ceres::SubsetManifold(sys.num_params(), options.fixed));
  }
  // Physical bounds (lengths > 0, time constants >= 0) of the free parameters.
  for (int i = 0; i < sys.num_params(); ++i) {
    const double lo = sys.params()[static_cast<size_t>(i)].min_value;
    if (std::isfinite(lo) && !IsFixed(options, i)) {
      pb->params[i] = std::max(pb->params[i], lo);
      pb->problem.SetParameterLowerBound(pb->params.data(), i, lo);
    }
  }
}

bool ComputeCovariance(const Problem& cpb, int np, Eigen::MatrixXd* cov) {
  auto& pb = const_cast<Problem&>(cpb);
  ceres::Covariance::Options copt;
  const int total = 3 * static_cast<int>(pb.starts.size()) + np;
  copt.algorithm_type = total <= 1500 ? ceres::DENSE_SVD : ceres::SPARSE_QR;
  ceres::Covariance covariance(copt);
  std::vector<std::pair<const double*, const double*>> blocks = {
      {pb.params.data(), pb.params.data()}};
  if (!covariance.Compute(blocks, &pb.problem)) return false;
  cov->resize(np, np);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> c(np, np);
  covariance.GetCovarianceBlock(pb.params.data(), pb.params.data(), c.data());
  *cov = c;
  return cov->allFinite();
}

// Per-segment Jacobians with the start pose profiled out: H = sum H_s, g_s the profiled
// gradient of segment s. Model covariance H^-1, cluster-robust H^-1 (sum g g^T) H^-1.
void ProfiledCovariance(Problem& pb, int np, const BatchOptions& options, BatchResult* r) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(np, np);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(np, np);
  int rows_total = 0;
  double sum_sq = 0.0, sum_lag = 0.0;
  for (size_t g = 0; g < pb.costs.size(); ++g) {
    SegmentCost* c = pb.costs[g];
    const int m = c->num_residuals();
    rows_total += m;
    Eigen::VectorXd res(m);
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Jx(m, 3), Jp(m, np);
    const double* params[2] = {pb.starts[g].data(), pb.params.data()};
    double* jac[2] = {Jx.data(), Jp.data()};
    c->Evaluate(params, res.data(), jac);
    for (int i : options.fixed) Jp.col(i).setZero();  // held: no information, no sigma
    sum_sq += res.squaredNorm();
    for (int i = 3; i < m; ++i) sum_lag += res[i] * res[i - 3];
    const Eigen::Matrix3d A = Jx.transpose() * Jx;
    Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
    const Eigen::MatrixXd B = Jx.transpose() * Jp;
    const Eigen::MatrixXd AiB = ldlt.solve(B);
    H += Jp.transpose() * Jp - B.transpose() * AiB;
    const Eigen::VectorXd grad = Jp.transpose() * res - AiB.transpose() * (Jx.transpose() * res);
    M += grad * grad.transpose();
  }
  if (options.prior) {
    H += options.prior->covariance.inverse();
  }
  r->information = H;
  r->num_segments = static_cast<int>(pb.costs.size());
  r->num_residuals = rows_total;
  const double rho = sum_sq > 0.0 ? std::clamp(sum_lag / sum_sq, 0.0, 0.999) : 0.0;
  r->residual_lag1 = rho;
  r->effective_residuals =
      std::max(static_cast<double>(r->num_segments), rows_total * (1.0 - rho) / (1.0 + rho));
  // Invert in scaled coordinates (unit diagonal): parameters of very different units
  // (ticks, metres per tick) must not look singular. A fixed parameter's row and column
  // are zero: it is inverted as a unit and its variance set to zero after.
  Eigen::MatrixXd Hf = H;
  for (int i : options.fixed) {
    Hf.row(i).setZero();
    Hf.col(i).setZero();
    Hf(i, i) = 1.0;
  }
  const Eigen::VectorXd d = Hf.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd Hs = d.asDiagonal() * Hf * d.asDiagonal();
  Eigen::FullPivLU<Eigen::MatrixXd> lu(Hs);
  if (!lu.isInvertible() || lu.rcond() < 1e-12) return;
  Eigen::MatrixXd Hi = d.asDiagonal() * lu.inverse() * d.asDiagonal();
  for (int i : options.fixed) Hi(i, i) = 0.0;
  r->profiled_covariance = 0.5 * (Hi + Hi.transpose());
  const double G = static_cast<double>(pb.costs.size());
  const double small_sample = G > 1.0 ? G / (G - 1.0) : 1.0;
  const Eigen::MatrixXd R = Hi * M * Hi * small_sample;
  r->robust_covariance = 0.5 * (R + R.transpose());
}

}  // namespace

bool BatchOptions::IsValid(const System& sys, std::string* error) const {
  if (max_iterations < 1) {
    *error = "max_iterations must be >= 1";
    return false;
  }
  if (!(warmup_s >= 0.0)) {
    *error = "warmup_s must be >= 0";
    return false;
  }
  if (huber_scale < 0.0) {
    *error = "huber_scale must be >= 0";
    return false;
  }
  std::vector<int> held = fixed;
  std::sort(held.begin(), held.end());
  if (std::adjacent_find(held.begin(), held.end()) != held.end() ||
      (!held.empty() && (held.front() < 0 || held.back() >= sys.num_params()))) {
    *error = "fixed parameters must be distinct indices below " + std::to_string(sys.num_params());
    return false;
  }
  if (!held.empty() && held.size() == static_cast<size_t>(sys.num_params())) {
    *error = "every parameter is fixed: nothing to fit";
    return false;
  }
  if (prior) {
    const int np = sys.num_params();
    if (prior->mean.size() != np || prior->covariance.rows() != np ||
        prior->covariance.cols() != np) {
      *error = "prior must have " + std::to_string(np) + " parameters";
      return false;
    }
    if (!prior->covariance.allFinite() ||
        Eigen::LLT<Eigen::MatrixXd>(prior->covariance).info() != Eigen::Success) {
      *error = "prior covariance is not positive definite";
      return false;
    }
  }
  return true;
}

BatchResult FitBatch(const System& sys, const ControlSignal& controls,
                     std::span<const PoseMeasurement> meas, const Eigen::VectorXd& params0,
                     const BatchOptions& options) {
  RouteCeresLogging();
  std::string error;
  BatchResult invalid;
  if (!options.IsValid(sys, &error)) {
    invalid.status = Status::Error("batch: " + error);
    return invalid;
  }
  if (params0.size() != sys.num_params() || !params0.allFinite()) {
    invalid.status = Status::Error("batch: the initial guess has " +
                                   std::to_string(params0.size()) + " parameters, the system " +
                                   std::to_string(sys.num_params()) + ", all finite expected");
    return invalid;
  }
  if (Status s = CheckMeasurements(meas); !s.ok()) {
    invalid.status = Status::Error("batch: " + s.message());
    return invalid;
  }
  Problem pb;
  pb.params = params0;
  Build(sys, controls, meas, options, &pb);
  // Start poses from the first measurement of each segment at the initial parameters.
  {
    size_t g = 0;
    int seg = meas.front().segment;
    bool first = true;
    for (const auto& m : meas) {
      if (!first && m.segment != seg) ++g;
      if (first || m.segment != seg) {
        StateVec x = StateVec::Zero(sys.state_dim());
        x.segment(3, sys.num_params()) = params0;
        sys.SetPoseFromMeasurement(m.z.data(), x.data());
        pb.starts[g] = {x[0], x[1], x[2]};
        seg = m.segment;
        first = false;
      }
    }
  }
  ceres::Solver::Options sopt;
  sopt.linear_solver_type = ceres::DENSE_SCHUR;
  sopt.max_num_iterations = options.max_iterations;
  sopt.num_threads = options.num_threads;
  sopt.function_tolerance = 1e-12;
  sopt.parameter_tolerance = 1e-12;
  sopt.gradient_tolerance = 1e-14;
  sopt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(sopt, &pb.problem, &summary);

  BatchResult r;
  r.params = pb.params;
  r.initial_cost = summary.initial_cost;
  r.final_cost = summary.final_cost;
  r.iterations = static_cast<int>(summary.iterations.size());
  r.converged = summary.termination_type == ceres::CONVERGENCE;
  r.message = summary.BriefReport();
  for (size_t g = 0; g < pb.starts.size(); ++g) {
    r.segment_start.emplace_back(pb.starts[g][0], pb.starts[g][1], pb.starts[g][2]);
  }
  r.segment_start_ns = pb.start_ns;
  if (options.compute_covariance) {
    r.covariance_ok = ComputeCovariance(pb, sys.num_params(), &r.covariance);
  }
  if (options.profiled_covariance) ProfiledCovariance(pb, sys.num_params(), options, &r);
  return r;
}

BatchResult BoundAt(const System& sys, const ControlSignal& controls,
                    std::span<const PoseMeasurement> meas, const Eigen::VectorXd& params_true,
                    const std::vector<Eigen::Vector3d>& segment_start_true,
                    const BatchOptions& options) {
  RouteCeresLogging();
  std::string error;
  BatchResult invalid;
  if (!options.IsValid(sys, &error)) {
    invalid.status = Status::Error("bound: " + error);
    return invalid;
  }
  if (Status s = CheckMeasurements(meas); !s.ok()) {
    invalid.status = Status::Error("bound: " + s.message());
    return invalid;
  }
  Problem pb;
  pb.params = params_true;
  Build(sys, controls, meas, options, &pb);
  if (segment_start_true.size() != pb.starts.size()) {
    invalid.status =
        Status::Error("bound: " + std::to_string(segment_start_true.size()) + " start poses for " +
                      std::to_string(pb.starts.size()) + " segments");
    return invalid;
  }
  for (size_t g = 0; g < pb.starts.size(); ++g) {
    pb.starts[g] = {segment_start_true[g].x(), segment_start_true[g].y(),
                    segment_start_true[g].z()};
  }
  BatchResult r;
  r.params = params_true;
  r.segment_start = segment_start_true;
  r.segment_start_ns = pb.start_ns;
  r.covariance_ok = ComputeCovariance(pb, sys.num_params(), &r.covariance);
  return r;
}

}  // namespace kincal
