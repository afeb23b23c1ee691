// Safe reading of one image file (image_file.hpp): completeness, a header-level pixel cap, decoder
// errors named.
#include "toposlam/io/image_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <sstream>

#include <opencv2/core.hpp>

#include "byte_order.hpp"

namespace toposlam {

namespace {

using bytes::be16;
using bytes::be32;
// BMP stores its width and height signed (a negative height: rows top-down).
std::int32_t le32(const unsigned char* p) { return static_cast<std::int32_t>(bytes::le32(p)); }

bool isJpegFrameMarker(unsigned char m) {
  // SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC).
  return m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
}

std::optional<ImageHeader> jpegHeader(const unsigned char* data, std::size_t size) {
  std::size_t i = 2;
  while (i + 4 <= size) {
    if (data[i] != 0xFF) return std::nullopt;  // lost sync: let the decoder judge
    const unsigned char marker = data[i + 1];
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) {  // no length field
      i += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA) return std::nullopt;  // end, or scan data before any frame header
    const std::size_t length = be16(data + i + 2);
    if (length < 2) return std::nullopt;
    if (isJpegFrameMarker(marker)) {
      if (i + 9 > size) return std::nullopt;
      ImageHeader h{"jpeg", be16(data + i + 7), be16(data + i + 5)};
      if (h.height == 0) return std::nullopt;  // height given later (DNL): unknown here
      return h;
    }
    i += 2 + length;
  }
  return std::nullopt;
}

std::string megapixels(std::int64_t pixels) {
  std::ostringstream out;
  out.precision(1);
  out << std::fixed << static_cast<double>(pixels) / 1e6 << " megapixels";
  return out.str();
}

}  // namespace

bool imageBytesLookComplete(const std::vector<unsigned char>& bytes) {
  const std::size_t n = bytes.size();
  if (n < 16) return false;
  if (bytes[0] == 0xFF && bytes[1] == 0xD8) {  // JPEG: the EOI marker near the end (some writers pad)
    const std::size_t from = n > 64 ? n - 64 : 0;
    for (std::size_t i = n - 1; i > from; --i) {
      if (bytes[i - 1] == 0xFF && bytes[i] == 0xD9) return true;
    }
    return false;
  }
  if (bytes[0] == 0x89 && bytes[1] == 'P' && bytes[2] == 'N' && bytes[3] == 'G') {  // PNG: an IEND chunk
    const std::size_t from = n > 64 ? n - 64 : 0;
    for (std::size_t i = from; i + 4 <= n; ++i) {
      if (bytes[i] == 'I' && bytes[i + 1] == 'E' && bytes[i + 2] == 'N' && bytes[i + 3] == 'D') return true;
    }
    return false;
  }
  if (bytes[0] == 'B' && bytes[1] == 'M') return bytes::le32(bytes.data() + 2) <= n;  // BMP: declared size
  return true;  // unknown format: let the decoder decide
}

std::optional<ImageHeader> readImageHeader(const unsigned char* data, std::size_t size) {
  if (size >= 24 && data[0] == 0x89 && std::memcmp(data + 1, "PNG\r\n\x1a\n", 7) == 0 &&
      std::memcmp(data + 12, "IHDR", 4) == 0)
    return ImageHeader{"png", be32(data + 16), be32(data + 20)};
  if (size >= 4 && data[0] == 0xFF && data[1] == 0xD8) return jpegHeader(data, size);
  if (size >= 26 && data[0] == 'B' && data[1] == 'M') {
    const std::int64_t width = le32(data + 18), height = le32(data + 22);
    return ImageHeader{"bmp", width < 0 ? -width : width, height < 0 ? -height : height};
  }
  return std::nullopt;
}

cv::Mat decodeImageBytes(const std::vector<unsigned char>& bytes, ImageColor color, std::int64_t max_pixels,
                         const std::string& name) {
  if (bytes.empty()) throw ImageReadError(ImageReadError::Kind::Truncated, name + ": empty file");
  if (!imageBytesLookComplete(bytes))
    throw ImageReadError(ImageReadError::Kind::Truncated,
                         name + ": truncated (" + std::to_string(bytes.size()) + " bytes, no end marker)");
  if (const auto header = readImageHeader(bytes.data(), bytes.size())) {
    // Each side is checked alone first: two sides near 2^32 would overflow the product (found by
    // fuzz_image_header; tests/fuzz/corpus/image_header/png-4g-sides).
    const bool side_too_long = header->width > max_pixels || header->height > max_pixels;
    const std::int64_t pixels = side_too_long ? std::numeric_limits<std::int64_t>::max() : header->width * header->height;
    if (header->width == 0 || header->height == 0)
      throw ImageReadError(ImageReadError::Kind::Corrupt, name + ": " + header->format + " header says " +
                                                              std::to_string(header->width) + "x" +
                                                              std::to_string(header->height) + " pixels");
    if (pixels > max_pixels)
      throw ImageReadError(
          ImageReadError::Kind::TooLarge,
          name + ": " + std::to_string(header->width) + "x" + std::to_string(header->height) + " pixels (" +
              (side_too_long ? std::string("a side alone") : megapixels(pixels)) + ") is over the cap of " +
              megapixels(max_pixels) + " (max_pixels); not decoded");
  }
  cv::Mat image;
  try {
    // The decoder checks the cap again from its own reading of the header (a JPEG whose height comes
    // later, in a DNL marker, is only known there).
    image = decodeImage(bytes.data(), bytes.size(), color, max_pixels);
  } catch (const ImageCodecError& e) {
    throw ImageReadError(ImageReadError::Kind::Corrupt,
                         name + ": not a readable image (corrupt or unsupported format): " + e.what());
  } catch (const cv::Exception& e) {
    throw ImageReadError(ImageReadError::Kind::Corrupt, name + ": cannot decode it (" + e.err + ")");
  } catch (const std::bad_alloc&) {
    throw ImageReadError(ImageReadError::Kind::TooLarge, name + ": cannot decode it (out of memory)");
  }
  return image;
}

cv::Mat readImageFileChecked(const std::string& path, ImageColor color, std::int64_t max_pixels) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    const int error = errno;
    throw ImageReadError(
        ImageReadError::Kind::Unreadable,
        path + ": " + (error == ENOENT ? std::string("no such file") : std::strerror(error)));
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    const bool folder = S_ISDIR(st.st_mode);
    ::close(fd);
    throw ImageReadError(ImageReadError::Kind::Unreadable,
                         path + (folder ? ": is a folder, not an image" : ": not a regular file"));
  }
  if (static_cast<std::uint64_t>(st.st_size) > kMaxImageFileBytes) {
    ::close(fd);
    throw ImageReadError(ImageReadError::Kind::TooLarge,
                         path + ": " + std::to_string(st.st_size) + " bytes is too large for an image file");
  }
  std::vector<unsigned char> bytes(static_cast<std::size_t>(st.st_size));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  const int read_error = errno;
  ::close(fd);
  if (done != bytes.size())
    throw ImageReadError(ImageReadError::Kind::Unreadable,
                         path + ": cannot read it (" + std::string(std::strerror(read_error)) + ")");
  return decodeImageBytes(bytes, color, max_pixels, path);
}

}  // namespace toposlam
