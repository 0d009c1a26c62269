// UnitWarnings (src/analysis/units_check.cc): fitted parameters that betray the inputs'
// units, named with the likely mistake; plausible robots, large and small, say nothing.
#include "analysis/units_check.h"

#include <gtest/gtest.h>

namespace kincal::analysis {
namespace {

TEST(UnitsCheck, MillimetrePosesAreNamed) {
  const auto diffdrive = MakeModel("diffdrive").value();
  // Issue 34's sweep: a recording's poses in millimetres fitted r_l 31 m, d 148 m, exit 0.
  const auto w = UnitWarnings(*diffdrive, Eigen::Vector3d(31.0, 31.31, 148.0));
  ASSERT_EQ(w.size(), 3u);
  EXPECT_EQ(w[0],
            "'r_l' came out 31 m, 1.03e+03 times its generic value (0.03 m): are the poses in "
            "millimetres or centimetres? kincal reads metres");
  EXPECT_NE(w[2].find("'d' came out 148 m, 987 times"), std::string::npos) << w[2];
  // Controls in degrees per second: the wheels come out 57 times too small.
  const auto deg = UnitWarnings(*diffdrive, Eigen::Vector3d(0.0005, 0.0005, 0.15));
  ASSERT_EQ(deg.size(), 2u);
  EXPECT_NE(deg[0].find("1/60 of its generic value"), std::string::npos) << deg[0];
  EXPECT_NE(deg[0].find("degrees"), std::string::npos) << deg[0];
  const auto unicycle = MakeModel("unicycle").value();
  const auto k = UnitWarnings(*unicycle, Eigen::Vector2d(1000.0, 1.02));
  ASSERT_EQ(k.size(), 1u);
  EXPECT_NE(k[0].find("'k_v' came out 1000, 1e+03 times its generic value (1): the poses and"),
            std::string::npos)
      << k[0];
}

TEST(UnitsCheck, RealRobotsSayNothing) {
  const auto diffdrive = MakeModel("diffdrive").value();
  // A TurtleBot 2 (3.5 cm wheels, 23 cm track), a Husky (16.5 cm, 55 cm), a warehouse
  // robot (10 cm, 1.2 m).
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(0.035, 0.035, 0.23), Eigen::Vector3d(0.165, 0.165, 0.55),
        Eigen::Vector3d(0.1, 0.1, 1.2)}) {
    EXPECT_TRUE(UnitWarnings(*diffdrive, p).empty()) << p.transpose();
  }
  // A full-size car's wheelbase (2.9 m) and a model car's slipping speed (k_v 0.7); a
  // steering offset (no generic size) is never judged.
  const auto bicycle = MakeModel("bicycle").value();
  Eigen::VectorXd car = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(bicycle->params().size()));
  for (size_t i = 0; i < bicycle->params().size(); ++i) {
    const auto& info = bicycle->params()[i];
    car[static_cast<Eigen::Index>(i)] = info.name == "wheelbase" ? 2.9
                                        : info.name == "k_v"     ? 0.7
                                                                 : info.default_value + 0.3;
  }
  EXPECT_TRUE(UnitWarnings(*bicycle, car).empty()) << car.transpose();
}

}  // namespace
}  // namespace kincal::analysis
