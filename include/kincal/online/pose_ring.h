// A fixed-capacity FIFO of poses (the filter thread's poses waiting for controls, and the
// recent poses a divergence re-fit uses). Storage is allocated once, at construction.
#pragma once

#include <cstddef>
#include <vector>

#include "kincal/online/samples.h"

namespace kincal {

class PoseRing {
 public:
  explicit PoseRing(size_t capacity) : items_(capacity) {}
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == items_.size(); }
  size_t size() const { return size_; }
  const PoseSample& at(size_t k) const { return items_[(head_ + k) % items_.size()]; }
  const PoseSample& front() const { return items_[head_]; }
  void push(const PoseSample& p) {
    items_[(head_ + size_) % items_.size()] = p;
    ++size_;
  }
  void pop() {
    head_ = (head_ + 1) % items_.size();
    --size_;
  }
  void clear() { head_ = size_ = 0; }

 private:
  std::vector<PoseSample> items_;
  size_t head_ = 0, size_ = 0;
};

}  // namespace kincal
