// Once the window is full, FiedlerSegmenter::addFrame() must not touch the heap: the affinity,
// Laplacian and eigen-solver storage are preallocated. This executable interposes malloc (glibc) to
// count calls made while a flag is set. Sanitizer builds replace malloc themselves, so there the test
// only runs the stream.
#include <catch2/catch.hpp>

#include <atomic>
#include <cstddef>
#include <memory>
#include <vector>

#include "fake_similarity.hpp"
#include "toposlam/segmentation/fiedler_segmenter.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define TOPOSLAM_COUNT_MALLOC 0
#else
#define TOPOSLAM_COUNT_MALLOC 1
#endif

namespace {
std::atomic<long> g_mallocs{0};
std::atomic<bool> g_counting{false};
}  // namespace

#if TOPOSLAM_COUNT_MALLOC
extern "C" void* __libc_malloc(std::size_t size);  // NOLINT: glibc's own allocator entry point
extern "C" void* malloc(std::size_t size) {        // NOLINT: deliberate interposition
  if (g_counting.load(std::memory_order_relaxed)) g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
#endif

TEST_CASE("GIVEN a full window WHEN frames keep arriving and places close THEN addFrame does not allocate",
          "[segmentation][allocation]") {
  auto block = [](int f) { return f / 40; };
  toposlam::test::TableSimilarity similarity([&](int a, int b) { return block(a) == block(b) ? 0.9 : 0.05; });
  toposlam::FiedlerSegmenterConfig config;
  config.window = 30;  // a window of 30 frames (window_s 0)
  SECTION("the window-degree representative") {}
  SECTION("the place-medoid representative, its samples thinned") {
    config.representative = toposlam::RepresentativeChoice::PlaceMedoid;
    config.representative_interval_s = 0.0;
  }
  SECTION("three place samples, every frame sampled") {
    config.place_samples = 3;
    config.representative_interval_s = 0.0;
  }
  toposlam::FiedlerSegmenter segmenter(config, similarity);
  std::vector<std::shared_ptr<const toposlam::Fingerprint>> prints;
  for (int f = 0; f < 400; ++f) prints.push_back(toposlam::test::fakeFingerprint(f));
  long closed = 0;
  long steady_mallocs = 0;
  for (int f = 0; f < 400; ++f) {
    const bool steady = f >= segmenter.config().window;
    g_counting = steady;
    const long before = g_mallocs.load();
    const toposlam::SegmenterStep step = segmenter.addFrame(f, 0.2 * f, prints[static_cast<std::size_t>(f)]);
    g_counting = false;
    if (steady) steady_mallocs += g_mallocs.load() - before;
    if (step.closed_place) ++closed;
  }
  CHECK(closed == 9);  // borders every 40 frames; the 10th block is closed by flush
#if TOPOSLAM_COUNT_MALLOC
  CHECK(steady_mallocs == 0);
  THEN("the counter itself works: the warm-up did allocate") {
    g_counting = true;
    const long before = g_mallocs.load();
    auto probe = std::make_unique<std::vector<int>>(100);
    g_counting = false;
    CHECK(g_mallocs.load() > before);
  }
#else
  WARN("allocation counting is off under sanitizers");
#endif
}
