// kincald's preview (KINCAL_PREVIEW): what the camera sees, for people (`kincal view`,
// Foxglove), not for the estimator. At preview.rate_hz of frame time the detection thread
// hands its grey image over (one copy into a buffer kept from frame to frame); a worker
// thread below the pipeline's priority downscales it by the smallest whole factor that
// fits preview.width (1280 px wide with 480 gives 426: halvings by area
// resampling, then linear for the rest) and encodes it as JPEG, published as
// a kincal.preview_t with the factor, so that markers_t's pixels map onto it. Policy when the
// worker is still busy with the last one: live, the new frame is skipped and counted (the pipeline
// never waits for it); lossless (a --fast replay), the detection thread waits, so that a replay's
// previews are the same every time.
#pragma once

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <kincal/preview_t.hpp>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "daemon/publisher.h"
#include "daemon/sources.h"
#include "kincal/daemon/config.h"

namespace kincal::daemon {

// The target's axes drawn on a preview: each axis this long (m).
inline constexpr double kPreviewAxisLengthM = 0.1;
// A pose on the floor (x, y, theta) to the image pixels of the target's origin and axis
// ends, each kPreviewAxisLengthM long (vision::TargetAxesInImage with kincald's camera);
// false when they are not in front of the camera.
using AxesInImage =
    std::function<bool(const Eigen::Vector3d& xytheta, std::array<Eigen::Vector2d, 3>* px)>;

class PreviewStage {
 public:
  // `floor_seen`: the floor polygon every preview carries (vision/floor_view.h); `axes`:
  // where the target's axes are drawn (empty: never).
  PreviewStage(const PreviewOptions& options, std::string channel, Publisher* publisher,
               bool lossless = false, const std::vector<Eigen::Vector2d>& floor_seen = {},
               AxesInImage axes = {});
  ~PreviewStage();  // stops the worker
  PreviewStage(const PreviewStage&) = delete;
  PreviewStage& operator=(const PreviewStage&) = delete;

  // From the detection thread, every frame: takes the image when a preview is due by frame
  // time and the worker is free. Never blocks on the worker.
  // `target`: the frame's pose on the floor (null: none).
  void Offer(const cv::Mat& grey, int64_t utime, int64_t sequence,
             const Eigen::Vector3d* target = nullptr);
  // Waits until the worker has published what it was given (tests, shutdown).
  void Drain();

  int64_t published() const { return published_.load(); }
  int64_t skipped() const { return skipped_.load(); }  // due, but the worker was busy

  // The whole downscale factor for a source this wide: the smallest that fits `width`.
  static int Scale(int source_width, int width);

 private:
  void Loop();
  // The target's axes into msg_ (none without a pose, or when they are not in view).
  void FillAxes(bool has_target, const Eigen::Vector3d& target);

  const PreviewOptions opt_;
  const std::string channel_;
  Publisher& publisher_;
  const bool lossless_;
  const int64_t period_us_;
  int64_t next_due_utime_ = INT64_MIN;  // detection thread only
  std::mutex mu_;
  std::condition_variable cv_;
  bool pending_ = false, busy_ = false, stop_ = false;
  cv::Mat shared_;  // the handed-over image (guarded by mu_)
  int64_t utime_ = 0, sequence_ = 0;
  bool has_target_ = false;
  Eigen::Vector3d target_ = Eigen::Vector3d::Zero();
  const AxesInImage axes_;
  cv::Mat work_, half_a_, half_b_, small_;  // worker thread only
  std::vector<uint8_t> jpeg_;
  kincal::preview_t msg_{};
  std::atomic<int64_t> published_{0}, skipped_{0};
  std::thread thread_;
};

// kincald's preview stage (null unless preview.enabled): on lcm.preview_channel, with the
// floor polygon and the target's axes from the camera and floor calibration in `v`.
std::unique_ptr<PreviewStage> MakePreviewStage(const DaemonConfig& c, const VisionSetup& v,
                                               Publisher* publisher, bool lossless);

}  // namespace kincal::daemon
