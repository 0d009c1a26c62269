#include "repeated_times.h"

#include <algorithm>
#include <utility>

#include "kincal/text.h"

namespace kincal {
namespace {

std::string Joined(std::span<const double> values) {
  std::string out;
  for (const double v : values) out += (out.empty() ? "" : ",") + ShortNumber(v);
  return out;
}

}  // namespace

ConflictingRepeats::ConflictingRepeats(std::string path, std::string unit)
    : path_(std::move(path)), unit_(std::move(unit)) {}

void ConflictingRepeats::Add(TimeNs t_ns, std::span<const double> values, int64_t place) {
  const bool repeat = have_previous_ && t_ns == previous_t_ns_;
  if (repeat && !std::equal(values.begin(), values.end(), previous_.begin(), previous_.end())) {
    if (count_++ == 0) {
      first_t_ns_ = t_ns;
      first_place_ = place;
      first_earlier_place_ = previous_place_;
      first_values_ = Joined(values);
      first_earlier_values_ = Joined(previous_);
    }
  }
  have_previous_ = true;
  previous_t_ns_ = t_ns;
  previous_ = values;
  previous_place_ = place;
}

std::string ConflictingRepeats::Warning() const {
  if (count_ == 0) return {};
  return path_ + ": " + unit_ + " " + std::to_string(first_place_) + " repeats the time of " +
         unit_ + " " + std::to_string(first_earlier_place_) + " (" +
         ShortNumber(NsToSeconds(first_t_ns_)) + " s from the start) with other values (" +
         first_values_ + " against " + first_earlier_values_ +
         "); the later is kept, as at every repeated time, and " + std::to_string(count_) +
         " repeated time" + (count_ == 1 ? "" : "s") +
         " differ so: two sources in one file, or times written coarser than the samples?";
}

}  // namespace kincal
