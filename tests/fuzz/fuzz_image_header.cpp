// libFuzzer target: image bytes through our reader (readImageHeader, the completeness check, the pixel
// cap, then our decoders: image_codec.hpp). Anything but an ImageReadError is a finding; a decoded image is never
// larger than the cap.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "toposlam/io/image_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  constexpr std::int64_t kCap = 1 << 20;  // one megapixel: keeps each run small
  (void)toposlam::readImageHeader(data, size);
  try {
    const cv::Mat image = toposlam::decodeImageBytes(std::vector<unsigned char>(data, data + size),
                                                     toposlam::ImageColor::Bgr, kCap, "fuzz");
    if (static_cast<std::int64_t>(image.cols) * image.rows > kCap) std::abort();
  } catch (const toposlam::ImageReadError&) {
  }
  return 0;
}
