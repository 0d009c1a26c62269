// Subcommands of the `kincal` tool. Each registers its options on the CLI11 app and
// returns the function that runs it: its exit code, or the error main() prints before
// exiting 1.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

#include "kincal/io/checkpoint.h"
#include "kincal/status.h"

namespace kincal::app {

using Command = std::function<StatusOr<int>()>;

// The largest image the tool decodes (pixels); main() hands it to OpenCV's decoders
// (OPENCV_IO_MAX_IMAGE_PIXELS), so that a huge image is refused before it is decompressed.
inline constexpr long kMaxImagePixels = 64L << 20;

// Inside a function returning Status or StatusOr<T>: returns the error of `expr` (a
// Status), if it is one.
#define KINCAL_RETURN_IF_ERROR(expr)                                                           \
  do {                                                                                         \
    if (::kincal::Status kincal_status_ = (expr); !kincal_status_.ok()) return kincal_status_; \
  } while (false)

#define KINCAL_STATUS_CONCAT_INNER(a, b) a##b
#define KINCAL_STATUS_CONCAT(a, b) KINCAL_STATUS_CONCAT_INNER(a, b)
// Inside a function returning Status or StatusOr<T>: `lhs = ` the value of `expr` (a
// StatusOr), or returns its error.
#define KINCAL_ASSIGN_OR_RETURN(lhs, expr) \
  KINCAL_ASSIGN_OR_RETURN_IMPL(KINCAL_STATUS_CONCAT(kincal_or_, __LINE__), lhs, expr)
#define KINCAL_ASSIGN_OR_RETURN_IMPL(tmp, lhs, expr) \
  auto tmp = (expr);                                 \
  if (!tmp.ok()) return tmp.status();                \
  lhs = std::move(tmp).value()

// Writes a tool's output whole or not at all (kincal/io/output_file.h).
Status WriteOutput(const std::string& path, const std::string& text, const char* what);
// Before a long computation: the folder `dir` can be made or written into, else an error
// naming why ("out: cannot write the plan here: /etc/passwd is not a directory"). Nothing
// is created.
Status CheckOutputFolder(const std::string& dir, const char* what);

// An analyze report.json's final estimate as a checkpoint; its covariance is diagonal (the
// report keeps only sigma). An error names the file and field.
StatusOr<Checkpoint> ReadReportAsCheckpoint(const std::string& path);

Command AddReproduce(CLI::App& app);
Command AddSimulate(CLI::App& app);
Command AddAnalyze(CLI::App& app);
Command AddCamcal(CLI::App& app);
Command AddTarget(CLI::App& app);
Command AddRender(CLI::App& app);
Command AddDetect(CLI::App& app);
Command AddFloorcal(CLI::App& app);
Command AddExport(CLI::App& app);
Command AddImport(CLI::App& app);
// kincal view: scripts/kincal_view.py in this process's place (cmd_view.cc).
Command AddView(CLI::App& app);
Command AddPlan(CLI::App& app);

}  // namespace kincal::app
