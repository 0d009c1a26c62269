#include "vision/opencv_file.h"

#include "kincal/text.h"

namespace kincal::vision {

Status OpenOpenCvFile(const std::string& path, const char* what, cv::FileStorage* fs) {
  const StatusOr<std::string> raw = ReadTextFile(path, what, kMaxOpenCvFileBytes);
  if (!raw.ok()) return raw.status();
  try {
    fs->open(raw.value(), cv::FileStorage::READ | cv::FileStorage::MEMORY);
  } catch (const cv::Exception& e) {
    return Status::Error(path + ": not a readable OpenCV FileStorage file (" + e.what() + ")");
  }
  if (!fs->isOpened()) return Status::Error(path + ": cannot open " + what);
  return Status();
}

}  // namespace kincal::vision
