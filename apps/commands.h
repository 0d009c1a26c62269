// Subcommands of the `kincal` tool. Each registers its options on the CLI11 app and
// returns the function that runs it (exit code).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <stdexcept>
#include <string>

#include "kincal/io/checkpoint.h"
#include "kincal/status.h"

namespace kincal::app {

using Command = std::function<int()>;

// The largest image the tool decodes (pixels); main() hands it to OpenCV's decoders
// (OPENCV_IO_MAX_IMAGE_PIXELS), so that a huge image is refused before it is decompressed.
inline constexpr long kMaxImagePixels = 64L << 20;

// Writes a tool's output whole or not at all (kincal/io/output_file.h); throws
// std::runtime_error with the status's message, which main() prints before exiting 1.
void WriteOutput(const std::string& path, const std::string& text, const char* what);

// A library function's error as the std::runtime_error a command reports and exits 1 on
// (main() prints it).
template <typename T>
T OrThrow(StatusOr<T> v) {
  if (!v.ok()) throw std::runtime_error(v.status().message());
  return std::move(v).value();
}

// An analyze report.json's final estimate as a checkpoint; its covariance is diagonal (the
// report keeps only sigma). Throws std::runtime_error naming the file and field.
Checkpoint ReadReportAsCheckpoint(const std::string& path);
// ReadCheckpoint's error as the std::runtime_error a command reports and exits 1 on.
Checkpoint ReadCheckpointOrThrow(const std::string& path);

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
