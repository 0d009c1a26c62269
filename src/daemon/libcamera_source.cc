// libcamera capture: camera manager, one stream, requests recycled on completion,
// sensor timestamps (CLOCK_MONOTONIC, ns) from the request metadata.
#include <libcamera/libcamera.h>
#include <sys/mman.h>

#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>

#include "daemon/device_common.h"
#include "daemon/sources.h"

namespace kincal::daemon {
namespace {

namespace lc = libcamera;

class LibcameraSource final : public FrameSource {
 public:
  explicit LibcameraSource(LibcameraOptions o) : opt_(std::move(o)) {}
  ~LibcameraSource() override { Close(); }
  std::string name() const override {
    return "libcamera(" + (id_.empty() ? opt_.camera : id_) + ")";
  }
  SourceCapabilities capabilities() const override { return {.can_reopen = true}; }

  // Finds, acquires, configures and starts the camera; on an error the camera is released
  // and the status names the camera, the step and (where libcamera returns one) errno's
  // text.
  Status Start() override {
    Close();
    for (Status (LibcameraSource::*step)() :
         {&LibcameraSource::Acquire, &LibcameraSource::Configure, &LibcameraSource::MapBuffers}) {
      if (Status s = (this->*step)(); !s.ok()) {
        Close();
        return s;
      }
    }
    camera_->requestCompleted.connect(this, &LibcameraSource::OnComplete);
    if (const int ret = camera_->start(); ret != 0) {
      Close();
      return Failed("start", ret);
    }
    started_ = true;
    for (auto& r : requests_) camera_->queueRequest(r.get());
    return {};
  }

  SourceStatus Next(Frame* f, int timeout_ms, std::string* error) override {
    lc::Request* r = nullptr;
    {
      std::unique_lock lock(mu_);
      if (!cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                        [&] { return !done_.empty() || stop_; })) {
        return SourceStatus::kTimeout;
      }
      if (stop_) return SourceStatus::kEnd;
      r = done_.front();
      done_.pop_front();
    }
    const TimeNs arrival = MonotonicNs();
    if (r->status() != lc::Request::RequestComplete) {
      *error = "libcamera: " + id_ + ": request failed";
      return SourceStatus::kError;
    }
    lc::FrameBuffer* buffer = r->buffers().begin()->second;
    const lc::FrameMetadata& md = buffer->metadata();
    const auto sensor_ts = r->metadata().get(lc::controls::SensorTimestamp);
    const TimeNs stamp = sensor_ts ? *sensor_ts : static_cast<TimeNs>(md.timestamp);
    gaps_.Observe(md.sequence);
    const auto& map = maps_.at(buffer);
    const auto& plane = buffer->planes()[0];
    const size_t used = std::min<size_t>(md.planes()[0].bytesused, map.length - plane.offset);
    f->data.resize(used);
    std::memcpy(f->data.data(), map.data + plane.offset, used);
    r->reuse(lc::Request::ReuseBuffers);
    camera_->queueRequest(r);
    f->width = width_;
    f->height = height_;
    f->stride = stride_;
    f->format = format_;
    f->utime = PipelineUtime(stamp > 0 ? stamp : arrival);
    f->device_utime = stamp / 1000;
    f->sequence = md.sequence;
    f->arrival_mono_ns = arrival;
    return SourceStatus::kFrame;
  }

  void Stop() override {
    std::lock_guard lock(mu_);
    stop_ = true;
    cv_.notify_all();
  }
  int64_t device_drops() const override { return gaps_.drops(); }
  Status Reopen() override {
    Close();
    {
      std::lock_guard lock(mu_);
      done_.clear();
    }
    gaps_.Restart();  // a reopened camera numbers its frames anew
    return Start();
  }

 private:
  // libcamera's calls return 0 or a negative errno.
  Status Failed(const std::string& what, int ret) const {
    return Status::Error("libcamera: " + (id_.empty() ? opt_.camera : id_) + ": " + what +
                         " failed" + (ret < 0 ? std::string(": ") + std::strerror(-ret) : ""));
  }

  Status Acquire() {
    cm_ = std::make_unique<lc::CameraManager>();
    if (const int ret = cm_->start(); ret != 0) return Failed("camera manager start", ret);
    const auto cams = cm_->cameras();
    if (cams.empty()) return Status::Error("libcamera: no cameras found");
    camera_ = opt_.camera.empty() ? cams.front() : cm_->get(opt_.camera);
    if (!camera_) {
      std::string ids;
      for (const auto& c : cams) ids += (ids.empty() ? "" : ", ") + c->id();
      return Status::Error("libcamera: no camera '" + opt_.camera + "' (found: " + ids + ")");
    }
    id_ = camera_->id();
    if (const int ret = camera_->acquire(); ret != 0) return Failed("acquire (in use?)", ret);
    acquired_ = true;
    return {};
  }

  // The requested pixel format and size; a camera that adjusts either is refused.
  Status Configure() {
    config_ = camera_->generateConfiguration({lc::StreamRole::Viewfinder});
    if (!config_ || config_->empty()) {
      return Status::Error("libcamera: " + id_ + ": no stream configuration");
    }
    lc::StreamConfiguration& sc = config_->at(0);
    const PixelFormat want = opt_.pixel_format;
    const lc::PixelFormat pf = want == PixelFormat::kGrey    ? lc::formats::R8
                               : want == PixelFormat::kYuyv  ? lc::formats::YUYV
                               : want == PixelFormat::kMjpeg ? lc::formats::MJPEG
                               : want == PixelFormat::kBgr24 ? lc::formats::RGB888
                                                             : lc::formats::BGR888;
    sc.pixelFormat = pf;
    sc.size = lc::Size(static_cast<unsigned>(opt_.width), static_cast<unsigned>(opt_.height));
    sc.bufferCount = static_cast<unsigned>(opt_.buffers);
    if (config_->validate() == lc::CameraConfiguration::Invalid) {
      return Status::Error("libcamera: " + id_ + ": configuration invalid");
    }
    if (sc.pixelFormat != pf || sc.size.width != static_cast<unsigned>(opt_.width) ||
        sc.size.height != static_cast<unsigned>(opt_.height)) {
      return Status::Error("libcamera: " + id_ + ": asked for " +
                           std::string(PixelFormatName(want)) + " " + std::to_string(opt_.width) +
                           "x" + std::to_string(opt_.height) + ", the camera offers " +
                           sc.toString());
    }
    if (const int ret = camera_->configure(config_.get()); ret != 0) {
      return Failed("configure", ret);
    }
    format_ = want;
    width_ = static_cast<int>(sc.size.width);
    height_ = static_cast<int>(sc.size.height);
    stride_ = static_cast<int>(sc.stride);
    stream_ = sc.stream();
    return {};
  }

  // Buffers allocated, mapped once, one request each.
  Status MapBuffers() {
    allocator_ = std::make_unique<lc::FrameBufferAllocator>(camera_);
    if (const int ret = allocator_->allocate(stream_); ret < 0) {
      return Failed("buffer allocation", ret);
    }
    for (const auto& buffer : allocator_->buffers(stream_)) {
      const auto& plane = buffer->planes()[0];
      size_t length = 0;
      for (const auto& p : buffer->planes()) length = std::max<size_t>(length, p.offset + p.length);
      void* map = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
      if (map == MAP_FAILED) {
        return Status::Error("libcamera: " + id_ + ": mmap failed: " + std::strerror(errno));
      }
      maps_[buffer.get()] = {static_cast<uint8_t*>(map), length};
      auto request = camera_->createRequest();
      if (!request) return Status::Error("libcamera: " + id_ + ": cannot create a request");
      if (const int ret = request->addBuffer(stream_, buffer.get()); ret != 0) {
        return Failed("adding a buffer to a request", ret);
      }
      requests_.push_back(std::move(request));
    }
    return {};
  }

  void OnComplete(lc::Request* r) {
    if (r->status() == lc::Request::RequestCancelled) return;
    std::lock_guard lock(mu_);
    done_.push_back(r);
    cv_.notify_one();
  }

  void Close() {
    if (started_) camera_->stop();
    started_ = false;
    if (camera_) camera_->requestCompleted.disconnect(this);
    requests_.clear();
    for (auto& [buf, m] : maps_) ::munmap(m.data, m.length);
    maps_.clear();
    allocator_.reset();
    if (acquired_) camera_->release();
    acquired_ = false;
    camera_.reset();
    if (cm_) cm_->stop();
    cm_.reset();
  }

  struct Map {
    uint8_t* data;
    size_t length;
  };
  LibcameraOptions opt_;
  std::unique_ptr<lc::CameraManager> cm_;
  std::shared_ptr<lc::Camera> camera_;
  std::unique_ptr<lc::CameraConfiguration> config_;
  std::unique_ptr<lc::FrameBufferAllocator> allocator_;
  lc::Stream* stream_ = nullptr;
  std::vector<std::unique_ptr<lc::Request>> requests_;
  std::map<const lc::FrameBuffer*, Map> maps_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<lc::Request*> done_;
  bool stop_ = false, acquired_ = false, started_ = false;
  std::string id_;
  PixelFormat format_ = PixelFormat::kGrey;
  int width_ = 0, height_ = 0, stride_ = 0;
  SequenceGaps gaps_;
};

}  // namespace

std::unique_ptr<FrameSource> MakeLibcameraSource(const LibcameraOptions& o) {
  return std::make_unique<LibcameraSource>(o);
}

}  // namespace kincal::daemon
