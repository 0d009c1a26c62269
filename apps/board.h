// Board specification shared by camcal, floorcal and render: KIND:COLSxROWS:PITCH with
// KIND chessboard (inner corners), circles or acircles (asymmetric grid), PITCH in metres.
#pragma once

#include <Eigen/Core>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

#include "kincal/status.h"

namespace kincal::app {

struct Board {
  std::string kind;
  int cols = 0, rows = 0;
  double pitch = 0;

  static StatusOr<Board> Parse(const std::string& s) {
    static const std::regex re(R"((chessboard|circles|acircles):(\d+)x(\d+):([0-9.eE+-]+))");
    std::smatch m;
    if (!std::regex_match(s, m, re)) {
      return Status::Error("--board '" + s +
                           "': expected KIND:COLSxROWS:PITCH with KIND chessboard, circles or "
                           "acircles, e.g. chessboard:9x6:0.025");
    }
    Board b;
    try {
      b = Board{m[1], std::stoi(m[2]), std::stoi(m[3]), std::stod(m[4])};
    } catch (const std::logic_error&) {  // out of range, or a pitch such as "+"
      return Status::Error("--board '" + s + "': a number out of range");
    }
    if (b.cols < 2 || b.rows < 2 || !(b.pitch > 0)) {
      return Status::Error("--board '" + s + "': need >= 2x2 points and pitch > 0");
    }
    return b;
  }
  // Board points in the board frame (z = 0), row-major as OpenCV's detectors order them.
  std::vector<Eigen::Vector3d> Points() const {
    std::vector<Eigen::Vector3d> pts;
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        pts.emplace_back((kind == "acircles" ? 2 * c + r % 2 : c) * pitch, r * pitch, 0.0);
      }
    }
    return pts;
  }
};

}  // namespace kincal::app
