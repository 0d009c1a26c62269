// Control shaping shared by the planner and the usual motions: channels that slew at
// their acceleration limits, and the controls that give a wanted body twist.
#pragma once

#include <Eigen/Core>

#include "kincal/control_signal.h"
#include "kincal/plan/planner.h"
#include "kincal/system.h"

namespace kincal::plan_internal {

using Values = ControlSignal::Values;

// Appends samples every 1 / control_rate_hz from t0_s (inclusive) to t1_s (exclusive),
// the channels moving from *u towards `to` together (a straight ramp in control space, as
// fast as the slowest channel's acceleration limit allows); *u ends at the last value
// appended. Times are seconds on the signal's origin.
void AppendSlewed(ControlSignal* signal, double t0_s, double t1_s, const Values& to,
                  const PlanOptions& o, Values* u);

// A sample of zeros at t_s: the robot stopped.
void AppendRest(ControlSignal* signal, double t_s);

// Appends every sample of `from` before t_s (at its time; the two signals share an origin):
// a motion's start, to be driven on from its values at t_s.
void AppendSamplesBefore(ControlSignal* signal, const ControlSignal& from, double t_s);

// From t0_s, every channel from *u to zero at its acceleration limit (AppendSlewed), then a
// sample at rest; *u ends at zero. Returns the time of the rest sample.
double AppendStop(ControlSignal* signal, double t0_s, const PlanOptions& o, Values* u);

// AppendStop from t0_s, and a sample at rest at end_s when the stop is over before it: a
// motion at rest by end_s (its last sample there) when end_s leaves time for the stop.
void AppendStopAndRest(ControlSignal* signal, double t0_s, double end_s, const PlanOptions& o,
                       Values* u);

// The longest stop AppendStop can need: every channel from its limit to zero, rounded up to
// the control rate. A motion that must be at rest by duration_s stops driving this long
// before it.
double LongestStopSeconds(const PlanOptions& o, int num_channels);

// Controls within the limits whose body twist at `params` is (v, omega) as nearly as the
// limits allow (least squares, Levenberg-Marquardt from a forward guess). Returns whether
// the twist is reached to 1e-6 of its size.
bool TwistToControls(const System& sys, const Eigen::VectorXd& params, double v, double omega,
                     const PlanOptions& o, Values* u);

// Body twist (v, omega) of controls u at params.
Eigen::Vector2d TwistOf(const System& sys, const Eigen::VectorXd& params, const Values& u);

}  // namespace kincal::plan_internal
