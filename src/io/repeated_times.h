// Repeated times whose values differ. A recording keeps the later of two samples at one
// time (RecordingStats counts them); when their values differ it also says so, since two
// sources written into one stream, or times written coarser than the samples, look so.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "kincal/time.h"

namespace kincal {

class ConflictingRepeats {
 public:
  // `path` names the stream in the warning; a sample's place in it is "<unit> N"
  // ("line 12", "event 40").
  ConflictingRepeats(std::string path, std::string unit);

  // The next sample in time order. `values` must outlive this object's use of it: the
  // previous sample's are compared with the next's (nothing is copied).
  void Add(TimeNs t_ns, std::span<const double> values, int64_t place);

  // How many repeated times had values different from the sample before them.
  int count() const { return count_; }
  // A warning naming the first of them, or empty when there were none.
  std::string Warning() const;

 private:
  std::string path_, unit_;
  bool have_previous_ = false;
  TimeNs previous_t_ns_ = 0;
  std::span<const double> previous_;
  int64_t previous_place_ = 0;
  int count_ = 0;
  TimeNs first_t_ns_ = 0;
  int64_t first_place_ = 0, first_earlier_place_ = 0;
  std::string first_values_, first_earlier_values_;
};

}  // namespace kincal
