// ConflictingRepeats (src/io/repeated_times.cc): repeated times with other values are
// counted and the first is named; a repeat with the same values, and a stream without
// repeats, say nothing.
#include "io/repeated_times.h"

#include <gtest/gtest.h>

#include <vector>

namespace kincal {
namespace {

TEST(ConflictingRepeats, NamesTheFirstAndCountsThem) {
  const std::vector<std::vector<double>> v = {{0, 0}, {1, 0}, {1, 0}, {2, 0}, {2.5, 0}, {3, 1}};
  const std::vector<TimeNs> t = {0,           100'000'000, 100'000'000,
                                 200'000'000, 200'000'000, 200'000'000};
  ConflictingRepeats c("p.csv", "line");
  for (size_t i = 0; i < v.size(); ++i) c.Add(t[i], v[i], static_cast<int64_t>(i + 2));
  EXPECT_EQ(c.count(), 2);  // line 6 (against 5) and line 7 (against 6); line 4 is a copy
  EXPECT_EQ(c.Warning(),
            "p.csv: line 6 repeats the time of line 5 (0.2 s from the start) with other values "
            "(2.5,0 against 2,0); the later is kept, as at every repeated time, and 2 repeated "
            "times differ so: two sources in one file, or times written coarser than the "
            "samples?");
}

TEST(ConflictingRepeats, CopiesAndDistinctTimesSayNothing) {
  const std::vector<double> a = {1, 2}, b = {1, 2}, c = {5, 6};
  ConflictingRepeats r("log.lcm", "event");
  r.Add(0, a, 1);
  r.Add(0, b, 2);  // the same values again: a copy, counted only as a repeated time
  r.Add(1, c, 3);
  EXPECT_EQ(r.count(), 0);
  EXPECT_EQ(r.Warning(), "");
}

}  // namespace
}  // namespace kincal
