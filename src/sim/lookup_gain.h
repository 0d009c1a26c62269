// The thesis robot's look-up-table gain errors as nuisance parameters of a joint
// calibration: each channel's realised rate is its command times (1 + g) with one g per
// channel and speed band,
//   u' = u (1 + g_<channel>_<band>),  band = min(bands - 1, floor(|u| / band_width))
// the structure of a wheel-speed table measured once per wheel (thesis Fig. 6-6). The
// gains and the wheel radii are identified only together (a radius times its band's gain),
// so a fit needs a prior on the gains (mean 0, the table's accuracy).
//
// Not registered: its bands are a property of one robot's table, not a general effect, so
// `kincal analyze` never tries it. The thesis scenario builds it directly.
#pragma once

#include <memory>

#include "kincal/effect.h"

namespace kincal {

// Binds to every channel of `model`. Throws std::invalid_argument on bands < 1 or a
// band width that is not positive.
std::shared_ptr<const Effect> MakeLookupTableGain(const KinematicModel& model, int bands,
                                                  double band_width);

}  // namespace kincal
