// Self-similarity of frames whose letters repeat (issue 4: a frame with itself scores >= 0.95): periodic
// grey bars (identical subregions, identical descriptors) and bands of one repeated diagonal texture.
// Equal candidates must resolve to the order-consistent correspondence, not the leftmost one.
#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "fingerprint/test_helpers.hpp"
#include "toposlam/fingerprint/vpack_extractor.hpp"
#include "toposlam/matching/ngram_similarity.hpp"

using namespace toposlam;

namespace {

/// Eight dark bars every 80 px on mid-grey: eight identical 74-px letters between them.
cv::Mat periodicBarsFrame() {
  std::vector<int> columns;
  for (int c = 40; c < 640; c += 80) columns.push_back(c);
  return test::barsFrame(640, 480, columns, 6);
}

/// Eight 80-px bands separated by dark bars, each filled with the same diagonal stripe texture
/// (period 16 px, so every band holds the same pattern at the same phase).
cv::Mat repeatedTextureFrame() {
  cv::Mat image(480, 640, CV_8UC3, cv::Scalar(170, 170, 170));
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const int band_x = x % 80;
      if (band_x < 6) {
        image.at<cv::Vec3b>(y, x) = cv::Vec3b(30, 30, 30);
      } else if (((band_x + y) / 8) % 2 == 0) {
        image.at<cv::Vec3b>(y, x) = cv::Vec3b(60, 120, 200);
      }
    }
  }
  return image;
}

}  // namespace

SCENARIO("Frames with repeated letters are (nearly) identical to themselves") {
  const VpackExtractor extractor{VpackConfig{}};
  const NgramSimilarity similarity;
  for (const bool textured : {false, true}) {
    const std::string frame = textured ? "bands of one repeated diagonal texture" : "a grey frame of eight periodic bars";
    GIVEN(frame) {
      const Fingerprint f = extractor.extract(textured ? repeatedTextureFrame() : periodicBarsFrame());
      REQUIRE(f.subregions.size() >= 6);
      WHEN("the frame is compared with itself") {
        const SimilarityBreakdown b = similarity.explain(f, f);
        INFO("letters " << f.subregions.size() << ", keypoints " << f.keypoints.size() << ", histogram part "
                        << b.histogram_part << ", keypoint part " << b.keypoint_part);
        THEN("it scores at least 0.95 (both directions, and the symmetric value)") {
          CHECK(b.similarity >= 0.95);
          CHECK(similarity.symmetricSimilarity(f, f) >= 0.95);
        }
      }
    }
  }
}
