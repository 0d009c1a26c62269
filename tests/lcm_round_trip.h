// A message's bytes on the wire, and the message encoded and decoded again: what a
// subscriber receives.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace kincal::testing {

template <typename Msg>
std::vector<uint8_t> Encoded(const Msg& m) {
  std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

template <typename Msg>
Msg RoundTrip(const Msg& m) {
  const std::vector<uint8_t> buf = Encoded(m);
  Msg out;
  EXPECT_EQ(out.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return out;
}

}  // namespace kincal::testing
