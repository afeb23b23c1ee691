// VPACK extraction end to end on real sample frames: keypoint budget, worker independence,
// serialisation round trip, bad input.
#include <atomic>
#include <sstream>
#include <thread>

#include <opencv2/imgproc.hpp>

#include <catch2/catch.hpp>

#include "test_helpers.hpp"
#include "toposlam/core/worker_pool.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"

using namespace toposlam;

TEST_CASE("GIVEN the real sample frames WHEN fingerprinted with ORB THEN every frame keeps <= 100 keypoints") {
  VpackExtractor extractor;
  int frames = 0, total_keypoints = 0, total_edges = 0, frames_with_edges = 0;
  for (int i = 1; i <= 84; ++i) {
    const cv::Mat image = test::sampleFrame(i);
    REQUIRE_FALSE(image.empty());
    const Fingerprint f = extractor.extract(image);
    INFO("frame " << i);
    REQUIRE(f.validate().empty());
    CHECK(f.keypointCount() <= 100);
    CHECK(f.subregions.size() == f.edge_columns.size() + 1);
    ++frames;
    total_keypoints += f.keypointCount();
    total_edges += static_cast<int>(f.edge_columns.size());
    frames_with_edges += f.edge_columns.empty() ? 0 : 1;
  }
  // A corridor has structure: most frames have edges and plenty of keypoints (measured: ~88 per frame,
  // ~3.5 edges per frame).
  CHECK(total_keypoints / frames >= 60);
  CHECK(frames_with_edges >= 70);
  CHECK(total_edges >= 2 * frames);
}

TEST_CASE("GIVEN other keypoint backends WHEN fingerprinting sample frames THEN the budget holds for each") {
  for (KeypointBackend backend : {KeypointBackend::Sift, KeypointBackend::Brisk, KeypointBackend::Akaze}) {
    VpackConfig config;
    config.keypoints.backend = backend;
    VpackExtractor extractor(config);
    for (int i : {1, 30, 60}) {
      const Fingerprint f = extractor.extract(test::sampleFrame(i));
      INFO(toString(backend) << " frame " << i);
      CHECK(f.keypointCount() <= 100);
      CHECK(f.keypointCount() >= 20);
      CHECK(f.descriptors.rows == f.keypointCount());
      CHECK(f.descriptors.type() == (backend == KeypointBackend::Sift ? CV_32F : CV_8U));
      CHECK(f.validate().empty());
    }
  }
}

TEST_CASE("GIVEN 1 or 3 workers WHEN fingerprinting THEN the fingerprints are identical") {
  WorkerPool one(1), three(3);
  VpackExtractor inline_extractor;
  VpackExtractor single(VpackConfig{}, &one), parallel(VpackConfig{}, &three);
  for (int i : {1, 17, 42, 84}) {
    const cv::Mat image = test::sampleFrame(i);
    const Fingerprint a = inline_extractor.extract(image);
    CHECK(a.equals(single.extract(image)));
    CHECK(a.equals(parallel.extract(image)));
  }
}

TEST_CASE("GIVEN fingerprints WHEN serialised and read back THEN they are exactly equal") {
  for (KeypointBackend backend : {KeypointBackend::Orb, KeypointBackend::Sift}) {
    VpackConfig config;
    config.keypoints.backend = backend;
    const Fingerprint f = VpackExtractor(config).extract(test::sampleFrame(5));
    std::stringstream buffer;
    writeFingerprint(buffer, f);
    const Fingerprint back = readFingerprint(buffer);
    CHECK(back.equals(f));
    CHECK(back.keypointCount() == f.keypointCount());
  }
  SECTION("a fingerprint with no keypoints round-trips too") {
    cv::Mat flat(60, 80, CV_8UC3, cv::Scalar(20, 200, 20));
    const Fingerprint f = VpackExtractor().extract(flat);
    CHECK(f.keypointCount() == 0);
    std::stringstream buffer;
    writeFingerprint(buffer, f);
    CHECK(readFingerprint(buffer).equals(f));
  }
  SECTION("in memory (a map's save and load): the same bytes as the stream's, read back equal") {
    const Fingerprint f = VpackExtractor().extract(test::sampleFrame(5));
    std::stringstream buffer;
    writeFingerprint(buffer, f);
    std::string bytes = "prefix";
    appendFingerprintBytes(bytes, f);
    CHECK(bytes == "prefix" + buffer.str());
    CHECK(fingerprintFromBytes(std::string_view(bytes).substr(6)).equals(f));
  }
}

TEST_CASE("GIVEN damaged fingerprint data WHEN read THEN a clear error names the problem") {
  const Fingerprint f = VpackExtractor().extract(test::sampleFrame(9));
  std::stringstream buffer;
  writeFingerprint(buffer, f);
  const std::string bytes = buffer.str();
  for (std::size_t cut : {std::size_t{2}, std::size_t{20}, bytes.size() / 2, bytes.size() - 1}) {
    std::istringstream truncated(bytes.substr(0, cut));
    CHECK_THROWS_WITH(readFingerprint(truncated), Catch::Contains("truncated"));
    CHECK_THROWS_WITH(fingerprintFromBytes(std::string_view(bytes).substr(0, cut)), Catch::Contains("truncated"));
  }
  std::string bad_magic = bytes;
  bad_magic[0] = 'X';
  std::istringstream wrong(bad_magic);
  CHECK_THROWS_WITH(readFingerprint(wrong), Catch::Contains("bad magic"));
  std::string huge_count = bytes;
  // The edge count follows magic (4), width (4), height (4) and backend (1).
  huge_count[13] = '\xff';
  huge_count[14] = '\xff';
  huge_count[15] = '\xff';
  huge_count[16] = '\x7f';
  std::istringstream garbage(huge_count);
  CHECK_THROWS_WITH(readFingerprint(garbage), Catch::Contains("corrupt"));
  CHECK_THROWS_WITH(fingerprintFromBytes(huge_count), Catch::Contains("corrupt"));
}

TEST_CASE("GIVEN bad images WHEN fingerprinted THEN a clear error, no crash") {
  VpackExtractor extractor;
  CHECK_THROWS_WITH(extractor.extract(cv::Mat()), Catch::Contains("empty image"));
  CHECK_THROWS_WITH(extractor.extract(cv::Mat(480, 1, CV_8UC3, cv::Scalar::all(9))),
                    Catch::Contains("1x480"));
  CHECK_THROWS_WITH(extractor.extract(cv::Mat(40, 40, CV_32FC3, cv::Scalar::all(0.5))),
                    Catch::Contains("32-bit"));
  CHECK_THROWS_WITH(extractor.extract(cv::Mat(40, 40, CV_8UC2, cv::Scalar::all(9))),
                    Catch::Contains("2 channels"));
}

TEST_CASE("GIVEN a grey or BGRA frame WHEN fingerprinted THEN it works and grey frames fill only grey bins") {
  cv::Mat colour = test::sampleFrame(3), grey, bgra;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  cv::cvtColor(colour, bgra, cv::COLOR_BGR2BGRA);
  VpackExtractor extractor;
  const Fingerprint g = extractor.extract(grey);
  REQUIRE(g.validate().empty());
  for (const Subregion& s : g.subregions)
    for (int b = 0; b < kHueBins; ++b) CHECK(s.histogram[b] == 0.f);
  CHECK(extractor.extract(bgra).equals(extractor.extract(colour)));
}

TEST_CASE("GIVEN subregion widths WHEN the keypoint budget is split THEN it follows width and sums to 100") {
  KeypointExtractor keypoints;
  std::vector<Subregion> regions = {{0, 100, {}, 0, 0}, {100, 150, {}, 0, 0}, {150, 640, {}, 0, 0}};
  const std::vector<int> b = keypoints.budgets(regions, 640);
  CHECK(b[0] + b[1] + b[2] == 100);
  CHECK(b[0] == 16);  // 15.6 -> 16 by largest remainder
  CHECK(b[1] == 8);   // 7.8 -> 8
  CHECK(b[2] == 76);  // 76.6 -> 76
}

TEST_CASE("GIVEN an invalid fingerprint config WHEN the extractor is built THEN the key is named") {
  VpackConfig config;
  config.keypoints.max_keypoints = -1;
  CHECK_THROWS_WITH(VpackExtractor(config), Catch::Contains("fingerprint.keypoints.max_keypoints"));
  CHECK_THROWS_WITH(parseKeypointBackend("surf"), Catch::Contains("allowed: orb, sift, brisk, akaze"));
}

TEST_CASE(
    "GIVEN one extractor WHEN frames of changing size and kind follow each other THEN each equals a fresh "
    "extractor's") {
  // The extractor keeps its working images and detector between frames: no frame may see another's.
  for (KeypointBackend backend : {KeypointBackend::Orb, KeypointBackend::Brisk}) {
    VpackConfig config;
    config.keypoints.backend = backend;
    WorkerPool two(2);
    VpackExtractor reused(config, &two);
    for (int i : {5, 40, 5, 77}) {
      cv::Mat colour = test::sampleFrame(i), small, grey, bgra;
      cv::resize(colour, small, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
      cv::cvtColor(small, grey, cv::COLOR_BGR2GRAY);
      cv::cvtColor(colour, bgra, cv::COLOR_BGR2BGRA);
      for (const cv::Mat& image : {colour, small, grey, bgra, colour}) {
        INFO(toString(backend) << " frame " << i << ", " << image.cols << "x" << image.rows << "x"
                               << image.channels());
        CHECK(reused.extract(image).equals(VpackExtractor(config).extract(image)));
      }
    }
  }
}

TEST_CASE(
    "GIVEN one extractor WHEN two threads fingerprint at once THEN both get the single-threaded "
    "fingerprints") {
  const VpackExtractor extractor;
  std::vector<cv::Mat> frames;
  std::vector<Fingerprint> expected;
  for (int i : {2, 21, 48, 80}) {
    frames.push_back(test::sampleFrame(i));
    expected.push_back(VpackExtractor().extract(frames.back()));
  }
  std::atomic<int> mismatches{0};
  auto work = [&] {
    for (int pass = 0; pass < 5; ++pass)
      for (std::size_t k = 0; k < frames.size(); ++k)
        if (!extractor.extract(frames[k]).equals(expected[k])) mismatches.fetch_add(1);
  };
  std::thread other(work);
  work();
  other.join();
  CHECK(mismatches.load() == 0);
}

TEST_CASE(
    "GIVEN a frame with its grey given WHEN fingerprinted THEN edges and keypoints come from that grey") {
  const cv::Mat colour = test::sampleFrame(12);
  cv::Mat grey;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  const VpackExtractor extractor;
  const Fingerprint converted = extractor.extract(colour);
  THEN("the grey the extractor would have made gives the same fingerprint, to the bit") {
    CHECK(extractor.extract(colour, grey).equals(converted));
    CHECK(extractor.extract(colour, cv::Mat()).equals(converted));
  }
  THEN("another grey (flipped) changes edges and keypoints but not what colour decides") {
    cv::Mat flipped;
    cv::flip(grey, flipped, 1);
    const Fingerprint f = extractor.extract(colour, flipped);
    const Fingerprint from_flipped = extractor.extract(flipped);
    CHECK(f.edge_columns == from_flipped.edge_columns);
    CHECK(f.keypointCount() == from_flipped.keypointCount());
    CHECK(f.subregions.size() == from_flipped.subregions.size());
    CHECK_FALSE(f.equals(converted));
  }
  THEN("a grey of the wrong size or type is refused") {
    CHECK_THROWS_WITH(extractor.extract(colour, cv::Mat(10, 10, CV_8UC1)), Catch::Contains("grey plane"));
    CHECK_THROWS_WITH(extractor.extract(colour, colour), Catch::Contains("grey plane"));
  }
}
