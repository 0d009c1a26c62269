#include "vision/labels.h"

#include <algorithm>
#include <utility>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace kincal::vision {
namespace {

// The root of blob i, halving the path on the way.
int Find(std::vector<Blob>& b, int i) {
  while (b[static_cast<size_t>(i)].parent != i) {
    b[static_cast<size_t>(i)].parent =
        b[static_cast<size_t>(b[static_cast<size_t>(i)].parent)].parent;
    i = b[static_cast<size_t>(i)].parent;
  }
  return i;
}

struct Run {
  int x0, x1, blob;
};

// Foreground test: dark-on-light markers are p <= thr, light-on-dark p > thr.
template <bool kDark>
inline bool Fg(uint8_t p, int thr) {
  return kDark ? p <= thr : p > thr;
}

// First x >= x in [x, w) that is foreground (w if none); skips 16 background pixels at a
// time with SSE2 where available.
template <bool kDark>
inline int NextFg(const uint8_t* row, int x, int w, int thr) {
#ifdef __SSE2__
  const __m128i t = _mm_set1_epi8(static_cast<char>(kDark ? thr : std::min(thr + 1, 255)));
  while (x + 16 <= w) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
    const __m128i hit =
        kDark ? _mm_cmpeq_epi8(_mm_min_epu8(v, t), v) : _mm_cmpeq_epi8(_mm_max_epu8(v, t), v);
    if (_mm_movemask_epi8(hit) != 0) break;
    x += 16;
  }
#endif
  while (x < w && !Fg<kDark>(row[x], thr)) ++x;
  return x;
}

template <bool kDark>
void LabelRunsOf(const cv::Mat& view, int thr, std::vector<Blob>* blobs) {
  std::vector<Run> prev, cur;
  for (int y = 0; y < view.rows; ++y) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    cur.clear();
    int x = 0;
    const int w = view.cols;
    size_t j = 0;  // first run of the previous row that may touch
    while ((x = NextFg<kDark>(row, x, w, thr)) < w) {
      const int x0 = x;
      while (x < w && Fg<kDark>(row[x], thr)) ++x;
      const int x1 = x - 1;
      int blob = -1;
      while (j < prev.size() && prev[j].x1 < x0 - 1) ++j;
      for (size_t k = j; k < prev.size() && prev[k].x0 <= x1 + 1; ++k) {
        const int r = Find(*blobs, prev[k].blob);
        if (blob < 0) {
          blob = r;
        } else if (r != blob) {
          (*blobs)[static_cast<size_t>(r)].parent = blob;
        }
      }
      if (blob < 0) {
        blob = static_cast<int>(blobs->size());
        blobs->push_back(Blob{blob});
      }
      Blob& b = (*blobs)[static_cast<size_t>(blob)];
      const double n = x1 - x0 + 1;
      const double s1 = n * (x0 + x1) * 0.5;
      auto s2 = [](double k) { return k * (k + 1) * (2 * k + 1) / 6.0; };
      b.area += x1 - x0 + 1;
      b.sx += s1;
      b.sy += n * y;
      b.sxx += s2(x1) - s2(x0 - 1);
      b.syy += n * y * y;
      b.sxy += s1 * y;
      b.x0 = std::min(b.x0, x0);
      b.x1 = std::max(b.x1, x1);
      b.y0 = std::min(b.y0, y);
      b.y1 = std::max(b.y1, y);
      cur.push_back({x0, x1, blob});
    }
    std::swap(prev, cur);
  }
  // Merge the statistics of every blob into its root.
  for (size_t i = 0; i < blobs->size(); ++i) {
    const int r = Find(*blobs, static_cast<int>(i));
    if (r == static_cast<int>(i)) continue;
    Blob& a = (*blobs)[static_cast<size_t>(r)];
    Blob& b = (*blobs)[i];
    a.area += b.area;
    a.sx += b.sx;
    a.sy += b.sy;
    a.sxx += b.sxx;
    a.syy += b.syy;
    a.sxy += b.sxy;
    a.x0 = std::min(a.x0, b.x0);
    a.x1 = std::max(a.x1, b.x1);
    a.y0 = std::min(a.y0, b.y0);
    a.y1 = std::max(a.y1, b.y1);
    b.area = 0;
  }
}

}  // namespace

void LabelRuns(const cv::Mat& view, int thr, bool dark_on_light, std::vector<Blob>* blobs) {
  blobs->clear();
  if (dark_on_light) {
    LabelRunsOf<true>(view, thr, blobs);
  } else {
    LabelRunsOf<false>(view, thr, blobs);
  }
}

}  // namespace kincal::vision
