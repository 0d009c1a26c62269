// Checks on raw LCM messages: real messages pass, length fields that claim more than the
// bytes received (or more than kincal's limits) are rejected with a reason, before
// lcm-gen's decoder could allocate for them.
#include "kincal/io/lcm_guard.h"

#include <gtest/gtest.h>

#include <cstring>
#include <kincal/controls_t.hpp>
#include <kincal/frame_t.hpp>
#include <kincal/params_t.hpp>
#include <vector>

namespace kincal {
namespace {

template <typename Msg>
std::vector<uint8_t> EncodeGuardMessage(const Msg& m) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

controls_t Controls(int n) {
  controls_t m{};
  m.schema_version = 1;
  m.model = "diffdrive";
  m.num_controls = n;
  for (int i = 0; i < n; ++i) {
    m.names.push_back("c" + std::to_string(i));
    m.values.push_back(0.5 * i);
  }
  return m;
}

// Offset of controls_t's num_controls: fingerprint, schema, two stamps, the model string.
size_t NumControlsOffset(const controls_t& m) { return 8 + 4 + 8 + 8 + 4 + m.model.size() + 1; }

void PutInt32(std::vector<uint8_t>* buf, size_t at, int32_t v) {
  for (int k = 0; k < 4; ++k)
    (*buf)[at + static_cast<size_t>(k)] = uint8_t(uint32_t(v) >> (24 - 8 * k));
}

TEST(LcmGuard, RealControlsPassAndHostileCountsAreRejected) {
  const controls_t m = Controls(2);
  std::vector<uint8_t> buf = EncodeGuardMessage(m);
  std::string why;
  EXPECT_TRUE(PlausibleControls(buf.data(), buf.size(), 8, &why)) << why;
  // More entries than the model allows.
  const controls_t many = Controls(9);
  const auto big = EncodeGuardMessage(many);
  EXPECT_FALSE(PlausibleControls(big.data(), big.size(), 8, &why));
  EXPECT_FALSE(why.empty());
  // A count of 2^31 - 1 in a message of a few dozen bytes.
  PutInt32(&buf, NumControlsOffset(m), 0x7fffffff);
  why.clear();
  EXPECT_FALSE(PlausibleControls(buf.data(), buf.size(), 8, &why));
  EXPECT_FALSE(why.empty());
  // Cut short.
  EXPECT_FALSE(PlausibleControls(buf.data(), 10, 8, &why));
}

TEST(LcmGuard, FrameSizeMustEqualTheBytesThatRemain) {
  frame_t f{};
  f.schema_version = 1;
  f.width = 4;
  f.height = 2;
  f.stride = 4;
  f.pixel_format = "GREY";
  f.size = 8;
  f.data.assign(8, 7);
  std::vector<uint8_t> buf = EncodeGuardMessage(f);
  std::string why;
  EXPECT_TRUE(PlausibleFrame(buf.data(), buf.size(), &why)) << why;
  EXPECT_FALSE(PlausibleFrame(buf.data(), buf.size() - 1, &why));
  EXPECT_FALSE(why.empty());
}

TEST(LcmGuard, ParamsWithinTheLimitPass) {
  params_t p{};
  p.schema_version = 1;
  p.model = "unicycle";
  p.estimator = "dd2";
  p.num_params = 2;
  p.names = {"k_v", "k_omega"};
  p.units = {"1", "1"};
  p.values = {1.0, 1.0};
  p.sigmas = {0.1, 0.1};
  p.covariance = {{0.01, 0.0}, {0.0, 0.01}};
  std::vector<uint8_t> buf = EncodeGuardMessage(p);
  std::string why;
  EXPECT_TRUE(PlausibleParams(buf.data(), buf.size(), 64, &why)) << why;
  EXPECT_FALSE(PlausibleParams(buf.data(), buf.size(), 1, &why));
  EXPECT_FALSE(PlausibleParams(buf.data(), buf.size() / 2, 64, &why));
}

}  // namespace
}  // namespace kincal
