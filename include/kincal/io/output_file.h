// Writing outputs whole or not at all: every file kincal writes (reports, checkpoints,
// exports, calibrations) goes to PATH.tmp in the same folder, created exclusively and never
// through a symbolic link, is fsynced and then renamed over PATH. A reader sees the old
// file or the new one, never half of one; a link planted at PATH or PATH.tmp is replaced,
// its target untouched; a full disk or an unwritable folder is a status naming the file,
// the step and errno's text, and leaves no temporary behind.
#pragma once

#include <string>

#include "kincal/status.h"

namespace kincal {

// `what` names the output in messages ("checkpoint", "report", ...).
Status WriteFileAtomically(const std::string& path, const std::string& text, const char* what);

}  // namespace kincal
