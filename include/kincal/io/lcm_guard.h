// Checks on raw LCM messages from outside, before lcm-gen's decoder sees them. The
// generated decoders size their arrays from the message's own length fields before
// checking that the bytes are there, so a hostile "2^31 - 1 elements" makes them allocate
// gigabytes. These checks read the length fields and reject a message whose arrays could
// not fit in the bytes received (or exceed kincal's own limits).
#pragma once

#include <cstddef>
#include <string>

namespace kincal {

// kincal.controls_t: at most `max_controls` entries that fit in `n` bytes.
bool PlausibleControls(const void* data, size_t n, int max_controls, std::string* why);
// kincal.params_t: at most `max_params` parameters whose arrays fit in `n` bytes.
bool PlausibleParams(const void* data, size_t n, int max_params, std::string* why);
// kincal.frame_t: `size` equal to the bytes that remain.
bool PlausibleFrame(const void* data, size_t n, std::string* why);

}  // namespace kincal
