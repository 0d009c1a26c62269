// What to drive next: with only the lever arm left uncertain the advice is to turn (a
// lever arm shows only in rotation); with only the wheel radii left, to drive; the advised
// motion shrinks the worst parameter's sigma; the time to the targets is the greedy plan's.
#include "kincal/plan/advice.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kincal {
namespace {

struct Reference {
  System sys = MakeSystem("diffdrive", {"actuator_lag", "time_offset", "lever_arm"}).value();
  Eigen::VectorXd p = (Eigen::VectorXd(8) << 0.03, 0.03, 0.3, 0.1, 0.0, 0.0, 0.0, 0.0).finished();
  PlanOptions o;
  Reference() {
    o.max_abs = {20.0, 20.0};
    o.max_accel = {40.0, 40.0};
    o.targets = (Eigen::VectorXd(8) << 3e-5, 3e-5, 3e-4, 3e-3, 3e-3, 2e-3, 2e-3, 0.0).finished();
    o.care = {0, 1, 2, 3, 4, 5, 6};
  }
  // Every parameter known to a tenth of its target, except `loose` (at 50 x).
  Eigen::MatrixXd Cov(const std::vector<int>& loose) const {
    Eigen::VectorXd s = 0.1 * o.targets;
    s[7] = 1e-4;
    for (int i : loose) s[i] = 50.0 * o.targets[i];
    return s.cwiseAbs2().asDiagonal();
  }
};

TEST(Advice, AnUnknownLeverArmCallsForTurning) {
  const Reference r;
  Advice a;
  ASSERT_TRUE(Advise(r.sys, r.p, r.Cov({5, 6}), r.o, 3.0, &a).ok());
  std::cout << r.sys.params()[static_cast<size_t>(a.worst)].name << ": " << a.motion << ", "
            << a.time_to_target_s << " s to the targets\n";
  EXPECT_TRUE(a.worst == 5 || a.worst == 6);
  EXPECT_GT(std::abs(a.twist.y()), 1.0);  // rad/s: turning hard
  EXPECT_LT(a.sigma_after[a.worst], 0.2 * a.sigma_now[a.worst]);
  EXPECT_NE(a.motion.find("turn"), std::string::npos) << a.motion;
  EXPECT_GT(a.time_to_target_s, 0.0);
  EXPECT_LT(a.time_to_target_s, 60.0);
}

TEST(Advice, UnknownRadiiCallForDriving) {
  const Reference r;
  Advice a;
  ASSERT_TRUE(Advise(r.sys, r.p, r.Cov({0, 1}), r.o, 3.0, &a).ok());
  std::cout << r.sys.params()[static_cast<size_t>(a.worst)].name << ": " << a.motion << "\n";
  EXPECT_TRUE(a.worst == 0 || a.worst == 1);
  EXPECT_GT(std::abs(a.twist.x()), 0.3);  // m/s
  EXPECT_LT(a.sigma_after[a.worst], 0.2 * a.sigma_now[a.worst]);
}

TEST(Advice, WithoutTargetsNoTimeAndBadOptionsAreStatuses) {
  Reference r;
  const Eigen::MatrixXd cov = r.Cov({3});
  r.o.targets = Eigen::VectorXd();
  r.o.care.clear();
  Advice a;
  ASSERT_TRUE(Advise(r.sys, r.p, cov, r.o, 2.0, &a).ok());
  EXPECT_TRUE(std::isnan(a.time_to_target_s));
  EXPECT_FALSE(Advise(r.sys, r.p, cov, r.o, 0.0, &a).ok());
  r.o.max_abs = {1.0};
  const Status s = Advise(r.sys, r.p, cov, r.o, 2.0, &a);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("omega_r"), std::string::npos) << s.message();
}

// The advised motion's path (drawn by kincal view) is the target's pose along it from where
// it starts: for a bare diff drive commanded without slewing, the constant twist's arc,
// written here in closed form (x = v/w sin wt, y = v/w (1 - cos wt)), every 0.1 s.
TEST(Advice, ThePathIsTheArcTheMotionDrivesFromTheTargetsStart) {
  const System sys = MakeSystem("diffdrive", {}).value();
  const Eigen::Vector3d p(0.03, 0.032, 0.3);
  PlanOptions o;
  o.max_abs = {20.0, 20.0};
  o.max_accel = {1e9, 1e9};  // no slewing: the twist is constant from the start
  o.targets = Eigen::Vector3d(3e-5, 3e-5, 3e-4);
  o.care = {0, 1, 2};
  const Eigen::MatrixXd cov = Eigen::Vector3d(1e-3, 1e-3, 1e-2).cwiseAbs2().asDiagonal();
  Advice a;
  ASSERT_TRUE(Advise(sys, p, cov, o, 2.5, &a).ok());
  ASSERT_EQ(a.path.size(), 26u);
  const double v = 0.5 * (p[0] * a.controls[0] + p[1] * a.controls[1]);
  const double w = (p[1] * a.controls[1] - p[0] * a.controls[0]) / p[2];
  std::cout << a.motion << ": v " << v << " m/s, w " << w << " rad/s\n";
  EXPECT_GT(std::hypot(v, w), 0.1);
  for (size_t k = 0; k < a.path.size(); ++k) {
    const double t = 0.1 * static_cast<double>(k);
    const double x = std::abs(w) < 1e-9 ? v * t : v / w * std::sin(w * t);
    const double y = std::abs(w) < 1e-9 ? 0.0 : v / w * (1.0 - std::cos(w * t));
    EXPECT_NEAR(a.path[k].x(), x, 1e-6) << "t " << t;
    EXPECT_NEAR(a.path[k].y(), y, 1e-6) << "t " << t;
    EXPECT_NEAR(std::remainder(a.path[k].z() - w * t, 2 * M_PI), 0.0, 1e-6) << "t " << t;
  }
}

TEST(Advice, MotionsInWords) {
  EXPECT_EQ(DescribeMotion({0.3, 0.0}, 3.0), "drive forward at 0.30 m/s for 3 s");
  EXPECT_EQ(DescribeMotion({0.0, -1.2}, 2.0), "turn in place right at 1.20 rad/s for 2 s");
  EXPECT_EQ(DescribeMotion({-0.3, 0.5}, 3.0),
            "drive backward at 0.30 m/s turning left at 0.50 rad/s (radius 0.60 m) for 3 s");
  EXPECT_EQ(DescribeMotion({0.0, 0.0}, 1.0), "stand still for 1 s");
}

}  // namespace
}  // namespace kincal
