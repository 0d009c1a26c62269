#include "analysis/units_check.h"

#include <cmath>
#include <sstream>

namespace kincal::analysis {
namespace {

// "987 times" or "1/57".
std::string Ratio(double r) {
  std::ostringstream out;
  out.precision(3);
  if (r >= 1.0) {
    out << r << " times";
  } else {
    out << "1/" << 1.0 / r << " of";
  }
  return out.str();
}

}  // namespace

std::vector<std::string> UnitWarnings(const KinematicModel& model, const Eigen::VectorXd& p) {
  std::vector<std::string> out;
  const auto& params = model.params();
  for (size_t i = 0; i < params.size() && static_cast<Eigen::Index>(i) < p.size(); ++i) {
    const ParamInfo& info = params[i];
    const double v = p[static_cast<Eigen::Index>(i)];
    if (!(info.default_value > 0.0) || !std::isfinite(v)) continue;
    const double r = std::abs(v) / info.default_value;
    const bool length = info.unit == "m", scale = info.unit == "1";
    const double limit = length ? kImplausibleLengthRatio : kImplausibleScaleRatio;
    if ((!length && !scale) || (r <= limit && r >= 1.0 / limit)) continue;
    std::ostringstream w;
    w.precision(4);
    w << "'" << info.name << "' came out " << v << (length ? " m" : "") << ", " << Ratio(r)
      << " its generic value (" << info.default_value << (length ? " m" : "") << "): ";
    if (length && r > 1.0) {
      w << "are the poses in millimetres or centimetres? kincal reads metres";
    } else if (length) {
      w << "are the controls in degrees (per second)? kincal reads radians, rad/s and m/s";
    } else {
      w << "the poses and the commands disagree on units (kincal reads metres and m/s, "
           "radians and rad/s)";
    }
    out.push_back(w.str());
  }
  return out;
}

}  // namespace kincal::analysis
