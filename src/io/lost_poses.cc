#include "lost_poses.h"

#include <cctype>

#include "kincal/text.h"

namespace kincal {

bool IsMissingValue(std::string_view field) {
  if (field.empty()) return true;
  if (field.front() == '-' || field.front() == '+') field.remove_prefix(1);
  if (field.size() != 3) return false;
  const auto lower = [](char c) { return std::tolower(static_cast<unsigned char>(c)); };
  return lower(field[0]) == 'n' && lower(field[1]) == 'a' && lower(field[2]) == 'n';
}

void LostPoses::Kept(double t_s, int line) {
  if (in_gap_ && have_kept_ && t_s - last_kept_t_s_ > longest_s_) {
    longest_s_ = t_s - last_kept_t_s_;
    longest_from_ = last_kept_line_;
    longest_to_ = line;
  }
  in_gap_ = false;
  have_kept_ = true;
  last_kept_t_s_ = t_s;
  last_kept_line_ = line;
}

std::string LostPoses::Warning(const std::string& path) const {
  if (rows_ == 0) return {};
  std::string w = path + ": " + std::to_string(rows_) + (rows_ == 1 ? " row has" : " rows have") +
                  " no pose (every pose field empty or NaN: the tracker lost the robot) and " +
                  (rows_ == 1 ? "was" : "were") + " skipped";
  if (longest_s_ >= 0.0) {
    w += "; the longest stretch without a pose is " + ShortNumber(longest_s_) + " s, from line " +
         std::to_string(longest_from_) + " to line " + std::to_string(longest_to_);
  }
  return w;
}

}  // namespace kincal
