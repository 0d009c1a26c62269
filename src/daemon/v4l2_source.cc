// Video4Linux2 capture: format negotiation, mmap streaming, kernel timestamps.
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <map>

#include "daemon/device_common.h"
#include "daemon/sources.h"

namespace kincal::daemon {
namespace {

int Ioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = ::ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

std::string FourCc(uint32_t f) {
  return {static_cast<char>(f & 0xff), static_cast<char>((f >> 8) & 0xff),
          static_cast<char>((f >> 16) & 0xff), static_cast<char>((f >> 24) & 0xff)};
}

// "Exposure Time, Absolute" -> "exposure_time_absolute"
std::string ControlKey(const char* name) {
  std::string k;
  for (const char* c = name; *c; ++c) {
    const char ch = static_cast<char>(std::tolower(static_cast<unsigned char>(*c)));
    if (std::isalnum(static_cast<unsigned char>(ch))) {
      k += ch;
    } else if (!k.empty() && k.back() != '_') {
      k += '_';
    }
  }
  while (!k.empty() && k.back() == '_') k.pop_back();
  return k;
}

class V4l2Source final : public FrameSource {
 public:
  explicit V4l2Source(V4l2Options o) : opt_(std::move(o)) {}
  ~V4l2Source() override { Close(); }

  std::string name() const override { return "v4l2(" + opt_.device + ")"; }
  SourceCapabilities capabilities() const override { return {.can_reopen = true}; }

  // Opens the device and starts streaming; a device already open is closed first (a
  // second Start() restarts it). An error names the device, the step that failed and
  // errno's text; the device is closed again.
  Status Start() override {
    Close();
    for (Status (V4l2Source::*step)() :
         {&V4l2Source::Open, &V4l2Source::SetFormat, &V4l2Source::SetFrameRate,
          &V4l2Source::SetControls, &V4l2Source::MapBuffers}) {
      if (Status s = (this->*step)(); !s.ok()) return s;
    }
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (Ioctl(fd_, VIDIOC_STREAMON, &type) != 0) {
      // EPIPE: a media-controller device whose pipeline does not deliver this format.
      if (errno == EPIPE) {
        const int err = errno;
        Close();
        return Status::Error(
            opt_.device + ": VIDIOC_STREAMON: " + std::strerror(err) +
            ": the device is one node of a media-controller pipeline whose links or subdevice "
            "formats do not produce " +
            std::to_string(width_) + "x" + std::to_string(height_) + " " +
            std::string(PixelFormatName(format_)) +
            "; configure the pipeline (media-ctl --links/--set-v4l2) or use the libcamera "
            "source, which configures it");
      }
      return Fail("VIDIOC_STREAMON");
    }
    streaming_ = true;
    return {};
  }

  SourceStatus Next(Frame* f, int timeout_ms, std::string* error) override {
    if (stop_.load()) Close();
    if (fd_ < 0) return SourceStatus::kEnd;
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, timeout_ms);
    if (r == 0) return SourceStatus::kTimeout;
    if (r < 0) {
      if (errno == EINTR) return SourceStatus::kTimeout;
      *error = opt_.device + ": poll: " + std::strerror(errno);
      return SourceStatus::kError;
    }
    if (p.revents & (POLLERR | POLLHUP | POLLNVAL)) {
      *error = opt_.device + ": device error or disconnected (poll revents " +
               std::to_string(p.revents) + ")";
      return SourceStatus::kError;
    }
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    if (Ioctl(fd_, VIDIOC_DQBUF, &b) != 0) {
      if (errno == EAGAIN) return SourceStatus::kTimeout;
      *error = opt_.device + ": VIDIOC_DQBUF: " + std::strerror(errno);
      return SourceStatus::kError;
    }
    const TimeNs arrival = MonotonicNs();
    // Kernel timestamp: CLOCK_MONOTONIC for every modern driver (flag checked).
    TimeNs stamp_ns =
        static_cast<TimeNs>(b.timestamp.tv_sec) * kNsPerSecond + b.timestamp.tv_usec * 1000;
    const bool monotonic =
        (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    if (!monotonic || stamp_ns == 0) stamp_ns = arrival;  // no usable device stamp: use arrival
    // End-of-frame stamps mark the end of readout: the exposure began about a period earlier.
    const bool eof = (b.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_EOF;
    const TimeNs exposure_ns = eof ? stamp_ns - frame_period_ns_ : stamp_ns;
    gaps_.Observe(b.sequence);
    const auto& buf = buffers_[b.index];
    const size_t used = std::min<size_t>(b.bytesused ? b.bytesused : buf.length, buf.length);
    f->data.resize(used);
    std::memcpy(f->data.data(), buf.start, used);
    if (Ioctl(fd_, VIDIOC_QBUF, &b) != 0) {
      *error = opt_.device + ": VIDIOC_QBUF: " + std::strerror(errno);
      return SourceStatus::kError;
    }
    f->width = width_;
    f->height = height_;
    f->stride = stride_;
    f->format = format_;
    f->utime = PipelineUtime(exposure_ns);
    f->device_utime = stamp_ns / 1000;
    f->sequence = b.sequence;
    f->arrival_mono_ns = arrival;
    f->tstamp_end_of_frame = eof;
    return SourceStatus::kFrame;
  }

  // Called from another thread: the capture thread closes the device on its next Next().
  void Stop() override { stop_.store(true); }
  int64_t device_drops() const override { return gaps_.drops(); }
  Status Reopen() override {
    Close();
    gaps_.Restart();  // a reopened device numbers its frames anew
    return Start();
  }

 private:
  Status Open() {
    fd_ = ::open(opt_.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) return Status::Error(opt_.device + ": cannot open: " + std::strerror(errno));
    v4l2_capability cap{};
    if (Ioctl(fd_, VIDIOC_QUERYCAP, &cap) != 0) return Fail("VIDIOC_QUERYCAP (not a V4L2 device?)");
    const uint32_t caps =
        (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) return Refuse("not a video capture device");
    if (!(caps & V4L2_CAP_STREAMING)) return Refuse("does not support streaming I/O");
    return {};
  }

  // The requested size and pixel format; a driver that adjusts either is refused.
  Status SetFormat() {
    const PixelFormat want = opt_.pixel_format;
    const std::string want_name(PixelFormatName(want));
    const uint32_t fourcc = want == PixelFormat::kGrey    ? V4L2_PIX_FMT_GREY
                            : want == PixelFormat::kYuyv  ? V4L2_PIX_FMT_YUYV
                            : want == PixelFormat::kBgr24 ? V4L2_PIX_FMT_BGR24
                            : want == PixelFormat::kRgb24 ? V4L2_PIX_FMT_RGB24
                                                          : V4L2_PIX_FMT_MJPEG;
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = static_cast<uint32_t>(opt_.width);
    fmt.fmt.pix.height = static_cast<uint32_t>(opt_.height);
    fmt.fmt.pix.pixelformat = fourcc;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (Ioctl(fd_, VIDIOC_S_FMT, &fmt) != 0) return Fail("VIDIOC_S_FMT " + want_name);
    if (fmt.fmt.pix.pixelformat != fourcc) {
      return Refuse("does not offer " + want_name + " (it offers " +
                    FourCc(fmt.fmt.pix.pixelformat) + "); set v4l2.pixel_format");
    }
    format_ = want;
    width_ = static_cast<int>(fmt.fmt.pix.width);
    height_ = static_cast<int>(fmt.fmt.pix.height);
    stride_ = static_cast<int>(fmt.fmt.pix.bytesperline);
    if (width_ != opt_.width || height_ != opt_.height) {
      return Refuse("asked for " + std::to_string(opt_.width) + "x" + std::to_string(opt_.height) +
                    ", the driver offers " + std::to_string(width_) + "x" +
                    std::to_string(height_));
    }
    return {};
  }

  // Not every driver can set its rate: then the driver's own rate stands.
  Status SetFrameRate() {
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = 1000;
    parm.parm.capture.timeperframe.denominator =
        static_cast<uint32_t>(std::lround(opt_.fps * 1000));
    if (Ioctl(fd_, VIDIOC_S_PARM, &parm) == 0 && parm.parm.capture.timeperframe.denominator > 0) {
      frame_period_ns_ = static_cast<TimeNs>(1e9 * parm.parm.capture.timeperframe.numerator /
                                             parm.parm.capture.timeperframe.denominator);
    } else {
      frame_period_ns_ = static_cast<TimeNs>(1e9 / opt_.fps);
    }
    return {};
  }

  // At least four mmap buffers, all queued.
  Status MapBuffers() {
    v4l2_requestbuffers req{};
    req.count = static_cast<uint32_t>(opt_.buffers);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (Ioctl(fd_, VIDIOC_REQBUFS, &req) != 0) return Fail("VIDIOC_REQBUFS (mmap)");
    if (req.count < 4) return Refuse("only " + std::to_string(req.count) + " buffers (need >= 4)");
    buffers_.resize(req.count);
    for (uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (Ioctl(fd_, VIDIOC_QUERYBUF, &b) != 0) return Fail("VIDIOC_QUERYBUF");
      void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
      if (p == MAP_FAILED) return Fail("mmap");
      buffers_[i] = {p, b.length};
      if (Ioctl(fd_, VIDIOC_QBUF, &b) != 0) return Fail("VIDIOC_QBUF");
    }
    return {};
  }

  // A failed system call: closes the device; the error names it with errno's text.
  Status Fail(const std::string& what) {
    const std::string msg = opt_.device + ": " + what + " failed: " + std::strerror(errno);
    Close();
    return Status::Error(msg);
  }
  // The device works but cannot do what was asked.
  Status Refuse(const std::string& why) {
    Close();
    return Status::Error(opt_.device + ": " + why);
  }

  Status SetControls() {
    if (opt_.controls.empty()) return {};
    std::map<std::string, v4l2_query_ext_ctrl> found;
    v4l2_query_ext_ctrl q{};
    q.id = V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND;
    while (Ioctl(fd_, VIDIOC_QUERY_EXT_CTRL, &q) == 0) {
      if (!(q.flags & V4L2_CTRL_FLAG_DISABLED) && q.type != V4L2_CTRL_TYPE_CTRL_CLASS)
        found[ControlKey(q.name)] = q;
      q.id |= V4L2_CTRL_FLAG_NEXT_CTRL | V4L2_CTRL_FLAG_NEXT_COMPOUND;
    }
    for (const auto& [key, value] : opt_.controls) {
      const auto it = found.find(key);
      if (it == found.end()) {
        std::string names;
        for (const auto& [k, _] : found) names += (names.empty() ? "" : ", ") + k;
        return Refuse("no control '" + key + "' (it has: " + names + ")");
      }
      const auto& qc = it->second;
      if (value < qc.minimum || value > qc.maximum) {
        return Refuse("control '" + key + "' = " + std::to_string(value) + " outside [" +
                      std::to_string(qc.minimum) + ", " + std::to_string(qc.maximum) + "]");
      }
      v4l2_control ctl{qc.id, static_cast<int32_t>(value)};
      if (Ioctl(fd_, VIDIOC_S_CTRL, &ctl) != 0) return Fail("setting control '" + key + "'");
    }
    return {};
  }

  void Close() {
    if (fd_ < 0) return;
    if (streaming_) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      // A device that vanished fails here too; the buffers and fd are released regardless.
      if (Ioctl(fd_, VIDIOC_STREAMOFF, &type) != 0) {
        spdlog::warn("{}: VIDIOC_STREAMOFF failed: {}", opt_.device, std::strerror(errno));
      }
      streaming_ = false;
    }
    for (auto& b : buffers_) {
      if (b.start != nullptr) ::munmap(b.start, b.length);
    }
    buffers_.clear();
    ::close(fd_);
    fd_ = -1;
  }

  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
  };
  V4l2Options opt_;
  int fd_ = -1;
  bool streaming_ = false;
  std::vector<Buffer> buffers_;
  PixelFormat format_ = PixelFormat::kGrey;
  int width_ = 0, height_ = 0, stride_ = 0;
  TimeNs frame_period_ns_ = 0;
  SequenceGaps gaps_;
  std::atomic<bool> stop_{false};
};

}  // namespace

std::unique_ptr<FrameSource> MakeV4l2Source(const V4l2Options& o) {
  return std::make_unique<V4l2Source>(o);
}

}  // namespace kincal::daemon
