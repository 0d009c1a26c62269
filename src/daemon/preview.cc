#include "daemon/preview.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "daemon/background_thread.h"
#include "kincal/vision/floor_view.h"

namespace kincal::daemon {
namespace {

// `in` (its size a multiple of k) down by k: halvings by OpenCV's area resampling while
// more than a factor of 2 is left (its fast path is the whole factor 2), then the rest, at
// most 2: area resampling when it is exactly 2, else linear (no pixel skipped below 2).
// Pixel centres map as (u + 0.5) / k - 0.5 through every step. `a` and `b` are kept
// buffers for the halvings.
void Downscale(const cv::Mat& in, int k, cv::Mat* a, cv::Mat* b, cv::Mat* out) {
  const cv::Size target(in.cols / k, in.rows / k);
  if (k == 1) {
    in.copyTo(*out);
    return;
  }
  const cv::Mat* src = &in;
  while (src->cols > 2 * target.width && src->cols % 2 == 0 && src->rows % 2 == 0) {
    cv::Mat* next = src == a ? b : a;
    cv::resize(*src, *next, cv::Size(src->cols / 2, src->rows / 2), 0, 0, cv::INTER_AREA);
    src = next;
  }
  const bool half = src->cols == 2 * target.width && src->rows == 2 * target.height;
  cv::resize(*src, *out, target, 0, 0, half ? cv::INTER_AREA : cv::INTER_LINEAR);
}

}  // namespace

int PreviewStage::Scale(int source_width, int width) {
  return std::max(1, (source_width + width - 1) / std::max(width, 1));
}

PreviewStage::PreviewStage(const PreviewOptions& options, std::string channel, Publisher* publisher,
                           bool lossless, const std::vector<Eigen::Vector2d>& floor_seen,
                           AxesInImage axes)
    : opt_(options),
      channel_(std::move(channel)),
      publisher_(*publisher),
      lossless_(lossless),
      period_us_(static_cast<int64_t>(std::llround(1e6 / options.rate_hz))),
      axes_(std::move(axes)) {
  msg_.schema_version = 1;
  msg_.format = "jpeg";
  msg_.num_floor = static_cast<int32_t>(floor_seen.size());
  for (const auto& p : floor_seen) {
    msg_.floor_x.push_back(p.x());
    msg_.floor_y.push_back(p.y());
  }
  thread_ = std::thread([this] { Loop(); });
}

PreviewStage::~PreviewStage() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void PreviewStage::Offer(const cv::Mat& grey, int64_t utime, int64_t sequence,
                         const Eigen::Vector3d* target) {
  const bool first = next_due_utime_ == INT64_MIN;
  const bool jumped_back = !first && utime < next_due_utime_ - 2 * period_us_;
  // A frame up to an eighth of a period early counts (a 30 Hz camera's stamps are not a
  // whole multiple of a 5 Hz preview's period).
  if (grey.empty() || (!first && !jumped_back && utime < next_due_utime_ - period_us_ / 8)) {
    return;
  }
  // Due: the next one a period later (after a gap or a time jump back, from this frame).
  next_due_utime_ = (first || jumped_back || utime - next_due_utime_ >= period_us_)
                        ? utime + period_us_
                        : next_due_utime_ + period_us_;
  {
    std::unique_lock lock(mu_, std::defer_lock);
    if (lossless_) {
      lock.lock();
      cv_.wait(lock, [this] { return stop_ || (!pending_ && !busy_); });
    } else if (!lock.try_lock() || pending_ || busy_) {
      skipped_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    grey.copyTo(shared_);  // no allocation once shared_ has the frame's size
    utime_ = utime;
    sequence_ = sequence;
    has_target_ = target != nullptr;
    if (target != nullptr) target_ = *target;
    pending_ = true;
  }
  cv_.notify_one();
}

void PreviewStage::FillAxes(bool has_target, const Eigen::Vector3d& target) {
  std::array<Eigen::Vector2d, 3> px;
  msg_.axis_length_m = kPreviewAxisLengthM;
  msg_.num_axes = has_target && axes_ && axes_(target, &px) ? 3 : 0;
  msg_.axes_u.resize(static_cast<size_t>(msg_.num_axes));  // capacity kept: no allocation
  msg_.axes_v.resize(static_cast<size_t>(msg_.num_axes));
  for (int k = 0; k < msg_.num_axes; ++k) {
    msg_.axes_u[static_cast<size_t>(k)] = px[static_cast<size_t>(k)].x();
    msg_.axes_v[static_cast<size_t>(k)] = px[static_cast<size_t>(k)].y();
  }
}

void PreviewStage::Drain() {
  std::unique_lock lock(mu_);
  cv_.wait(lock, [this] { return stop_ || (!pending_ && !busy_); });
}

void PreviewStage::Loop() {
  RunThisThreadInTheBackground();  // a preview is late before a pose is
  const std::vector<int> params = {cv::IMWRITE_JPEG_QUALITY, opt_.quality};
  std::unique_lock lock(mu_);
  while (true) {
    cv_.wait(lock, [this] { return stop_ || pending_; });
    if (stop_) return;
    pending_ = false;
    busy_ = true;
    cv::swap(shared_, work_);  // the next Offer copies into the other buffer
    const int64_t utime = utime_, sequence = sequence_;
    const bool has_target = has_target_;
    const Eigen::Vector3d target = target_;
    lock.unlock();
    const int k = Scale(work_.cols, opt_.width);
    const cv::Mat cut =
        work_(cv::Rect(0, 0, work_.cols - work_.cols % k, work_.rows - work_.rows % k));
    Downscale(cut, k, &half_a_, &half_b_, &small_);
    if (cv::imencode(".jpg", small_, jpeg_, params)) {
      msg_.utime = utime;
      msg_.frame_sequence = sequence;
      msg_.source_width = work_.cols;
      msg_.source_height = work_.rows;
      msg_.scale = k;
      msg_.width = small_.cols;
      msg_.height = small_.rows;
      FillAxes(has_target, target);
      msg_.size = static_cast<int32_t>(jpeg_.size());
      msg_.data.assign(jpeg_.begin(), jpeg_.end());
      publisher_.Publish(channel_, utime, msg_);
      published_.fetch_add(1, std::memory_order_relaxed);
    }
    lock.lock();
    busy_ = false;
    cv_.notify_all();
  }
}

std::unique_ptr<PreviewStage> MakePreviewStage(const DaemonConfig& c, const VisionSetup& v,
                                               Publisher* publisher, bool lossless) {
  if (!c.preview.enabled) return nullptr;
  // `v` outlives the stage (kincald keeps both for its life): captured by reference.
  return std::make_unique<PreviewStage>(
      c.preview, c.lcm.preview_channel, publisher, lossless,
      vision::FloorSeen(v.camera, v.floor, v.target_height_m),
      [&v](const Eigen::Vector3d& pose, std::array<Eigen::Vector2d, 3>* px) {
        return vision::TargetAxesInImage(v.camera, v.floor, v.target_height_m, pose,
                                         kPreviewAxisLengthM, px);
      });
}

}  // namespace kincal::daemon
