// Tests of image_file.hpp: the header-level pixel cap (a small JPEG claiming 65500x65500, an 8000x8000
// PNG), a half JPEG refused instead of decoded half grey, and an image folder that survives such files.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include <opencv2/imgcodecs.hpp>

#include "test_files.hpp"
#include "toposlam/io/file_sources.hpp"
#include "toposlam/io/image_file.hpp"
#include "toposlam/io/source_factory.hpp"

using namespace toposlam;
namespace fs = std::filesystem;

namespace {

const std::string kSamples = std::string(TOPOSLAM_SAMPLES_DIR) + "/samples";

using test::TempFolder;

std::vector<unsigned char> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

/// A real JPEG (the first sample) whose SOF0 header is patched to claim width x height.
std::vector<unsigned char> jpegClaiming(int width, int height) {
  std::vector<unsigned char> bytes = readBytes(kSamples + "/1.jpg");
  for (std::size_t i = 2; i + 9 < bytes.size(); ++i) {
    if (bytes[i] == 0xFF && (bytes[i + 1] == 0xC0 || bytes[i + 1] == 0xC2)) {
      bytes[i + 5] = static_cast<unsigned char>(height >> 8);
      bytes[i + 6] = static_cast<unsigned char>(height & 0xff);
      bytes[i + 7] = static_cast<unsigned char>(width >> 8);
      bytes[i + 8] = static_cast<unsigned char>(width & 0xff);
      return bytes;
    }
  }
  FAIL("no SOF marker in 1.jpg");
  return bytes;
}

/// A small real PNG whose IHDR claims width x height (the IHDR checksum is left stale on purpose: the
/// cap must refuse from the header alone).
std::vector<unsigned char> pngClaiming(std::uint32_t width, std::uint32_t height) {
  std::vector<unsigned char> bytes;
  cv::imencode(".png", cv::Mat(8, 8, CV_8UC3, cv::Scalar(10, 20, 30)), bytes);
  for (int i = 0; i < 4; ++i) {
    bytes[16 + static_cast<std::size_t>(i)] = static_cast<unsigned char>(width >> (24 - 8 * i));
    bytes[20 + static_cast<std::size_t>(i)] = static_cast<unsigned char>(height >> (24 - 8 * i));
  }
  return bytes;
}

}  // namespace

TEST_CASE("GIVEN PNG, JPEG and BMP bytes WHEN their header is read THEN width and height come without decoding",
          "[io][image]") {
  const auto jpeg = readBytes(kSamples + "/1.jpg");
  const auto h = readImageHeader(jpeg.data(), jpeg.size());
  REQUIRE(h);
  CHECK(h->format == "jpeg");
  CHECK(h->width == 512);
  CHECK(h->height == 384);
  std::vector<unsigned char> png, bmp;
  cv::imencode(".png", cv::Mat(30, 70, CV_8UC1, cv::Scalar(1)), png);
  cv::imencode(".bmp", cv::Mat(30, 70, CV_8UC3, cv::Scalar(1)), bmp);
  CHECK(readImageHeader(png.data(), png.size())->width == 70);
  CHECK(readImageHeader(png.data(), png.size())->height == 30);
  CHECK(readImageHeader(bmp.data(), bmp.size())->format == "bmp");
  CHECK(readImageHeader(bmp.data(), bmp.size())->height == 30);
  const std::string text = "not an image at all";
  CHECK_FALSE(readImageHeader(reinterpret_cast<const unsigned char*>(text.data()), text.size()));
  CHECK_FALSE(readImageHeader(jpeg.data(), 3));
}

TEST_CASE("GIVEN a small JPEG claiming 65500x65500 pixels WHEN read THEN it is refused from its header, named",
          "[io][image][reliability]") {
  TempFolder folder("huge-jpeg");
  const fs::path huge = folder.path / "huge.jpg";
  writeBytes(huge, jpegClaiming(65500, 65500));
  CHECK(fs::file_size(huge) < 64 * 1024);
  CHECK_THROWS_AS(readImageFileChecked(huge.string(), ImageColor::Bgr), ImageReadError);
  CHECK_THROWS_WITH(readImageFileChecked(huge.string(), ImageColor::Bgr),
                    Catch::Contains(huge.string()) && Catch::Contains("65500x65500 pixels") &&
                        Catch::Contains("over the cap"));
}

TEST_CASE("GIVEN an 8000x8000 PNG WHEN read with the default cap THEN refused, and with a higher cap the header passes",
          "[io][image][reliability]") {
  TempFolder folder("big-png");
  const fs::path big = folder.path / "big.png";
  writeBytes(big, pngClaiming(8000, 8000));
  CHECK_THROWS_WITH(readImageFileChecked(big.string(), ImageColor::Bgr),
                    Catch::Contains("8000x8000 pixels (64.0 megapixels) is over the cap of 16.8 megapixels"));
  // Sides near 2^32: refused without overflowing the product (found by fuzz_image_header).
  writeBytes(big, pngClaiming(0xFFFFFFFFu, 0xFFFFFFF0u));
  CHECK_THROWS_WITH(readImageFileChecked(big.string(), ImageColor::Bgr), Catch::Contains("a side alone"));
  writeBytes(big, pngClaiming(8000, 8000));
  // Under a cap it fits, the decoder gets it (and refuses the stale checksum: an error, not a crash).
  CHECK_THROWS_AS(readImageFileChecked(big.string(), ImageColor::Bgr, 100'000'000), ImageReadError);
}

TEST_CASE("GIVEN half a JPEG without its end marker WHEN read THEN it is refused, not decoded half grey",
          "[io][image][reliability]") {
  TempFolder folder("half-jpeg");
  std::vector<unsigned char> bytes = readBytes(kSamples + "/5.jpg");
  bytes.resize(bytes.size() / 2);
  const fs::path half = folder.path / "half.jpg";
  writeBytes(half, bytes);
  CHECK_THROWS_WITH(readImageFileChecked(half.string(), ImageColor::AsStored),
                    Catch::Contains(half.string()) && Catch::Contains("truncated"));
  CHECK(readImageFileChecked(kSamples + "/5.jpg", ImageColor::AsStored).cols == 512);
  CHECK_THROWS_WITH(readImageFileChecked(folder.path.string(), ImageColor::AsStored), Catch::Contains("is a folder"));
  CHECK_THROWS_WITH(readImageFileChecked((folder.path / "none.jpg").string(), ImageColor::AsStored),
                    Catch::Contains("no such file"));
}

TEST_CASE("GIVEN an image folder with a 65500x65500 JPEG and an 8000x8000 PNG among good frames WHEN played "
          "THEN the bad ones are skipped and counted and the stream goes on",
          "[io][image][reliability]") {
  TempFolder folder("mixed");
  fs::copy_file(kSamples + "/1.jpg", folder.path / "1.jpg");
  writeBytes(folder.path / "2.jpg", jpegClaiming(65500, 65500));
  writeBytes(folder.path / "3.png", pngClaiming(8000, 8000));
  fs::copy_file(kSamples + "/4.jpg", folder.path / "4.jpg");
  std::unique_ptr<FrameSource> source = openFrameSource("images:" + folder.path.string());
  std::vector<std::string> names;
  while (std::optional<Frame> frame = source->next()) names.push_back(frame->name);
  CHECK(names == std::vector<std::string>{"1.jpg", "4.jpg"});
  CHECK(source->skippedFrames() == 2);

  WHEN("the cap is set in the URI below a sample's 512x384") {
    std::unique_ptr<FrameSource> capped = openFrameSource("images:" + folder.path.string() + "?max_pixels=1000");
    int frames = 0;
    while (capped->next()) ++frames;
    CHECK(frames == 0);
    CHECK(capped->skippedFrames() == 4);
  }
}
