// OpenCV FileStorage files (camera intrinsics, floor extrinsics) opened as people's tools
// save them: a UTF-8 byte-order mark and CRLF line endings are taken (OpenCV's parser
// refuses both).
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "kincal/status.h"

namespace kincal::vision {

// The largest FileStorage file read (a camera or floor file is a few kB).
inline constexpr size_t kMaxOpenCvFileBytes = 16 << 20;

// Opens `path` for reading into *fs; an error names the file (errno's text, a folder, its
// size, or OpenCV's parse error). `what` says what the file should be, for "cannot open".
Status OpenOpenCvFile(const std::string& path, const char* what, cv::FileStorage* fs);

}  // namespace kincal::vision
