// Lines of the text files kincal reads, as people's tools write them: a UTF-8 byte-order
// mark before the first line and Windows line endings (CRLF) are taken; what remains
// invisible in a bad token is shown escaped in errors.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "kincal/status.h"

namespace kincal {

// The UTF-8 byte-order mark some editors and spreadsheet programs write first.
inline constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";

// Removes a trailing carriage return (a CRLF line read up to its LF), and on the first line
// of a file (`first`) a leading UTF-8 byte-order mark.
void CleanLine(std::string* line, bool first);

// `text` with what a terminal would not show written out: \r, \n, \t, \\, and other control
// or non-ASCII bytes as \xNN (so "237.257\r" reads '237.257\r', not '237.257').
std::string Escaped(std::string_view text);

// The largest text file read whole (a configuration, a layout, a camera's intrinsics).
inline constexpr size_t kMaxTextFileBytes = size_t{16} << 20;

// The whole of a small text file (a YAML file handed to a parser), or an error naming the
// file and `what` it was to be, with errno's text: "cam.yaml: cannot open camera
// intrinsics: No such file or directory". A file larger than `max_bytes` is an error too.
StatusOr<std::string> ReadTextFile(const std::string& path, std::string_view what,
                                   size_t max_bytes = kMaxTextFileBytes);

}  // namespace kincal
