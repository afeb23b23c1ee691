// Reading one image file safely: the whole file is read once (up to a size cap), refused when it looks
// truncated (a JPEG without its end marker decodes as a half-grey frame), its width and height are read
// from the header (PNG IHDR, JPEG SOFn, BMP info header) and checked against a pixel cap *before* any
// decoding (image_codec.hpp: JPEG, PNG, BMP), and the decoder's errors become an ImageReadError naming the file. A small file that
// claims 65500x65500 pixels is refused in microseconds instead of asking the decoder for 12 GB.
// Reentrant; no state.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "toposlam/io/image_codec.hpp"

namespace toposlam {

/// Default pixel cap of a decoded image: 4096 x 4096 (16.8 megapixels; a 12 MP camera fits).
inline constexpr std::int64_t kDefaultMaxImagePixels = 4096LL * 4096LL;
/// Files larger than this are not read (bytes).
inline constexpr std::uint64_t kMaxImageFileBytes = 256ull << 20;

/// A file that cannot be used as an image; kind() says why (a frame source counts it by reason).
class ImageReadError : public std::runtime_error {
 public:
  enum class Kind {
    Unreadable,  ///< cannot be opened or read, or not a regular file
    Truncated,   ///< empty, or cut short (no end marker)
    Corrupt,     ///< the header or the decoder refused it (corrupt data, unsupported format)
    TooLarge,    ///< over the pixel cap or the file-size cap
  };
  ImageReadError(Kind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

struct ImageHeader {
  std::string format;  ///< "png", "jpeg", "bmp"
  std::int64_t width = 0;
  std::int64_t height = 0;
};

/// True when the bytes of an image file look complete: JPEG ends with the EOI marker, PNG with IEND,
/// BMP is as long as its header says. (Decoders often accept truncated files and fill the rest grey.)
bool imageBytesLookComplete(const std::vector<unsigned char>& bytes);

/// Width and height from the header of PNG, JPEG or BMP bytes, without decoding. nullopt when the bytes
/// are none of these or the header does not say (the decoder then decides).
std::optional<ImageHeader> readImageHeader(const unsigned char* data, std::size_t size);

/// Decodes file bytes (decodeImage, as `color`) after the completeness and pixel-cap checks. Throws
/// ImageReadError "<name>: <reason>".
cv::Mat decodeImageBytes(const std::vector<unsigned char>& bytes, ImageColor color, std::int64_t max_pixels,
                         const std::string& name);

/// Reads and decodes `path` (see decodeImageBytes). Throws ImageReadError "<path>: <reason>".
cv::Mat readImageFileChecked(const std::string& path, ImageColor color,
                             std::int64_t max_pixels = kDefaultMaxImagePixels);

}  // namespace toposlam
