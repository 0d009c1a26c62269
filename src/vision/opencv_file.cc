#include "vision/opencv_file.h"

#include <sstream>

#include "kincal/text.h"

namespace kincal::vision {

Status OpenOpenCvFile(const std::string& path, const char* what, cv::FileStorage* fs) {
  const StatusOr<std::string> raw = ReadTextFile(path, what, kMaxOpenCvFileBytes);
  if (!raw.ok()) return raw.status();
  std::istringstream in(raw.value());
  std::string text, line;
  bool first = true;
  while (std::getline(in, line)) {
    CleanLine(&line, first);
    first = false;
    text += line;
    text += '\n';
  }
  try {
    fs->open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  } catch (const cv::Exception& e) {
    return Status::Error(path + ": not a readable OpenCV FileStorage file (" + e.what() + ")");
  }
  if (!fs->isOpened()) return Status::Error(path + ": cannot open " + what);
  return Status();
}

}  // namespace kincal::vision
