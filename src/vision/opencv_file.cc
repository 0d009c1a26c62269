#include "vision/opencv_file.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "kincal/text.h"

namespace kincal::vision {

Status OpenOpenCvFile(const std::string& path, const char* what, cv::FileStorage* fs) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open " + what + ": " + std::strerror(errno));
  std::string text, line;
  bool first = true;
  while (std::getline(in, line)) {
    CleanLine(&line, first);
    first = false;
    text += line;
    text += '\n';
    if (text.size() > kMaxOpenCvFileBytes) {
      return Status::Error(path + ": larger than " + std::to_string(kMaxOpenCvFileBytes) +
                           " bytes: not a " + what + " file");
    }
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
