// BoundedQueue: a fixed-capacity FIFO between two threads, with an explicit policy when
// it is full and a count of what that policy dropped.
//
// Items move by swap: Push() swaps the caller's item into a slot and hands back the slot's
// previous content (a recycled buffer), Pop() swaps a slot's item out. Items that own
// buffers (frames, encoded messages) therefore circulate between producer and consumer
// and the queue allocates nothing after construction.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <utility>
#include <vector>

namespace kincal::daemon {

enum class FullPolicy {
  kBlock,       // the producer waits (replay --fast: nothing may be lost)
  kDropOldest,  // the oldest queued item is discarded (live frames: keep the freshest)
  kDropNewest,  // the new item is discarded (recorder: never stall the pipeline)
};

template <typename T>
class BoundedQueue {
 public:
  BoundedQueue(size_t capacity, FullPolicy policy)
      : slots_(capacity > 0 ? capacity : 1), policy_(policy) {}

  // Returns false if the item was dropped (kDropNewest when full) or the queue is closed;
  // with kDropOldest the oldest item is dropped instead and Push returns true.
  bool Push(T& item) {
    std::unique_lock lock(mu_);
    if (policy_ == FullPolicy::kBlock) {
      not_full_.wait(lock, [&] { return size_ < slots_.size() || closed_; });
    }
    if (closed_) return false;
    if (size_ == slots_.size()) {
      ++dropped_;
      if (policy_ == FullPolicy::kDropNewest) return false;
      head_ = (head_ + 1) % slots_.size();  // kDropOldest: overwrite the oldest
      --size_;
    }
    using std::swap;
    swap(slots_[(head_ + size_) % slots_.size()], item);
    ++size_;
    ++pushed_;
    lock.unlock();
    not_empty_.notify_one();
    return true;
  }

  // Waits up to `timeout` for an item. Returns false on timeout or when the queue is
  // closed and empty (check closed_and_empty()).
  template <typename Rep, typename Period>
  bool Pop(T& out, std::chrono::duration<Rep, Period> timeout) {
    std::unique_lock lock(mu_);
    if (!not_empty_.wait_for(lock, timeout, [&] { return size_ > 0 || closed_; })) return false;
    if (size_ == 0) return false;
    using std::swap;
    swap(out, slots_[head_]);
    head_ = (head_ + 1) % slots_.size();
    --size_;
    lock.unlock();
    not_full_.notify_one();
    return true;
  }
  bool TryPop(T& out) { return Pop(out, std::chrono::seconds(0)); }

  // No more pushes; consumers drain what is queued.
  void Close() {
    {
      std::lock_guard lock(mu_);
      closed_ = true;
    }
    not_empty_.notify_all();
    not_full_.notify_all();
  }
  bool closed_and_empty() const {
    std::lock_guard lock(mu_);
    return closed_ && size_ == 0;
  }
  size_t size() const {
    std::lock_guard lock(mu_);
    return size_;
  }
  size_t capacity() const { return slots_.size(); }
  int64_t dropped() const {
    std::lock_guard lock(mu_);
    return dropped_;
  }
  int64_t pushed() const {
    std::lock_guard lock(mu_);
    return pushed_;
  }
  FullPolicy policy() const { return policy_; }

 private:
  mutable std::mutex mu_;
  std::condition_variable not_empty_, not_full_;
  std::vector<T> slots_;
  size_t head_ = 0, size_ = 0;
  FullPolicy policy_;
  bool closed_ = false;
  int64_t dropped_ = 0, pushed_ = 0;
};

}  // namespace kincal::daemon
