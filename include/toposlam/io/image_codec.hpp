// Image bytes in and out: JPEG through libjpeg-turbo, PNG through libpng, BMP and PNM (PGM, PPM, PBM) by
// hand. It replaces OpenCV's
// imgcodecs, which loads about 120 shared libraries (GDAL, HDF5, OpenEXR, ...) into every program at
// start-up for formats toposlam never reads (docs/performance.md, "Start-up").
//
// Decoding gives what cv::imdecode gives for these formats, to the bit (tests/io/test_image_codec.cpp
// compares the two): the same libjpeg output colour spaces and defaults, libpng's transforms in the same
// order, a JPEG's EXIF orientation applied. Encoding uses OpenCV's settings too (a JPEG is byte for byte
// what cv::imencode writes at the same quality). No file access here: see image_file.hpp for the checked
// reading of a file (size cap, truncation, the pixel cap from the header, errors naming the file).
// Reentrant; no state.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

namespace toposlam {

/// What a decoded image holds.
enum class ImageColor {
  Bgr,       ///< CV_8UC3, B,G,R (grey images made three equal channels); cv::IMREAD_COLOR
  Grey,      ///< CV_8UC1; cv::IMREAD_GRAYSCALE
  AsStored,  ///< grey stays CV_8UC1, anything with colour (or alpha) becomes BGR; cv::IMREAD_ANYCOLOR
};

enum class ImageFormat { Jpeg, Png, Bmp };

class ImageCodecError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Decodes JPEG, PNG, BMP or PNM bytes (the format from the bytes, not a name). 8 bits per channel out
/// (16-bit PNG is reduced), alpha dropped. `max_pixels`: width x height above it is refused after the
/// header is read and before any pixel memory is taken. Throws ImageCodecError with the reason
/// ("not a JPEG, PNG, BMP or PNM image", libjpeg's or libpng's own message, "BMP with RLE compression is not
/// supported", ...).
cv::Mat decodeImage(const unsigned char* data, std::size_t size, ImageColor color,
                    std::int64_t max_pixels = std::int64_t{1} << 32);

/// The format an output path asks for by its extension (.jpg, .jpeg, .png, .bmp; any case), if any.
std::optional<ImageFormat> imageFormatOfPath(const std::string& path);

/// Encodes an 8-bit image (CV_8UC1 grey, CV_8UC3 BGR or CV_8UC4 BGRA, alpha dropped except in PNG) into
/// `out` (replaced; its capacity is reused). `jpeg_quality` 0..100 (OpenCV's default is 95). Throws
/// ImageCodecError for an empty image or another type.
void encodeImage(const cv::Mat& image, ImageFormat format, std::vector<unsigned char>& out, int jpeg_quality = 95);
std::vector<unsigned char> encodeImage(const cv::Mat& image, ImageFormat format, int jpeg_quality = 95);

}  // namespace toposlam
