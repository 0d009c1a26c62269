// Shared by the daemon's tests: scratch paths, the simulated robot's config and truth, and
// the checks of an estimate against the truth.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>

#include "daemon/frame_source.h"
#include "io/io_test_util.h"
#include "kincal/daemon/config.h"
#include "kincal/io/checkpoint.h"
#include "kincal/sim/scenario.h"
#include "source_dir.h"
#include "temp_path.h"

namespace kincal::daemon::test_util {

inline const std::string kConfigDir = ::kincal::testing::SourceDir() + "/config";

using ::kincal::testing::OpenLog;
using ::kincal::testing::TempPath;

// The shipped simulated robot, on memq://, as fast as possible (lossless).
inline DaemonConfig SimConfig(double duration_s) {
  DaemonConfig c = ReadDaemonConfig(kConfigDir + "/kincald_sim.yaml").value();
  c.lcm.url = "memq://";
  c.sim.speed = 0;
  c.sim.duration_s = duration_s;
  return c;
}

inline std::map<std::string, double> Truth(const DaemonConfig& c) {
  return LoadScenario(c.sim.scenario).value().truth;
}

// Normalised parameter error against the truth.
inline double Nnde(const Checkpoint& e, const std::map<std::string, double>& truth) {
  double s = 0;
  for (size_t i = 0; i < e.names.size(); ++i) {
    const double t = truth.at(e.names[i]);
    s += std::pow((e.values[i] - t) / t, 2);
  }
  return std::sqrt(s);
}

// Every parameter within 3 of its sigmas of the truth (a held one: exactly at it).
inline void ExpectWithin3Sigma(const Checkpoint& e, const std::map<std::string, double>& truth) {
  ASSERT_FALSE(e.names.empty());
  for (size_t i = 0; i < e.names.size(); ++i) {
    const double sigma = std::sqrt(e.covariance(static_cast<int>(i), static_cast<int>(i)));
    if (std::find(e.held.begin(), e.held.end(), e.names[i]) != e.held.end()) {
      EXPECT_EQ(e.values[i], truth.at(e.names[i])) << e.names[i] << " is held";
      continue;
    }
    EXPECT_LT(std::abs(e.values[i] - truth.at(e.names[i])), 3 * sigma)
        << e.names[i] << " = " << e.values[i] << " +- " << sigma << ", truth "
        << truth.at(e.names[i]);
  }
}

struct Counted {
  int frames = 0, controls = 0;
  int64_t last_utime = 0;
  bool in_order = true;
};

// Reads a started source to its end (or `max_frames`).
inline void Drain(FrameSource* s, Counted* c, int max_frames = 1 << 30) {
  Frame f;
  std::string error;
  while (c->frames < max_frames) {
    const SourceStatus st = s->Next(&f, 1000, &error);
    if (st == SourceStatus::kEnd) break;
    ASSERT_NE(st, SourceStatus::kError) << error;
    if (st != SourceStatus::kFrame) continue;
    c->in_order = c->in_order && f.utime > c->last_utime;
    c->last_utime = f.utime;
    ++c->frames;
  }
}

}  // namespace kincal::daemon::test_util
