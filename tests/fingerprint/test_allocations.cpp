// Heap allocations per frame on the fingerprint path, counted by interposing the C allocator (glibc)
// as the segmenter's test does, plus posix_memalign (OpenCV's fastMalloc). Zero per frame is not within
// reach while OpenCV's filters and ORB build their own buffers on every call; what is ours is checked:
// the histograms never allocate, and a reused extractor allocates less per frame than one made afresh
// (its working images and detector stay). The counts are printed for docs/performance.md.
// Sanitizer builds replace malloc themselves, so there the test only runs the frames.
#include <catch2/catch.hpp>

#include <atomic>
#include <cstddef>
#include <iostream>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "test_helpers.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define TOPOSLAM_COUNT_MALLOC 0
#else
#define TOPOSLAM_COUNT_MALLOC 1
#endif

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
[[maybe_unused]] void count() {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

#if TOPOSLAM_COUNT_MALLOC
extern "C" void* __libc_malloc(std::size_t size);                        // NOLINT: glibc's own entry points
extern "C" void* __libc_calloc(std::size_t n, std::size_t size);         // NOLINT
extern "C" void* __libc_realloc(void* p, std::size_t size);              // NOLINT
extern "C" void* __libc_memalign(std::size_t alignment, std::size_t n);  // NOLINT
extern "C" void* malloc(std::size_t size) {                              // NOLINT: deliberate interposition
  count();
  return __libc_malloc(size);
}
extern "C" void* calloc(std::size_t n, std::size_t size) {  // NOLINT
  count();
  return __libc_calloc(n, size);
}
extern "C" void* realloc(void* p, std::size_t size) {  // NOLINT
  count();
  return __libc_realloc(p, size);
}
extern "C" int posix_memalign(void** out, std::size_t alignment, std::size_t size) {  // NOLINT
  count();
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return 12;  // ENOMEM
  *out = p;
  return 0;
}
#endif

namespace {

template <typename F>
long allocationsOf(F&& f) {
  g_counting = true;
  const long before = g_allocations.load();
  f();
  g_counting = false;
  return g_allocations.load() - before;
}

}  // namespace

using namespace toposlam;

TEST_CASE("GIVEN real frames WHEN fingerprinted frame after frame THEN the histograms never allocate and a kept "
          "extractor allocates less than a fresh one", "[fingerprint][allocation]") {
  cv::setNumThreads(1);  // OpenCV's own pool would add its threads' allocations
  std::vector<cv::Mat> frames;
  for (int i : {3, 20, 41, 66, 83}) {
    cv::Mat frame;
    cv::resize(test::sampleFrame(i), frame, cv::Size(640, 480), 0, 0, cv::INTER_AREA);
    frames.push_back(frame);
  }
  const HclHistogram histogram;
  cv::Mat grey;
  cv::cvtColor(frames[0], grey, cv::COLOR_BGR2GRAY);
  HclHistogramBins sink{};
  const long histogram_allocations = allocationsOf([&] {
    sink = histogram.compute(frames[0], 0, 640);
    sink = histogram.computeGrey(grey, 100, 400);
  });
  CHECK(sink[0] >= 0.f);

  const VpackExtractor kept;
  for (const cv::Mat& frame : frames) (void)kept.extract(frame);  // warm-up: working images sized
  long kept_allocations = 0, fresh_allocations = 0;
  for (const cv::Mat& frame : frames) {
    kept_allocations += allocationsOf([&] { (void)kept.extract(frame); });
    fresh_allocations += allocationsOf([&] { (void)VpackExtractor().extract(frame); });
  }
  // Where they come from (printed only): the edge detector and the keypoint detector, each kept.
  const VerticalEdgeDetector edges;
  VerticalEdgeScratch edge_scratch;
  VerticalEdges edge_result;
  const KeypointExtractor keypoints;
  const cv::Ptr<cv::Feature2D> detector = keypoints.createDetector();
  KeypointCandidates candidates;
  cv::Mat frame_grey;
  long edge_allocations = 0, keypoint_allocations = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (const cv::Mat& frame : frames) {
      cv::cvtColor(frame, frame_grey, cv::COLOR_BGR2GRAY);
      const long e = allocationsOf([&] { edges.detect(frame_grey, edge_result, edge_scratch); });
      const long k = allocationsOf([&] { keypoints.detect(*detector, frame_grey, candidates); });
      if (pass == 1) {
        edge_allocations += e;
        keypoint_allocations += k;
      }
    }
  }
  const auto n = static_cast<long>(frames.size());
  std::cout << "allocations per 640x480 frame: extractor kept " << kept_allocations / n << ", made afresh "
            << fresh_allocations / n << "; of these, edges " << edge_allocations / n << ", ORB candidates "
            << keypoint_allocations / n << "\n";
#if TOPOSLAM_COUNT_MALLOC
  CHECK(histogram_allocations == 0);
  CHECK(kept_allocations < fresh_allocations);
  CHECK(kept_allocations > 0);  // the counter works (OpenCV's filters and ORB do allocate)
#else
  (void)histogram_allocations;
  WARN("allocation counting is off under sanitizers");
#endif
}
