// Pixel formats and decoding to grey.
#include "kincal/daemon/frame.h"

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "kincal/text.h"

namespace kincal::daemon {

std::string_view PixelFormatName(PixelFormat f) {
  switch (f) {
    case PixelFormat::kGrey:
      return "GREY";
    case PixelFormat::kYuyv:
      return "YUYV";
    case PixelFormat::kMjpeg:
      return "MJPG";
    case PixelFormat::kPng:
      return "PNG";
    case PixelFormat::kBgr24:
      return "BGR3";
    case PixelFormat::kRgb24:
      return "RGB3";
  }
  return "?";
}

StatusOr<PixelFormat> ParsePixelFormat(std::string_view name) {
  if (name == "GREY") return PixelFormat::kGrey;
  if (name == "YUYV") return PixelFormat::kYuyv;
  if (name == "MJPG") return PixelFormat::kMjpeg;
  if (name == "PNG") return PixelFormat::kPng;
  if (name == "BGR3") return PixelFormat::kBgr24;
  if (name == "RGB3") return PixelFormat::kRgb24;
  return Status::Error("pixel format '" + Escaped(name) +
                       "': expected GREY, YUYV, MJPG, PNG, BGR3 or RGB3");
}

namespace {

// A frame that cannot be decoded (short buffer, bad size, corrupt data); thrown by the
// decoders below and caught in ToGrey, never outside this file.
class FrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

int Be16(const uint8_t* d) { return static_cast<int>(d[0]) << 8 | d[1]; }

// The image size in a PNG's IHDR header; false with *why when there is none.
bool PngSize(const uint8_t* d, size_t n, int* w, int* h, std::string* why) {
  static constexpr uint8_t kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (n < 24 || std::memcmp(d, kSig, 8) != 0 || std::memcmp(d + 12, "IHDR", 4) != 0) {
    *why = "not PNG data (no PNG signature and IHDR header)";
    return false;
  }
  if (d[16] != 0 || d[17] != 0 || d[20] != 0 || d[21] != 0) {
    *why = "PNG header declares an image larger than 65535 pixels on a side";
    return false;
  }
  *w = Be16(d + 18);
  *h = Be16(d + 22);
  return true;
}

// The image size in a JPEG's first frame header (SOFn); false with *why when there is none.
bool JpegSize(const uint8_t* d, size_t n, int* w, int* h, std::string* why) {
  if (n < 4 || d[0] != 0xff || d[1] != 0xd8) {
    *why = "not JPEG data (no start-of-image marker FF D8)";
    return false;
  }
  for (size_t i = 2; i + 9 < n;) {
    if (d[i] != 0xff) {
      *why = "JPEG data: no marker at byte " + std::to_string(i);
      return false;
    }
    const uint8_t m = d[i + 1];
    if (m == 0xff) {  // fill byte
      ++i;
      continue;
    }
    if (m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc) {
      *h = Be16(d + i + 5);
      *w = Be16(d + i + 7);
      return true;
    }
    if (m == 0xd9 || m == 0xda) break;  // end of image / start of scan before any frame header
    if (m == 0x01 || (m >= 0xd0 && m <= 0xd7)) {  // standalone markers carry no length
      i += 2;
      continue;
    }
    i += 2 + static_cast<size_t>(Be16(d + i + 2));
  }
  *why = "JPEG data without a frame header (SOFn) before the scan";
  return false;
}

// The image size in a PNG (IHDR) or JPEG (first SOFn segment) header must be the frame's.
bool EncodedHeaderMatches(const Frame& f, std::string* why) {
  int w = -1, h = -1;
  const bool found = f.format == PixelFormat::kPng
                         ? PngSize(f.data.data(), f.data.size(), &w, &h, why)
                         : JpegSize(f.data.data(), f.data.size(), &w, &h, why);
  if (!found) return false;
  if (w != f.width || h != f.height) {
    *why = "header declares " + std::to_string(w) + "x" + std::to_string(h) + ", expected " +
           std::to_string(f.width) + "x" + std::to_string(f.height);
    return false;
  }
  return true;
}

FrameError SizeError(const Frame& f, size_t need) {
  return FrameError(std::string(PixelFormatName(f.format)) + " frame " + std::to_string(f.width) +
                    "x" + std::to_string(f.height) + " stride " + std::to_string(f.stride) +
                    ": needs " + std::to_string(need) + " bytes, has " +
                    std::to_string(f.data.size()));
}

// Raw formats: the rows into the caller's grey image.
void RawToGrey(const Frame& f, cv::Mat* grey) {
  switch (f.format) {
    case PixelFormat::kGrey: {
      if (f.stride < f.width) throw SizeError(f, static_cast<size_t>(f.width) * f.height);
      const size_t need = static_cast<size_t>(f.stride) * (f.height - 1) + f.width;
      if (f.data.size() < need) throw SizeError(f, need);
      grey->create(f.height, f.width, CV_8UC1);
      for (int r = 0; r < f.height; ++r) {
        std::memcpy(grey->ptr(r), f.data.data() + static_cast<size_t>(r) * f.stride,
                    static_cast<size_t>(f.width));
      }
      return;
    }
    case PixelFormat::kYuyv: {
      if (f.width % 2 != 0 || f.stride < 2 * f.width)
        throw FrameError("YUYV frame: odd width or stride < 2*width");
      const size_t need =
          static_cast<size_t>(f.stride) * (f.height - 1) + 2 * static_cast<size_t>(f.width);
      if (f.data.size() < need) throw SizeError(f, need);
      grey->create(f.height, f.width, CV_8UC1);
      for (int r = 0; r < f.height; ++r) {
        const uint8_t* src = f.data.data() + static_cast<size_t>(r) * f.stride;
        uint8_t* dst = grey->ptr(r);
        for (int x = 0; x < f.width; ++x) dst[x] = src[2 * x];  // Y of Y0 U Y1 V
      }
      return;
    }
    default: {  // kBgr24, kRgb24
      if (f.stride < 3 * f.width) throw FrameError("24-bit frame: stride < 3*width");
      const size_t need =
          static_cast<size_t>(f.stride) * (f.height - 1) + 3 * static_cast<size_t>(f.width);
      if (f.data.size() < need) throw SizeError(f, need);
      const cv::Mat colour(f.height, f.width, CV_8UC3, const_cast<uint8_t*>(f.data.data()),
                           static_cast<size_t>(f.stride));
      cv::cvtColor(colour, *grey,
                   f.format == PixelFormat::kBgr24 ? cv::COLOR_BGR2GRAY : cv::COLOR_RGB2GRAY);
      return;
    }
  }
}

// MJPEG and PNG: decoded straight to grey after the header's size is checked.
void EncodedToGrey(const Frame& f, cv::Mat* grey) {
  const std::string_view format = PixelFormatName(f.format);
  if (f.data.empty()) throw FrameError(std::string(format) + " frame is empty");
  // cv::imdecode picks a decoder by content (DICOM, TIFF, JPEG 2000, HDR...; one of
  // them aborts the process on malformed input): only the declared format goes
  // through, with its header's image size checked before anything is decompressed.
  std::string why;
  if (!EncodedHeaderMatches(f, &why)) throw FrameError(std::string(format) + " frame: " + why);
  const cv::Mat buf(1, static_cast<int>(f.data.size()), CV_8UC1,
                    const_cast<uint8_t*>(f.data.data()));
  // Straight to grey (libjpeg-turbo then skips the chroma's inverse DCT and the colour
  // conversion), into the caller's buffer: no allocation once its size is set.
  cv::Mat& decoded = *grey;
  try {
    cv::imdecode(buf, cv::IMREAD_GRAYSCALE, &decoded);
  } catch (const cv::Exception& e) {
    throw FrameError(std::string(format) + " frame: decoder error: " + e.what());
  }
  if (decoded.empty())
    throw FrameError(std::string(format) + " frame: corrupt data (" +
                     std::to_string(f.data.size()) + " bytes)");
  if (decoded.cols != f.width || decoded.rows != f.height) {
    throw FrameError(std::string(format) + " frame decodes to " + std::to_string(decoded.cols) +
                     "x" + std::to_string(decoded.rows) + ", expected " + std::to_string(f.width) +
                     "x" + std::to_string(f.height));
  }
}

}  // namespace

Status ToGrey(const Frame& f, cv::Mat* grey) {
  if (f.width <= 0 || f.height <= 0 || f.width > 16384 || f.height > 16384) {
    return Status::Error("frame size " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                         " is out of range");
  }
  try {
    if (f.format == PixelFormat::kMjpeg || f.format == PixelFormat::kPng) {
      EncodedToGrey(f, grey);
    } else {
      RawToGrey(f, grey);
    }
  } catch (const FrameError& e) {
    return Status::Error(e.what());
  }
  return Status();
}

void FromGrey(const cv::Mat& grey, Frame* f) {
  CV_Assert(grey.type() == CV_8UC1);
  f->width = grey.cols;
  f->height = grey.rows;
  f->stride = grey.cols;
  f->format = PixelFormat::kGrey;
  f->data.resize(static_cast<size_t>(grey.cols) * grey.rows);
  for (int r = 0; r < grey.rows; ++r)
    std::memcpy(f->data.data() + static_cast<size_t>(r) * grey.cols, grey.ptr(r), grey.cols);
}

}  // namespace kincal::daemon
