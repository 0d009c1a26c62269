// Pose rows without a pose. A motion-capture export leaves a frame's fields empty (Vicon
// Nexus, OptiTrack Motive) or writes NaN (pandas, numpy) while the tracker has lost the
// robot. Such a row is no measurement: the poses CSV reader skips it, counts it, and says
// so with the longest stretch it left without poses. A row with some fields and not others
// is still an error naming the column.
#pragma once

#include <string>
#include <string_view>

namespace kincal {

// An empty field or a NaN ("nan", "NaN", "-nan", ...).
bool IsMissingValue(std::string_view field);

class LostPoses {
 public:
  // The next row, without a pose.
  void Lost() {
    ++rows_;
    in_gap_ = true;
  }
  // The next row, with a pose, at file time t_s (s) on `line`.
  void Kept(double t_s, int line);

  int rows() const { return rows_; }
  // "p.csv: 37 rows have no pose ...", or empty when every row had one.
  std::string Warning(const std::string& path) const;

 private:
  int rows_ = 0;
  bool in_gap_ = false, have_kept_ = false;
  double last_kept_t_s_ = 0.0;
  int last_kept_line_ = 0;
  double longest_s_ = -1.0;
  int longest_from_ = 0, longest_to_ = 0;
};

}  // namespace kincal
