// libcamera capture: camera manager, one stream, requests recycled on completion,
// sensor timestamps (CLOCK_MONOTONIC, ns) from the request metadata. A size or format the
// camera adjusts is taken when kincal can read it, and said (in the log and the source's
// name). A camera that delivers nothing for kStallNs is an error: one that stalled is
// reopened by the capture stage; one whose device vanished ends the run (see Close()).
#include <libcamera/libcamera.h>
#include <spdlog/spdlog.h>
#include <sys/mman.h>

#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <mutex>

#include "daemon/device_common.h"
#include "daemon/media_devices.h"
#include "daemon/sources.h"

namespace kincal::daemon {
namespace {

namespace lc = libcamera;

// No completed request for this long: the camera is gone or stalled (an error, so the
// capture stage reopens it).
constexpr TimeNs kStallNs = 3 * kNsPerSecond;

class LibcameraSource final : public FrameSource {
 public:
  explicit LibcameraSource(LibcameraOptions o) : opt_(std::move(o)) {}
  ~LibcameraSource() override {
    if (abandoned_) {  // see Close(): left alive on purpose until the process exits
      [[maybe_unused]] auto* requests = new auto(std::move(requests_));
      [[maybe_unused]] auto* allocator = allocator_.release();
      [[maybe_unused]] auto* config = config_.release();
      [[maybe_unused]] auto* camera = new auto(std::move(camera_));
      [[maybe_unused]] auto* manager = cm_.release();
      return;
    }
    Close();
  }
  std::string name() const override {
    return "libcamera(" + (id_.empty() ? opt_.camera : id_) + (notes_.empty() ? "" : ", ") +
           notes_ + ")";
  }
  // A camera whose device vanished cannot be reopened in this process (see Close()).
  SourceCapabilities capabilities() const override { return {.can_reopen = !abandoned_}; }

  // Finds, acquires, configures and starts the camera; on an error the camera is released
  // and the status names the camera, the step and (where libcamera returns one) errno's
  // text.
  Status Start() override {
    Close();
    if (abandoned_) {
      return Status::Error("libcamera: " + id_ +
                           ": the camera's device vanished; libcamera cannot release a vanished "
                           "camera, so kincald cannot reopen it: restart kincald when it is back");
    }
    for (Status (LibcameraSource::*step)() :
         {&LibcameraSource::Acquire, &LibcameraSource::Configure, &LibcameraSource::MapBuffers}) {
      if (Status s = (this->*step)(); !s.ok()) {
        Close();
        return s;
      }
    }
    camera_->requestCompleted.connect(this, &LibcameraSource::OnComplete);
    camera_->disconnected.connect(this, &LibcameraSource::OnDisconnect);
    lc::ControlList start_controls = FrameRateControls();
    if (const int ret = camera_->start(&start_controls); ret != 0) {
      Close();
      return Failed("start", ret);
    }
    started_ = true;
    last_completion_ = MonotonicNs();
    for (auto& r : requests_) camera_->queueRequest(r.get());
    return {};
  }

  SourceStatus Next(Frame* f, int timeout_ms, std::string* error) override {
    lc::Request* r = nullptr;
    {
      std::unique_lock lock(mu_);
      if (!cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                        [&] { return !done_.empty() || stop_ || disconnected_; })) {
        if (MonotonicNs() - last_completion_ > kStallNs) {
          stalled_ = true;
          abandoned_ = !AllPresent(media_nodes_);  // see Close()
          *error = fmt::format("libcamera: {}: no frame for {} s", id_, kStallNs / kNsPerSecond) +
                   (abandoned_ ? ": the camera's device vanished (its media device is gone); "
                                 "libcamera cannot release a vanished camera, so kincald stops "
                                 "here: restart it when the camera is back"
                               : " (camera unplugged or stalled)");
          return SourceStatus::kError;
        }
        return SourceStatus::kTimeout;
      }
      if (stop_) return SourceStatus::kEnd;
      if (disconnected_) {
        *error = "libcamera: " + id_ + ": camera disconnected";
        return SourceStatus::kError;
      }
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
      disconnected_ = false;
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
    media_nodes_ = ListMediaNodes();
    const auto cams = cm_->cameras();
    if (cams.empty()) {
      // A media device another process uses is not even enumerated: say who holds it.
      const std::string held = DescribeMediaHolders();
      return Status::Error(
          "libcamera: no cameras found" +
          (held.empty() ? std::string() : ": a camera may be in use by another process: " + held));
    }
    camera_ = opt_.camera.empty() ? cams.front() : cm_->get(opt_.camera);
    if (!camera_) {
      std::string ids;
      for (const auto& c : cams) ids += (ids.empty() ? "" : ", ") + c->id();
      return Status::Error("libcamera: no camera '" + opt_.camera + "' (found: " + ids + ")");
    }
    id_ = camera_->id();
    if (const int ret = camera_->acquire(); ret != 0) {
      const std::string held = DescribeMediaHolders();
      return Status::Error(Failed("acquire", ret).message() +
                           ": the camera is in use by another process" +
                           (held.empty() ? "" : " (" + held + ")"));
    }
    acquired_ = true;
    return {};
  }

  // libcamera's formats that kincal reads, as its own.
  static bool FromLibcamera(const lc::PixelFormat& pf, PixelFormat* out) {
    if (pf == lc::formats::R8)
      *out = PixelFormat::kGrey;
    else if (pf == lc::formats::YUYV)
      *out = PixelFormat::kYuyv;
    else if (pf == lc::formats::MJPEG)
      *out = PixelFormat::kMjpeg;
    else if (pf == lc::formats::RGB888)
      *out = PixelFormat::kBgr24;  // B, G, R in memory
    else if (pf == lc::formats::BGR888)
      *out = PixelFormat::kRgb24;
    else
      return false;
    return true;
  }

  // FrameDurationLimits pinned to 1/fps when asked and the camera has the control.
  lc::ControlList FrameRateControls() {
    lc::ControlList controls;
    if (opt_.fps <= 0) return controls;
    if (camera_->controls().count(&lc::controls::FrameDurationLimits) == 0) {
      AddNote(fmt::format("no frame-rate control: the camera's own rate, not {:g} fps", opt_.fps));
      return controls;
    }
    const auto us = static_cast<int64_t>(1e6 / opt_.fps);
    controls.set(lc::controls::FrameDurationLimits, lc::Span<const int64_t, 2>({us, us}));
    return controls;
  }

  void AddNote(const std::string& note) {
    spdlog::warn("libcamera: {}: {}", id_, note);
    notes_ += (notes_.empty() ? "" : "; ") + note;
  }

  // The requested pixel format and size, or what the camera adjusts them to when kincal
  // can read that (said in the log and the name: intrinsics must be for that size).
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
    notes_.clear();
    const std::string asked = std::string(PixelFormatName(want)) + " " +
                              std::to_string(opt_.width) + "x" + std::to_string(opt_.height);
    if (config_->validate() == lc::CameraConfiguration::Invalid) {
      return Status::Error("libcamera: " + id_ + ": configuration invalid for " + asked);
    }
    PixelFormat got = want;
    if (!FromLibcamera(sc.pixelFormat, &got)) {
      return Status::Error("libcamera: " + id_ + ": asked for " + asked + ", the camera offers " +
                           sc.toString() + ", a format kincal does not read");
    }
    if (sc.pixelFormat != pf || sc.size.width != static_cast<unsigned>(opt_.width) ||
        sc.size.height != static_cast<unsigned>(opt_.height)) {
      AddNote(std::string(PixelFormatName(got)) + " " + std::to_string(sc.size.width) + "x" +
              std::to_string(sc.size.height) + ", adjusted by the camera from " + asked);
    }
    if (const int ret = camera_->configure(config_.get()); ret != 0) {
      return Failed("configure", ret);
    }
    format_ = got;
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
    last_completion_ = MonotonicNs();
    done_.push_back(r);
    cv_.notify_one();
  }

  void OnDisconnect() {
    std::lock_guard lock(mu_);
    disconnected_ = true;
    cv_.notify_one();
  }

  // A camera that stalled because its device vanished cannot be stopped, nor dropped:
  // libcamera 0.0.3 aborts either way (its pipeline handler asserts that every request came
  // back, which STREAMOFF on a vanished node never gives; its IPA thread cannot be
  // destroyed running), and its hot-unplug path does not disconnect the camera. Such a
  // camera is abandoned, alive, and the source cannot be reopened in this process: the
  // daemon ends with the error (after its final checkpoint), for its supervisor to restart
  // it (docs/daemon.md, "libcamera").
  void Close() {
    if (abandoned_) return;
    if (started_ && stalled_ && !AllPresent(media_nodes_)) {
      abandoned_ = true;
      return;
    }
    stalled_ = false;
    if (started_) camera_->stop();
    started_ = false;
    if (camera_) {
      camera_->requestCompleted.disconnect(this);
      camera_->disconnected.disconnect(this);
    }
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
  bool stop_ = false, acquired_ = false, started_ = false, disconnected_ = false;
  bool stalled_ = false, abandoned_ = false;
  std::vector<MediaNode> media_nodes_;  // present when the camera was acquired
  TimeNs last_completion_ = 0;          // under mu_
  std::string id_;
  std::string notes_;  // adjustments the camera made
  PixelFormat format_ = PixelFormat::kGrey;
  int width_ = 0, height_ = 0, stride_ = 0;
  SequenceGaps gaps_;
};

}  // namespace

std::unique_ptr<FrameSource> MakeLibcameraSource(const LibcameraOptions& o) {
  return std::make_unique<LibcameraSource>(o);
}

}  // namespace kincal::daemon
