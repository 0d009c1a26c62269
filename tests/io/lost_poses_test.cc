// LostPoses (src/io/lost_poses.cc): which fields are missing, and the warning that counts
// the rows without a pose and names the longest stretch they left.
#include "io/lost_poses.h"

#include <gtest/gtest.h>

namespace kincal {
namespace {

TEST(LostPoses, EmptyAndNaNFieldsAreMissingAndNothingElse) {
  for (const char* missing : {"", "nan", "NaN", "NAN", "-nan", "+nan"})
    EXPECT_TRUE(IsMissingValue(missing)) << missing;
  for (const char* present : {"0", "-", "nan1", "inf", "n/a", "0.0", "nana"})
    EXPECT_FALSE(IsMissingValue(present)) << present;
}

TEST(LostPoses, CountsTheRowsAndNamesTheLongestStretch) {
  LostPoses lost;
  EXPECT_EQ(lost.Warning("p.csv"), "");
  lost.Kept(0.0, 2);
  lost.Lost();
  lost.Kept(0.2, 4);  // 0.2 s without a pose
  lost.Kept(0.3, 5);
  lost.Lost();
  lost.Lost();
  lost.Lost();
  lost.Kept(0.8, 9);  // 0.5 s, the longest
  lost.Lost();        // at the end: no pose after it
  EXPECT_EQ(lost.rows(), 5);
  EXPECT_EQ(lost.Warning("p.csv"),
            "p.csv: 5 rows have no pose (every pose field empty or NaN: the tracker lost the "
            "robot) and were skipped; the longest stretch without a pose is 0.5 s, from line 5 "
            "to line 9");
  LostPoses first;
  first.Lost();  // before any pose: no stretch between poses to name
  first.Kept(1.0, 3);
  EXPECT_EQ(first.Warning("p.csv"),
            "p.csv: 1 row has no pose (every pose field empty or NaN: the tracker lost the robot) "
            "and was skipped");
}

}  // namespace
}  // namespace kincal
